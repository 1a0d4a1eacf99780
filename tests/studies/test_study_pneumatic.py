"""The pneumatic design study: its optimum against the closed-form relaxation isolator (1 + 2/N), its
numbers against single runs and direct linearisations, the physics of the orifice, the Pareto front's
definition, bad input, and the command."""

from __future__ import annotations

import csv
import math
from dataclasses import replace

import numpy as np
import pytest
from pneumatic_cases import pneumatic_dict

from conftest import base_dict, make
from isolator import ParameterError, Simulator, load_scenario
from isolator.analysis.linear import linearise
from isolator.analysis.pneumatic import relaxation_time
from isolator.analysis.transmissibility import transmissibility
from isolator.cli.app import main
from isolator.scenario.pneumatic import Capillary
from studies.pneumatic import closed_form_optimum, default_diameters, heave_peak, run_pneumatic_study

RATIOS = [0.5, 1.0, 2.0, 4.0, 8.0]


def one_mass_transmissibility(omega: np.ndarray, m: float, k0: float, ratio: float, tau: float) -> np.ndarray:
    """|T| of a mass on a Zener air spring, ``k = k_inf (1 + i w tau) / ((1 + N) + i w tau)``."""
    k_inf = (1 + ratio) * k0
    k = k_inf * (1 + 1j * omega * tau) / ((1 + ratio) + 1j * omega * tau)
    return np.abs(k / (k - m * omega**2))


@pytest.fixture(scope="module")
def heave_study(tmp_path_factory):
    """Four identical air springs under the table's mass centre, no carriage: heave is one mass."""
    sc = make(pneumatic_dict(carriage=False))
    d0 = sc.isolators[0].orifice.diameter
    return run_pneumatic_study(tmp_path_factory.mktemp("heave"), sc, diameters=d0 * np.array([0.5, 0.8, 1.25, 2.0]),
                               ratios=RATIOS, progress=False)


def test_the_closed_form_optimum_is_the_fixed_point_maximum():
    # the derivation checked on the one-mass formula itself: at tau = sqrt(1 + N) / w*, |T| peaks at the
    # fixed point w*^2 = 2 k0 (N + 1) / (m (N + 2)) with 1 + 2/N, and any other tau peaks higher
    m, k0 = 1000.0, 4.0e5
    omega = np.linspace(1.0, 80.0, 400_001)
    for ratio in RATIOS:
        w_star = math.sqrt(2 * k0 * (ratio + 1) / (m * (ratio + 2)))
        tau = math.sqrt(1 + ratio) / w_star
        assert tau == pytest.approx(math.sqrt(m * (ratio + 2) / (2 * k0)), rel=1e-12)
        t = one_mass_transmissibility(omega, m, k0, ratio, tau)
        assert t.max() == pytest.approx(1 + 2 / ratio, rel=1e-8)
        assert omega[np.argmax(t)] == pytest.approx(w_star, rel=1e-4)
        for other in (0.7 * tau, 1.4 * tau):
            t_other = one_mass_transmissibility(omega, m, k0, ratio, other)
            assert t_other.max() > (1 + 2 / ratio) * (1 + 1e-4)
            assert np.interp(w_star, omega, t_other) == pytest.approx(1 + 2 / ratio, rel=1e-6)  # the fixed point


def test_the_optimal_orifice_gives_the_closed_form_relaxation_isolator(heave_study):
    study = heave_study
    sc = study.scenario
    assert not study.moves
    iso = sc.isolators[0]
    air = sc.air
    gauge = sc.total_mass * sc.gravity / (4 * iso.area)  # symmetric: every spring carries a quarter
    p0 = gauge + air.atmosphere
    k0_one = air.polytropic * p0 * iso.area**2 / iso.volume
    for ratio, optimum, closed in zip(RATIOS, study.optima, study.closed_form, strict=True):
        assert not optimum.at_edge
        assert optimum.peak == pytest.approx(1 + 2 / ratio, rel=1e-6)  # 1e-14 in fact: the optimum is flat
        assert optimum.peak == pytest.approx(closed.peak, rel=1e-6)
        k0 = 4 * k0_one / (1 + ratio)
        tau = math.sqrt(sc.total_mass * (ratio + 2) / (2 * k0))
        assert closed.relaxation_time == pytest.approx(tau, rel=1e-9)
        assert closed.frequency_hz == pytest.approx(math.sqrt(2 * k0 * (ratio + 1) / (sc.total_mass * (ratio + 2)))
                                                    / (2 * math.pi), rel=1e-9)
        # the study's optimal orifice, through the library's own relaxation time of an isolator
        sized = replace(iso, damping_volume=ratio * iso.volume, orifice=Capillary(optimum.diameter, iso.orifice.length))
        assert relaxation_time(sized, gauge, air) == pytest.approx(tau, rel=1e-5)  # 3e-7 at most in fact
        assert optimum.relaxation_time == pytest.approx(relaxation_time(sized, gauge, air), rel=1e-9)
        assert optimum.diameter == pytest.approx(closed.diameter, rel=1e-5)
        assert optimum.frequency_hz == pytest.approx(closed.frequency_hz, rel=1e-4)  # the peak at the fixed point
    assert np.all(np.isnan(study.settling_time))
    assert "No carriage moves" in (study.folder / "report.md").read_text()


@pytest.fixture(scope="module")
def paper_study(tmp_path_factory):
    """The bundled pneumatic table, a quick grid around its own design (N = 2 and its orifice on it)."""
    sc = load_scenario("paper-table-3-2-pneumatic")
    d = default_diameters(sc)[[2, 7, 12]]
    return run_pneumatic_study(tmp_path_factory.mktemp("pneumatic"), sc, diameters=d, ratios=[1.0, 2.0, 4.0],
                               progress=False)


def _parameters(sim: Simulator, diameter: float, ratio: float) -> np.ndarray:
    changes = {}
    for k, iso in enumerate(sim.scenario.isolators):
        changes[f"isolators[{k}].orifice.diameter"] = diameter
        changes[f"isolators[{k}].damping_volume"] = ratio * iso.volume
    return sim.parameter_vector(changes)


def test_the_study_gives_single_runs_and_direct_linearisations(paper_study):
    study = paper_study
    sc = study.scenario
    assert study.nominal() == (1, 1)
    for i, j in ((0, 0), (1, 1), (2, 2)):
        sim = Simulator(replace(sc, simulation=replace(sc.simulation, duration=float(study.runs.duration[i, j]))))
        p = _parameters(sim, study.diameters[i], study.ratios[j])
        lin = linearise(sc, parameters=p)
        response = transmissibility(lin)
        assert study.heave_peak[i, j] == pytest.approx(response.peak("z")[0], rel=1e-9)
        assert study.rocking_peak[i, j] == pytest.approx(max(response.peak("rx")[0], response.peak("ry")[0]),
                                                         rel=1e-9)
        h = lin.frequency_response(np.array([10.0]), ["ground:x", "ground:y", "ground:z"], ["x", "y", "z"])[0]
        assert study.transmissibility[i, j] == pytest.approx(np.abs(np.diag(h)).max(), rel=1e-12)
        run = sim.run(p=p)
        assert study.contract_settling_time[i, j] == pytest.approx(run.settling_time_max or math.nan, nan_ok=True)
        assert study.settling_time[i, j] == pytest.approx(run.pneumatic.dynamic_settling_time_max, abs=1e-12)
        levels = list(run.pneumatic.leveling_time.values())
        assert study.leveling_time[i, j] == pytest.approx(max(levels), abs=1e-12)
    # the scenario's own design is the grid's (1, 1)
    assert study.own_runs.settling[0, 0] == study.settling_time[1, 1]
    assert study.own_linear["heave"] == pytest.approx(study.heave_peak[1, 1], rel=1e-9)
    # the refined optimum: no worse than the grid, and what a direct linearisation gives there
    sim = Simulator(sc)
    for j, optimum in enumerate(study.optima):
        assert optimum.peak <= np.nanmin(study.heave_peak[:, j])
        assert optimum.peak == pytest.approx(heave_peak(sc, _parameters(sim, optimum.diameter, optimum.ratio))[0],
                                             rel=1e-12)


def test_the_orifice_has_an_optimum_inside_and_larger_chambers_damp_better(paper_study):
    study = paper_study
    # too small an orifice: the spring chamber alone (stiff, undamped); too large: both chambers as one
    # (soft, undamped); in between the flow through the orifice damps
    assert np.all(study.heave_peak[1] < study.heave_peak[0])
    assert np.all(study.heave_peak[1] < study.heave_peak[2])
    d = study.optimal_diameter
    assert np.all((d > study.diameters[0]) & (d < study.diameters[-1]))
    assert not any(o.at_edge for o in study.optima)
    assert np.all(np.diff(study.optimal_peak) < 0)  # larger N, lower best peak (1 + 2/N for one mass)
    closed = np.array([c.peak for c in study.closed_form])
    np.testing.assert_allclose(study.optimal_peak, closed, rtol=0.01)  # the table is nearly one mass in heave
    # the scenario's own design settles and levels
    assert np.isfinite(study.own_runs.settling[0, 0])
    assert np.isfinite(study.own_runs.leveling[0, 0])


def test_the_pareto_front_by_its_definition(paper_study):
    study = paper_study
    front = study.pareto()
    assert front
    settle, trans = study.settling_time, study.transmissibility
    assert [settle[p] for p in front] == sorted(settle[p] for p in front)
    for i in range(study.diameters.size):
        for j in range(study.ratios.size):
            if not (np.isfinite(settle[i, j]) and np.isfinite(trans[i, j])):
                assert (i, j) not in front
                continue
            dominated = np.any((settle <= settle[i, j]) & (trans <= trans[i, j])
                               & ((settle < settle[i, j]) | (trans < trans[i, j])))
            assert dominated == ((i, j) not in front)


def test_the_study_writes_its_files(paper_study):
    folder = paper_study.folder
    for name in ("maps.png", "pareto.png"):
        assert (folder / name).stat().st_size > 30_000
    with open(folder / "designs.csv") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 9
    assert "dynamic_settling_time_s" in rows[0]
    assert "leveling_time_s" in rows[0]
    report = (folder / "report.md").read_text()
    for heading in ("## The scenario's design", "## Optimal orifice per volume ratio", "## Pareto-optimal designs",
                    "## Assumptions"):
        assert heading in report
    assert "dynamic_settling_time_max" in report


def test_bad_study_input_is_named(tmp_path):
    sc = load_scenario("paper-table-3-2-pneumatic")
    with pytest.raises(ParameterError, match=r"diameters: must be finite and > 0, got -0\.001"):
        run_pneumatic_study(tmp_path, sc, diameters=[-1e-3, 1e-3], progress=False)
    with pytest.raises(ParameterError, match="ratios: must be finite and > 0, got 0"):
        run_pneumatic_study(tmp_path, sc, ratios=[0.0, 1.0], progress=False)
    with pytest.raises(ParameterError, match="ratios: must be increasing"):
        run_pneumatic_study(tmp_path, sc, ratios=[2.0, 1.0], progress=False)
    with pytest.raises(ParameterError, match="diameters: give at least two"):
        run_pneumatic_study(tmp_path, sc, diameters=[5e-4], progress=False)
    with pytest.raises(ParameterError, match="reference_hz"):
        run_pneumatic_study(tmp_path, sc, reference_hz=-1.0, progress=False)
    with pytest.raises(ParameterError, match="needs pneumatic isolators"):
        run_pneumatic_study(tmp_path, make(base_dict()), progress=False)
    with pytest.raises(ParameterError, match="no damping chamber"):
        run_pneumatic_study(tmp_path, make(pneumatic_dict(damping_volume=0.0)), progress=False)
    data = pneumatic_dict()
    data["carriages"][0]["profile"] = {"type": "sine", "amplitude": 0.1, "omega": 3.0}
    with pytest.raises(ParameterError, match="sine and never stops"):
        run_pneumatic_study(tmp_path, make(data), progress=False)
    assert not any(tmp_path.iterdir())  # nothing written before the input is checked
    with pytest.raises(ParameterError, match="ratio"):
        closed_form_optimum(sc, 0.0)


def test_the_command_runs_the_quick_study(tmp_path, capsys):
    assert main(["study", "pneumatic", "--out", str(tmp_path), "--quick"]) == 0
    out = capsys.readouterr().out
    assert "N = 2: optimal orifice" in out
    assert "Pareto-optimal designs of 9" in out
    assert (tmp_path / "maps.png").exists()
    assert (tmp_path / "pareto.png").exists()
    assert main(["study", "pneumatic", "paper-table-3-2", "--out", str(tmp_path), "--quick"]) == 2
    assert "needs pneumatic isolators" in capsys.readouterr().err
    assert main(["study", "pneumatic", "--out", str(tmp_path), "--frequency", "0"]) == 2
    assert capsys.readouterr().err.strip() == "isolator: error: --frequency: must be a finite frequency > 0 Hz, got 0.0"


def test_each_designs_settling_times_are_reproduced_in_the_band_beside_them(paper_study):
    """Each design is judged in its own 5 % band (the ``band`` column of ``designs.csv``); the command line
    has no orifice option, so ``Simulator.run(p=..., band=...)`` reproduces a design."""
    from isolator.simulation.band import parse_half_widths

    study = paper_study
    sc = study.scenario
    with open(study.folder / "designs.csv") as handle:
        rows = list(csv.DictReader(handle))
    assert "Settling band: the scenario's `[settling]` rule" in (study.folder / "report.md").read_text()
    for i, j in ((0, 0), (2, 2)):
        row = rows[i * study.ratios.size + j]
        band = parse_half_widths(row["band"])
        sim = Simulator(replace(sc, simulation=replace(sc.simulation, duration=float(study.runs.duration[i, j]))))
        run = sim.run(p=_parameters(sim, study.diameters[i], study.ratios[j]), band=band)
        assert run.band.half_widths == band.half_widths
        assert run.pneumatic.dynamic_settling_time_max == pytest.approx(study.settling_time[i, j], abs=1e-12)
        assert float(row["dynamic_settling_time_s"]) == pytest.approx(study.settling_time[i, j], rel=1e-5)
        assert run.settling_time_max == pytest.approx(study.contract_settling_time[i, j], abs=1e-12, nan_ok=True) \
            if run.settling_time_max is not None else math.isnan(study.contract_settling_time[i, j])
