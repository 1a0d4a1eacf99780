"""The isolation-against-settling study: its numbers against single runs and direct
linearisations, the physics its maps must show, the Pareto front's definition, and its files."""

from __future__ import annotations

import csv
from dataclasses import replace

import numpy as np
import pytest

from conftest import base_dict, make
from isolator import ParameterError, ScenarioError, Simulator, load_scenario
from isolator.analysis.linear import linearise
from isolator.cli.app import main
from studies.tradeoff import pareto_front, run_tradeoff_study


def test_pareto_front_by_its_definition():
    points = np.array([[1.0, 5.0], [2.0, 3.0], [2.0, 4.0], [3.0, 3.0], [4.0, 1.0], [np.nan, 0.0], [0.5, 9.0]])
    front = pareto_front(points)
    assert list(front) == [6, 0, 1, 4]  # by increasing first objective; ties and NaN rows out
    rng = np.random.default_rng(3)
    cloud = rng.uniform(size=(200, 2))
    front = set(pareto_front(cloud).tolist())
    for i, p in enumerate(cloud):
        dominated = np.any(np.all(cloud <= p, axis=1) & np.any(cloud < p, axis=1))
        assert dominated == (i not in front)


@pytest.fixture(scope="module")
def paper_study(tmp_path_factory):
    folder = tmp_path_factory.mktemp("tradeoff")
    sc = load_scenario("paper-table-3-2")
    return run_tradeoff_study(folder, sc, stiffness=[0.25, 0.5, 1.0, 2.0], damping=[0.5, 1.0, 2.0, 4.0],
                              progress=False)


def test_the_study_gives_single_runs_and_direct_linearisations(paper_study):
    study = paper_study
    sc = study.scenario
    assert study.stable.all()
    assert np.isfinite(study.settling_time).all()
    sim = Simulator(replace(sc, simulation=replace(sc.simulation, duration=study.duration)))
    for i, j in ((0, 0), (2, 1), (3, 3)):
        run = sim.run(p=sim.scaled_parameters(study.stiffness[i], study.damping[j]))
        assert study.settling_time[i, j] == pytest.approx(run.settling_time_max, abs=1e-9)
        lin = linearise(sc, parameters=sim.scaled_parameters(study.stiffness[i], study.damping[j]))
        h = lin.frequency_response(np.array([10.0]), ["ground:x", "ground:y", "ground:z"], ["x", "y", "z"])[0]
        assert study.transmissibility[i, j] == pytest.approx(np.abs(np.diag(h)).max(), rel=1e-12)
    assert study.nominal() == (2, 1)


def test_the_maps_show_the_physics_of_isolators(paper_study):
    study = paper_study
    sim = Simulator(study.scenario)
    # damping lowers the resonance peak, and lets more floor motion through well above every mode
    # (the dashpot's force grows with frequency, the spring's does not)
    assert np.all(np.diff(study.peak, axis=1) < 0)
    checked = 0
    for i, k in enumerate(study.stiffness):
        lin = linearise(study.scenario, parameters=sim.scaled_parameters(k, 1.0))
        if 2.0 * np.abs(lin.eigenvalues).max() / (2 * np.pi) < study.reference_hz:
            assert np.all(np.diff(study.transmissibility[i]) > 0), k
            checked += 1
    assert checked >= 2
    # stiffer isolators isolate worse at 10 Hz and resonate at higher frequencies
    assert np.all(np.diff(study.transmissibility, axis=0) > 0)
    assert np.all(np.diff(study.peak_hz, axis=0) > 0)
    # the design that damps most settles fastest at every stiffness
    assert np.all(np.argmin(study.settling_time, axis=1) == study.damping.size - 1)
    front = study.pareto()
    assert front
    for p in front:  # nothing on the grid beats a front design in both
        better = (study.settling_time <= study.settling_time[p]) & (study.transmissibility <= study.transmissibility[p])
        strictly = (study.settling_time < study.settling_time[p]) | (study.transmissibility < study.transmissibility[p])
        assert not np.any(better & strictly)


def test_the_study_writes_its_files(paper_study):
    folder = paper_study.folder
    for name in ("maps.png", "tradeoff.png"):
        assert (folder / name).stat().st_size > 30_000
    with open(folder / "designs.csv") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 16
    assert {r["status"] for r in rows} == {"ok"}
    report = (folder / "report.md").read_text()
    assert "## Pareto-optimal designs" in report
    assert "| 1 | 1 |" in report  # the scenario's design


def test_tipping_designs_are_marked_not_run(tmp_path):
    study = run_tradeoff_study(tmp_path, make(base_dict()), stiffness=[0.005, 1.0], damping=[1.0, 2.0],
                               progress=False)
    assert list(study.stable) == [False, True]
    assert np.isnan(study.settling_time[0]).all()
    assert np.isnan(study.transmissibility[0]).all()
    assert np.isfinite(study.transmissibility[1]).all()
    assert "tips at stiffness x0.005" in (tmp_path / "report.md").read_text()


def test_bad_study_input_is_named(tmp_path):
    sc = make(base_dict())
    with pytest.raises(ParameterError, match="reference_hz"):
        run_tradeoff_study(tmp_path, sc, reference_hz=0.0, progress=False)
    with pytest.raises(ParameterError, match="stiffness: scale factors must be"):
        run_tradeoff_study(tmp_path, sc, stiffness=[1.0, 0.5], progress=False)
    with pytest.raises(ParameterError, match="damping: give at least two"):
        run_tradeoff_study(tmp_path, sc, damping=[1.0], progress=False)
    data = base_dict()
    data["carriages"][0]["profile"] = {"type": "sine", "amplitude": 0.1, "omega": 3.0}
    with pytest.raises(ScenarioError, match="never stop"):
        run_tradeoff_study(tmp_path, make(data), progress=False)


def test_the_command_runs_the_quick_study(tmp_path, capsys):
    assert main(["study", "tradeoff", "--out", str(tmp_path), "--quick", "--frequency", "8"]) == 0
    out = capsys.readouterr().out
    assert "Pareto-optimal designs of 12" in out
    assert "transmissibility at 8 Hz" in (tmp_path / "report.md").read_text()
    assert main(["study", "tradeoff", "--out", str(tmp_path), "--frequency", "0"]) == 2
    assert capsys.readouterr().err.strip() == "isolator: error: --frequency: must be a finite frequency > 0 Hz, got 0.0"


def test_each_designs_settling_time_is_reproduced_in_the_band_beside_it(paper_study, capsys):
    """Each design is judged in its own 5 % band (``band`` column); ``Simulator.run(p=..., band=...)``
    reproduces any design, ``isolator simulate --band`` the scenario's own design."""
    import json

    from isolator import Band
    from isolator.simulation.band import parse_half_widths

    study = paper_study
    sc = study.scenario
    with open(study.folder / "designs.csv") as handle:
        rows = list(csv.DictReader(handle))
    assert study.band.kind == "own"
    sim = Simulator(replace(sc, simulation=replace(sc.simulation, duration=study.duration)))
    for i, j in ((0, 0), (3, 3)):
        row = rows[i * study.damping.size + j]
        band = parse_half_widths(row["band"])
        np.testing.assert_allclose(band.half_widths, study.half_widths[i, j], rtol=1e-15)
        run = sim.run(p=sim.scaled_parameters(study.stiffness[i], study.damping[j]), band=band)
        assert run.settling_time_max == pytest.approx(float(row["settling_time_max_s"]), rel=1e-5)
        assert run.settling_time_max == pytest.approx(study.settling_time[i, j], abs=1e-9)
        # a neighbour's band gives another number: the band matters
        other = Band.absolute(study.half_widths[(i + 1) % 4, (j + 1) % 4])
        assert sim.run(p=sim.scaled_parameters(study.stiffness[i], study.damping[j]),
                       band=other).settling_time_max != pytest.approx(study.settling_time[i, j], abs=1e-6)
    nominal = study.nominal()
    cell = rows[nominal[0] * study.damping.size + nominal[1]]["band"]
    assert main(["simulate", "paper-table-3-2", "--json", "--band", cell]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["settling_time_max"] == pytest.approx(study.settling_time[nominal], abs=1e-6)
    assert "--band x=" in (study.folder / "report.md").read_text()
