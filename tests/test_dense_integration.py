"""The DOP853 integration with dense output, the staged right-hand side, batched equilibria and batches.

Independent checks: the tableau against the exact solution of a harmonic
oscillator (numpy only, no casadi), the compiled DOP853 path against RK4 with
eight substeps on the same grid, the compiled C++ loop (one run, or four in
SIMD lanes) against casadi's evaluator of the same steps written as a casadi
graph, batches against single runs, and the vectorised helpers against their
one-at-a-time forms.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from conftest import asymmetric_3d_dict, base_dict
from isolator import (
    ScenarioError,
    SimulationError,
    Simulator,
    UnstableTableError,
    load_scenario,
    scenario_from_dict,
)
from isolator.model.equilibrium import static_equilibria, static_equilibrium
from isolator.model.signals import relative_rotation_vector, table_signals
from isolator.model.variants import EXACT
from isolator.numerics.dop853 import STAGES, TAIL, dop853_tableau, step_plan
from isolator.numerics.native import MappedFunction
from isolator.simulation.settling import settling_time, settling_times
from isolator.simulation.stepping import rk4_stepper
from studies.paper import relative_rms


# -- the method ---------------------------------------------------------------------------------
def _dop853_step(a: np.ndarray, y0: np.ndarray, h: float, fractions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One DOP853 step of y' = a y in numpy from the tableau: the new state and the dense output."""
    tab = dop853_tableau()
    k = np.zeros((STAGES, y0.size))
    for i in range(STAGES):
        k[i] = a @ (y0 + h * tab.a[i, :i] @ k[:i])
    y1 = y0 + h * tab.weights @ k[: tab.end]
    powers = fractions[None, :] ** np.arange(1, tab.dense.shape[1] + 1)[:, None]
    dense = y0[:, None] + h * k.T @ tab.dense @ powers
    return y1, dense


def test_the_tableau_is_eighth_order_with_a_seventh_order_dense_output():
    omega = 2 * np.pi * 5.0
    a = np.array([[0.0, 1.0], [-(omega**2), -0.02 * omega]])
    y0 = np.array([1.0, 0.0])
    s = np.linspace(0.05, 1.0, 20)
    step_errors, dense_errors = [], []
    for h in (0.02, 0.01):
        y1, dense = _dop853_step(a, y0, h, s)
        exact = np.stack([expm(a * h * f) @ y0 for f in s], axis=1)
        step_errors.append(np.abs(y1 - expm(a * h) @ y0).max())
        dense_errors.append(np.abs(dense - exact).max())
    # local errors: h^9 for the step, h^8 for the interpolant
    assert step_errors[0] / step_errors[1] > 2**8.5
    assert dense_errors[0] / dense_errors[1] > 2**7.5
    # the interpolant ends on the step
    _, end = _dop853_step(a, y0, 0.02, np.array([1.0]))
    assert np.allclose(end[:, 0], _dop853_step(a, y0, 0.02, s)[0], rtol=1e-12, atol=1e-12)


def test_the_step_plan_keeps_breakpoints_on_step_edges_and_reads_every_sample_once():
    samples = np.arange(0, 2001) / 1000.0
    breakpoints = np.array([0.2, 0.2505, 1.0, 1.7])
    plan = step_plan(samples, breakpoints, 0.03)
    real = slice(0, plan.steps)
    ends = plan.start[real] + plan.length[real]
    assert plan.start.size % TAIL == 0
    assert np.all(plan.length[real] <= 0.03 + 1e-12)
    assert np.all(plan.length[plan.steps:] == 0.0)
    for b in breakpoints:  # never strictly inside a step
        assert not np.any((plan.start[real] < b - 1e-12) & (ends > b + 1e-12))
    flat = plan.fraction.ravel()
    assert np.unique(plan.sample_slots).size == samples.size - 1
    owner = plan.sample_slots // plan.per_step
    times = plan.start[owner] + flat[plan.sample_slots] * plan.length[owner]
    assert np.allclose(times, samples[1:], atol=1e-12)
    assert np.all(flat[plan.sample_slots] > 0)
    unused = np.setdiff1d(np.arange(flat.size), plan.sample_slots)
    assert np.all(flat[unused] == -1.0)
    assert plan.first[0] == 1.0
    assert np.count_nonzero(plan.first[: plan.steps]) == breakpoints.size + 1


# -- the compiled path against RK4 ---------------------------------------------------------------
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


def test_the_staged_right_hand_side_is_the_right_hand_side():
    rng = np.random.default_rng(3)
    data = asymmetric_3d_dict()
    data["actuators"] = [{"name": "z1", "position": [0.5, 0.2, -0.1], "direction": [0, 0, 1], "max_force": 100.0}]
    data["ground"] = {"z": {"type": "sine", "amplitude": 1e-6, "omega": 20.0}}
    for sc in (load_scenario("paper-table-3-2"), scenario_from_dict(data)):
        sim = Simulator(sc)
        model, p = sim.model, sim.parameters
        for _ in range(5):
            x = rng.normal(size=13) * 1e-2
            x[3:7] = [1.0, 0.02, -0.01, 0.03]
            u = rng.normal(size=model.layout.input_size) * 0.2
            direct = np.asarray(model.rhs(x, u, p)).ravel()
            staged = np.asarray(model.staged_rhs(x, model.staged_inputs(u, p), p)).ravel()
            assert np.allclose(staged, direct, rtol=1e-12, atol=1e-12 * np.abs(direct).max())


# -- equilibria and batches --------------------------------------------------------------------
def test_batched_equilibria_match_one_at_a_time_and_name_the_failing_run():
    sc = load_scenario("paper-table-3-2")
    sim = Simulator(sc)
    params = np.array([sim.scaled_parameters(k, c) for k, c in ((0.5, 1.0), (1.0, 2.0), (2.0, 4.0))])
    many = static_equilibria(sim.model, params, sc.initial_positions())
    for p, eq in zip(params, many, strict=True):
        one = static_equilibrium(sim.model, p, sc.initial_positions())
        assert np.allclose(eq.pose, one.pose, rtol=0, atol=1e-14)
        assert np.allclose(np.sort_complex(eq.eigenvalues), np.sort_complex(one.eigenvalues), rtol=1e-9, atol=1e-9)
    soft = params.copy()
    soft[1] = sim.scaled_parameters(1e-4, 1.0)  # far too soft: the table tips
    with pytest.raises(UnstableTableError, match=r"^run 1: "):
        static_equilibria(sim.model, soft, sc.initial_positions())


def test_a_batch_gives_the_single_runs_metrics():
    sim = Simulator(load_scenario("paper-table-3-2"))
    stiffness, damping = [0.6, 1.0, 1.9], [3.5, 1.0, 0.6]
    batch = sim.run_batch(stiffness, damping, workers=2)
    for i, (k, c) in enumerate(zip(stiffness, damping, strict=True)):
        single = sim.run(p=sim.scaled_parameters(k, c))
        assert batch.settling_time_max[i] == pytest.approx(single.settling_time_max, abs=1e-12)
        assert np.allclose(batch.settling_time[i], list(single.settling_time.values()), rtol=0, atol=1e-12)
        # four runs per SIMD call round differently from one (fast-math): ~1e-16 m on a 2e-6 m peak
        assert np.allclose(batch.peak[i], list(single.peak.values()), rtol=1e-9, atol=0)


def test_an_empty_batch_and_mismatched_scales():
    sim = Simulator(load_scenario("paper-table-3-2"))
    assert sim.run_batch([], []).peak.shape == (0, 6)
    with pytest.raises(Exception, match="damping: needs one scale per stiffness scale"):
        sim.run_batch([1.0], [])


# -- vectorised helpers ----------------------------------------------------------------------------
def test_settling_of_many_signals_is_settling_of_each():
    t = np.arange(0, 5001) / 1000.0
    rng = np.random.default_rng(0)
    signals = np.exp(-t / rng.uniform(0.2, 1.5, (4, 1))) * np.sin(2 * np.pi * rng.uniform(1, 5, (4, 1)) * t)
    final = rng.normal(size=4) * 1e-3
    band = np.array([0.05, 0.01, 0.2, 1e-6])
    many = settling_times(t, signals, final, 1.0, band, hold=0.3)
    assert many == [settling_time(t, s, f, 1.0, b, hold=0.3) for s, f, b in zip(signals, final, band, strict=True)]


def test_rotation_vectors_against_one_reference_per_row():
    rng = np.random.default_rng(1)
    q = rng.normal(size=(6, 4))
    refs = rng.normal(size=(6, 4))
    rows = relative_rotation_vector(q, refs)
    one_by_one = np.vstack([relative_rotation_vector(q[i : i + 1], refs[i]) for i in range(6)])
    assert np.allclose(rows, one_by_one, rtol=1e-14, atol=1e-14)


def test_a_mapped_function_over_a_part_block():
    import casadi as ca

    x, y = ca.SX.sym("x", 2), ca.SX.sym("y", 3)
    fn = ca.Function("f", [x, y], [ca.vertcat(x[0] * y[2], ca.sin(x[1])), x @ y[:2].T])
    mapped = MappedFunction(fn, "test_mapped_block", block=4)
    xs, ys = np.random.default_rng(2).normal(size=(7, 2)), np.array([1.0, 2.0, 3.0])
    column, matrix = mapped(xs, ys)
    for i in range(7):
        c, m = fn(xs[i], ys)
        assert np.allclose(column[i], np.asarray(c).ravel())
        assert np.allclose(matrix[i], np.asarray(m))


def test_the_series_rotation_vector_is_exact_up_to_the_divergence_limit():
    from isolator.model.signals import signal_function

    signals = signal_function(EXACT, 13)
    rng = np.random.default_rng(4)
    for angle in (1e-6, 1e-3, 0.05, 0.2):
        for _ in range(20):
            axis = rng.normal(size=3)
            axis /= np.linalg.norm(axis)
            ref = rng.normal(size=4)
            ref /= np.linalg.norm(ref)
            turn = np.r_[np.cos(angle / 2), np.sin(angle / 2) * axis]
            q = np.r_[turn[0] * ref[0] - turn[1:] @ ref[1:],
                      turn[0] * ref[1:] + ref[0] * turn[1:] + np.cross(turn[1:], ref[1:])]
            q *= rng.choice([-1.0, 1.0]) * rng.uniform(0.5, 2.0)  # either sign, any scale
            x, r = np.zeros(13), np.zeros(13)
            x[3:7], r[3:7] = q, ref
            series = np.asarray(signals(x, r)).ravel()[3:]
            assert np.allclose(series, angle * axis, rtol=0, atol=1e-15 + 2e-15 * angle)
            assert np.allclose(series, relative_rotation_vector(q[None], ref)[0], rtol=0, atol=1e-15)


def test_the_stepper_without_a_compiler_gives_the_same_run(monkeypatch):
    import isolator.numerics.native as native
    from isolator.model.signals import signal_function
    from isolator.numerics.dop853 import DenseStepper

    data = base_dict()
    data["simulation"] = {"duration": 1.2, "sample_rate": 500.0}
    sim = Simulator(scenario_from_dict(data))
    p = sim.parameters
    start, end = sim.equilibria(p)
    method = sim.method_for(max(start.max_frequency, end.max_frequency))
    inputs = sim.plan_inputs(method, p)
    signals = signal_function(EXACT, 13)
    compiled = DenseStepper(sim.model, signals)
    evaluated = DenseStepper(sim.model, signals, compile=False)
    assert compiled.native
    assert not evaluated.native
    a = compiled.run(start.state, method.plan, inputs, p, start.state)
    b = evaluated.run(start.state, method.plan, inputs, p, start.state)
    # the same numbers up to rounding (the compiled code is built with -ffast-math)
    assert np.allclose(a[0], b[0], rtol=0, atol=1e-10 * np.abs(a[0]).max())
    assert np.allclose(a[1], b[1], rtol=0, atol=1e-10 * np.abs(a[1]).max())
    # a C compiler but no C++ one: the casadi graph is compiled as C, with a warning
    any_compiler = native._compiler
    monkeypatch.setattr(native, "_compiler", lambda language="c": any_compiler(language) if language == "c" else None)
    with pytest.warns(RuntimeWarning, match=r"no C\+\+ compiler found \(set CXX\)"):
        graph = DenseStepper(sim.model, signals)
    assert not graph.native
    c = graph.run(start.state, method.plan, inputs, p, start.state)
    assert graph.graph is not None
    assert graph.graph.functions(method.plan.per_step, True)[0].native
    assert np.allclose(c[0], b[0], rtol=0, atol=1e-10 * np.abs(a[0]).max())


@pytest.mark.parametrize("kind", ["exact", "paper"])
def test_four_runs_side_by_side_step_like_casadis_evaluator_one_at_a_time(kind):
    from isolator.model.signals import signal_function
    from isolator.numerics.dop853 import DenseStepper

    data = asymmetric_3d_dict()
    data["simulation"] = {"duration": 1.6, "sample_rate": 500.0}
    sim = Simulator(scenario_from_dict(data), model=kind)
    params = np.array([sim.scaled_parameters(k, c) for k, c in ((0.6, 3.0), (1.0, 1.0), (1.4, 0.5), (2.0, 2.0))])
    starts = [sim.equilibria(p)[0] for p in params]
    method = sim.method_for(max(s.max_frequency for s in starts))  # one plan for all four
    plan, inputs = method.plan, sim.plan_inputs(method, params[0])
    x0 = np.array([s.state for s in starts])
    signals = signal_function(sim.model.variant, sim.model.n_states)
    lanes = DenseStepper(sim.model, signals, lanes=4)
    assert lanes.native
    sig, peaks, polys = lanes.run_slots(x0, plan, inputs, params, x0, with_states=True)
    assert sig.shape[-1] == peaks.shape[-1] == polys.shape[-1] == 4
    evaluated = DenseStepper(sim.model, signals, compile=False)
    for lane in range(4):
        ref_sig, ref_peaks, ref_polys = evaluated.run_slots(
            x0[lane], plan, inputs, params[lane], x0[lane], with_states=True
        )
        scale = np.abs(ref_sig[plan.sample_slots]).max()
        assert scale > 1e-6  # the runs move
        assert np.allclose(sig[plan.sample_slots, :, lane], ref_sig[plan.sample_slots], rtol=0, atol=1e-10 * scale)
        assert np.allclose(peaks[..., lane], ref_peaks, rtol=0, atol=1e-10 * scale)
        # the states at the samples (the dense output's high coefficients are sums that cancel)
        ours, theirs = (DenseStepper.states(plan, q) for q in (polys[..., lane], ref_polys))
        assert np.allclose(ours, theirs, rtol=0, atol=1e-9 * np.abs(theirs).max(axis=0))
    # the lanes are the runs: different parameters, different answers
    assert np.abs(sig[plan.sample_slots, :, 0] - sig[plan.sample_slots, :, 3]).max() > 1e-3 * scale
    with pytest.raises(ValueError, match="lanes"):
        lanes.run_slots(x0[0], plan, inputs, params[0], x0[0])


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
    assert np.allclose(batch.settling_time[3], expected, rtol=0, atol=1e-12, equal_nan=True)
    assert np.allclose(batch.peak[3], list(single.peak.values()), rtol=1e-9)
    with pytest.raises(ScenarioError, match="diverged: must be"):
        sim.run_batch([1.0], [1.0], diverged="ignore")


def test_a_compiler_error_is_one_line_naming_the_library(tmp_path, monkeypatch):
    from isolator.numerics.native import compiled_library

    monkeypatch.setenv("ISOLATOR_CACHE", str(tmp_path))
    with pytest.raises(RuntimeError, match=r"failed on broken: .*error"):
        compiled_library("broken", "int f( {", language="c++")
    assert not list(tmp_path.glob("*.so"))  # nothing half-built is left
    assert not list(tmp_path.glob("*.cpp"))


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
