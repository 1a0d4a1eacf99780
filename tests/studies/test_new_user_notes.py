"""Issue 26, item 7: the smaller things a new user hit (the sweep's progress is the sweep's own)."""

from __future__ import annotations

import sys

import pytest

import controllers.feedback as fb
from isolator import ParameterError, linearise, load_scenario, stability
from isolator.cli.app import main


def test_the_control_study_says_why_lqr_shows_no_settling_time(tmp_path, capsys):
    assert main(["study", "control", "--quick", "--controller", "lqr", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    line = next(row for row in out.splitlines() if row.strip().startswith("feedback:"))
    assert "settling n/a (its actuators saturate at 500 N from t = " in line
    assert "- feedback: no settling time: its actuators saturate at 500 N" in (tmp_path / "report.md").read_text()


def test_the_stability_line_gives_the_weights_share_its_unit():
    line = stability(load_scenario("paper-table-3-2")).describe()
    assert "the weight above their attachment points takes " in line
    assert line.split("takes ", 1)[1].split(")")[0].endswith(" N m/rad")


def test_hinf_without_slycot_names_the_extra_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "slycot", None)  # import slycot then raises ImportError
    lin = linearise(load_scenario("paper-table-3-2-active"))
    with pytest.raises(ParameterError, match=r'pip install "\.\[hinf\]"'):
        fb.hinf(lin)
