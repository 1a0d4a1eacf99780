"""Transient runs with DOP853 and dense output, and batches.

Independent checks: the DOP853 runs against RK4 with eight substeps on the
same grid, batches against single runs, the settling of many signals against
one at a time.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import asymmetric_3d_dict, base_dict
from isolator import (
    ParameterError,
    SimulationError,
    Simulator,
    load_scenario,
    scenario_from_dict,
)
from isolator.model.signals import table_signals
from isolator.simulation.settling import settling_time, settling_times
from isolator.simulation.stepping import rk4_stepper
from studies.paper import relative_rms


def _tight(sim: Simulator, p: np.ndarray) -> np.ndarray:
    """RK4 with eight substeps per sample interval: the reference signals."""
    start, _ = sim.equilibria(p)
    states = rk4_stepper(sim.model, 8).run(start.state, sim.grid_inputs(8), np.diff(sim.grid.nodes), p)
    return table_signals(np.vstack([start.state, states])[sim.grid.is_sample], start.state)


@pytest.mark.parametrize("case", ["paper-table-3-2", "asymmetric-3d"])
def test_dop853_runs_match_fine_rk4(case):
    sc = load_scenario(case) if case.startswith("paper") else scenario_from_dict(asymmetric_3d_dict())
    sim = Simulator(sc)
    for stiffness, damping in ((1.0, 1.0), (2.0, 0.5)):
        p = sim.scaled_parameters(stiffness, damping)
        start, end = sim.equilibria(p)
        method = sim.method_for(max(start.max_frequency, end.max_frequency))
        assert method.plan is not None  # smooth profiles: long DOP853 steps
        response = sim.run(p=p)
        assert relative_rms(response.signals, _tight(sim, p)).max() < 2e-7
        assert response.states.shape == (sim.grid.samples.size, 13)


def test_dense_breakpoints_choose_rk4_on_the_sample_grid():
    data = base_dict()
    t = np.linspace(0.2, 1.2, 1500)  # a sampled move: a breakpoint every 0.67 ms
    data["carriages"][0]["profile"] = {"type": "samples", "t": t.tolist(),
                                       "q": (0.1 * np.sin(np.pi * (t - 0.2))).tolist()}
    data["simulation"] = {"duration": 2.0, "sample_rate": 1000.0}
    sim = Simulator(scenario_from_dict(data))
    start, _ = sim.equilibria(sim.parameters)
    assert sim.method_for(start.max_frequency).plan is None
    batch = sim.run_batch([1.0, 1.5], [1.0, 0.5])  # such runs go one by one in a batch
    for i, (k, c) in enumerate(((1.0, 1.0), (1.5, 0.5))):
        single = sim.run(p=sim.scaled_parameters(k, c))
        assert np.allclose(batch.peak[i], list(single.peak.values()), rtol=1e-12, atol=0)
    smooth = Simulator(scenario_from_dict(base_dict()))
    assert smooth.method_for(start.max_frequency).plan is not None


def test_a_batch_gives_the_single_runs_metrics():
    sim = Simulator(load_scenario("paper-table-3-2"))
    stiffness, damping = [0.6, 1.0, 1.9], [3.5, 1.0, 0.6]
    batch = sim.run_batch(stiffness, damping, workers=2)
    for i, (k, c) in enumerate(zip(stiffness, damping, strict=True)):
        single = sim.run(p=sim.scaled_parameters(k, c))
        # the settling instants are roots on the dense output, their bands 5 % of peaks that round
        # differently in four lanes (below): ~1e-11 s
        assert batch.settling_time_max[i] == pytest.approx(single.settling_time_max, abs=1e-9)
        assert np.allclose(batch.settling_time[i], list(single.settling_time.values()), rtol=0, atol=1e-9)
        # four runs per SIMD call round differently from one (fast-math): ~1e-16 m on a 2e-6 m peak
        assert np.allclose(batch.peak[i], list(single.peak.values()), rtol=1e-9, atol=0)


def test_an_empty_batch_and_mismatched_scales():
    sim = Simulator(load_scenario("paper-table-3-2"))
    assert sim.run_batch([], []).peak.shape == (0, 6)
    with pytest.raises(Exception, match="damping: needs one scale per stiffness scale"):
        sim.run_batch([1.0], [])


def test_settling_of_many_signals_is_settling_of_each():
    t = np.arange(0, 5001) / 1000.0
    rng = np.random.default_rng(0)
    signals = np.exp(-t / rng.uniform(0.2, 1.5, (4, 1))) * np.sin(2 * np.pi * rng.uniform(1, 5, (4, 1)) * t)
    final = rng.normal(size=4) * 1e-3
    band = np.array([0.05, 0.01, 0.2, 1e-6])
    many = settling_times(t, signals, final, 1.0, band, hold=0.3)
    assert many == [settling_time(t, s, f, 1.0, b, hold=0.3) for s, f, b in zip(signals, final, band, strict=True)]


def test_a_batch_names_the_run_that_turns_too_far_or_records_it():
    data = base_dict()
    data["simulation"]["duration"] = 4.0
    data["carriages"][0]["mass"] *= 4  # rocks the soft table past 0.2 rad at stiffness x0.03
    sim = Simulator(scenario_from_dict(data))
    with pytest.raises(SimulationError, match=r"^run 2 \(stiffness x0\.03, damping x0\.05\): .*0\.2 rad"):
        sim.run_batch([1.0, 1.2, 0.03, 0.9, 1.1], [1.0, 1.0, 0.05, 1.0, 1.0])
    # or, recorded, the others still give their metrics
    batch = sim.run_batch([1.0, 1.2, 0.03, 0.9, 1.1], [1.0, 1.0, 0.05, 1.0, 1.0], diverged="record")
    assert list(batch.failures) == [2]
    assert "0.2 rad" in batch.failures[2]
    assert np.isnan(batch.settling_time_max[2])
    assert np.all(np.isnan(batch.peak[2]))
    single = sim.run(p=sim.scaled_parameters(0.9, 1.0))
    expected = [np.nan if v is None else v for v in single.settling_time.values()]
    assert np.allclose(batch.settling_time[3], expected, rtol=0, atol=1e-9, equal_nan=True)
    assert np.allclose(batch.peak[3], list(single.peak.values()), rtol=1e-9)
    with pytest.raises(ParameterError, match="diverged: must be"):
        sim.run_batch([1.0], [1.0], diverged="ignore")


@pytest.mark.parametrize("kind", ["exact", "paper"])
def test_a_table_without_carriages_stays_at_rest(kind):
    data = base_dict()
    data["carriages"] = []
    sim = Simulator(scenario_from_dict(data), model=kind)
    run = sim.run()
    assert np.abs(run.signals).max() < 1e-12
    assert run.settling_time_max == 0.0
    batch = sim.run_batch([0.5, 2.0], [1.0, 3.0])
    assert np.abs(batch.peak).max() < 1e-12
