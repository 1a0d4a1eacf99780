"""Active control of the bundled pneumatic table from the command line: feedforward, the control study."""

from __future__ import annotations

import json

import pytest

from controllers import feedback as fb
from isolator import ParameterError, linearise, load_scenario
from isolator.cli.app import main

SCENARIO = "paper-table-3-2-pneumatic-active"


def test_feedforward_command_on_the_pneumatic_table(capsys):
    assert main(["feedforward", SCENARIO, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["reduction_db"]["x"] < -20.0  # the carriage's reaction cancelled, measured about the leveling


def test_control_study_on_the_pneumatic_table(tmp_path, capsys):
    assert main(["study", "control", SCENARIO, "--quick", "--out", str(tmp_path)]) == 0
    results = json.loads((tmp_path / "results.json").read_text())
    assert "skyhook" in (tmp_path / "report.md").read_text()
    assert results  # the runs' settling and band are written


def test_state_feedback_is_refused_on_air_springs():
    lin = linearise(load_scenario(SCENARIO))
    with pytest.raises(ParameterError, match=r"^controller: lqr feeds back the whole state"):
        fb.lqr(lin)
