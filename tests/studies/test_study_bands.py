"""Studies state their band and write it beside each settling time; ``isolator simulate`` (or
``Simulator.run`` where the command line cannot express the design) reproduces the study's numbers in it.

The control study's skyhook run and the profile study's ZVD move settle differently in ``isolator simulate``
(5 % of the run's own peak) and in the studies (5 % of the baseline's: the passive run's, the paper
profile's): the band explains the whole difference, and it vanishes in the same band."""

from __future__ import annotations

import json

import pytest

from controllers import feedback as fb
from controllers.profiles import ModelVariant
from isolator import Simulator, load_scenario
from isolator.analysis.linear import linearise
from isolator.cli.app import main
from studies.cli import CONTROL_SCENARIO
from studies.control import design, run_control_study
from studies.profiles import run_profile_study


def _simulate(capsys, *args):
    assert main(["simulate", "--json", *args]) == 0
    return json.loads(capsys.readouterr().out)


@pytest.fixture(scope="module")
def control(tmp_path_factory):
    folder = tmp_path_factory.mktemp("control")
    return run_control_study(folder, load_scenario(CONTROL_SCENARIO), "skyhook", progress=False)


def test_control_study_writes_one_baseline_band_beside_every_settling_time(control):
    results = json.loads((control.folder / "results.json").read_text())
    passive = control.runs["passive"]
    for run in ("passive", "feedforward", "feedback", "both"):
        band = results[run]["band"]
        assert band["kind"] == "baseline"
        assert band["baseline"] == "passive"
        assert band["fraction"] == 0.05
        assert band["half_widths"] == pytest.approx({k: 0.05 * v for k, v in passive.peak.items()}, rel=1e-12)
    report = (control.folder / "report.md").read_text()
    assert "Settling band: 5 % of the passive run's peaks" in report
    assert f"isolator simulate {CONTROL_SCENARIO} --band x=" in report


def test_control_study_numbers_are_reproduced_by_simulate(control, capsys, tmp_path):
    results = json.loads((control.folder / "results.json").read_text())
    (tmp_path / "band.json").write_text(json.dumps(results["passive"]["band"]))
    passive = _simulate(capsys, CONTROL_SCENARIO, "--band-json", str(tmp_path / "band.json"))
    assert passive["settling_time"] == results["passive"]["settling_time"]
    option = control.band.option()
    ff = _simulate(capsys, CONTROL_SCENARIO, "--band", option, "--forces", str(control.folder / "feedforward.csv"))
    assert ff["settling_time_max"] == pytest.approx(results["feedforward"]["settling_time_max"], abs=1e-9)


def test_skyhook_settling_differs_only_by_the_band(control):
    """The feedback run cannot be given to the command line: Simulator.run(feedback=..., band=...)."""
    scenario = load_scenario(CONTROL_SCENARIO)
    sim = Simulator(scenario)
    law = fb.feedback_law(scenario, design("skyhook", linearise(scenario)))
    own = sim.run(feedback=law)
    study = control.settling_time_max("feedback")
    assert own.band.kind == "own"
    # the discrepancy: the skyhook run's own peak is smaller than the passive run's, so its own band is
    # narrower and it settles later in it
    assert all(own.band.widths[k] < control.band.widths[k] for k in ("x", "ry"))
    assert own.settling_time_max > study + 0.05
    # in the study's band it vanishes, whether the run is given the band or measured again in it
    assert sim.run(feedback=law, band=control.band).settling_time_max == pytest.approx(study, abs=1e-12)
    assert own.with_band(control.band).settling_time_max == pytest.approx(study, abs=1e-12)


@pytest.fixture(scope="module")
def profiles(tmp_path_factory):
    folder = tmp_path_factory.mktemp("profiles")
    return run_profile_study(folder, load_scenario("paper-table-3-2"), (ModelVariant(),), progress=False,
                             source="paper-table-3-2")


def test_profile_study_judges_every_method_in_the_paper_profiles_band(profiles, capsys):
    results = json.loads((profiles.folder / "results.json").read_text())
    paper = profiles.methods["paper"]
    assert profiles.band.kind == "baseline"
    assert profiles.band.baseline == "paper"
    for name, entry in results.items():
        assert entry["band"]["half_widths"] == pytest.approx(
            {k: 0.05 * v for k, v in paper.peak.items()}, rel=1e-12), name
    assert "Settling band: 5 % of the paper run's peaks" in (profiles.folder / "report.md").read_text()
    # the methods a scenario file holds are written and reproduced by simulate in the study's band
    for name in ("paper", "optimised (settling)"):
        path = results[name]["scenario_file"]
        assert path is not None, name
        run = _simulate(capsys, path, "--band", profiles.band.option())
        assert run["settling_time_max"] == pytest.approx(results[name]["settling_time_max"], abs=1e-9), name


def test_zvd_settling_differs_only_by_the_band(profiles):
    """An input-shaped move is a piecewise polynomial no scenario file holds: Simulator.run(band=...)."""
    zvd = profiles.methods["ZVD"]
    sim = Simulator(profiles.scenarios["ZVD"])
    own = sim.run()
    assert own.band.kind == "own"
    assert own.settling_time_max != pytest.approx(zvd.settling_time_max, abs=1e-3)
    assert sim.run(band=profiles.band).settling_time_max == pytest.approx(zvd.settling_time_max, abs=1e-12)
    assert own.with_band(profiles.band).settling_time_max == pytest.approx(zvd.settling_time_max, abs=1e-12)
