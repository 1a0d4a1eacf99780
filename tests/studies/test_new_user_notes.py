"""Issue 26, item 7: the smaller things a new user hit (the sweep's progress is the sweep's own)."""

from __future__ import annotations

import dataclasses
import sys

import pytest

import controllers.feedback as fb
import studies.control as control_study
from isolator import ParameterError, linearise, load_scenario, stability
from isolator.cli.app import main
from studies.control import design


def test_the_control_study_says_why_a_run_shows_no_settling_time(tmp_path, capsys, monkeypatch):
    # the LQR held to the initial equilibrium (as it ran before issue 24 item 7) saturates against the tilt
    def held(name: str, lin: object) -> fb.Controller:
        return dataclasses.replace(design(name, lin), follows_path=False)

    monkeypatch.setattr(control_study, "design", held)
    assert main(["study", "control", "--quick", "--controller", "lqr", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    line = next(row for row in out.splitlines() if row.strip().startswith("feedback:"))
    assert "settling n/a (its actuators saturate at 500 N from t = " in line
    assert "- feedback: no settling time: its actuators saturate at 500 N" in (tmp_path / "report.md").read_text()


def test_the_control_study_runs_lqr_about_the_quasi_static_path(tmp_path, capsys):
    assert main(["study", "control", "--quick", "--controller", "lqr", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    settle = {row.split(":")[0].strip(): row for row in out.splitlines() if "settling" in row}
    assert "n/a" not in settle["feedback"]
    passive = float(settle["passive"].split("settling")[1].split()[0])
    assert float(settle["feedback"].split("settling")[1].split()[0]) < 0.2 * passive
    report = (tmp_path / "report.md").read_text()
    assert "With feedback alone the controller regulates to the planned move's quasi-static path" in report
    assert "no settling time" not in report


def test_the_stability_line_gives_the_weights_share_its_unit():
    line = stability(load_scenario("paper-table-3-2")).describe()
    assert "the weight above their attachment points takes " in line
    assert line.split("takes ", 1)[1].split(")")[0].endswith(" N m/rad")


def test_hinf_without_slycot_names_the_extra_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "slycot", None)  # import slycot then raises ImportError
    lin = linearise(load_scenario("paper-table-3-2-active"))
    with pytest.raises(ParameterError, match=r'pip install "\.\[hinf\]"'):
        fb.hinf(lin)
