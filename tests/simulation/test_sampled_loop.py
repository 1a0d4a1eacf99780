"""The compiled closed loop with an exported controller (docs/scenario-format.md, "Sensors in the scenario, output
feedback and exported controllers"): against the same loop written here in numpy on the linearised plant,
delay, schedules, noise, the command line, and the state-feedback laws against the Python loop it replaced."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import tomli_w
from scipy.linalg import expm

import isolator.simulation.closed_loop as loopmod
from conftest import active_dict, make, run_command
from controllers import feedback as fb
from isolator import ParameterError, Simulator, scenario_from_dict
from isolator.analysis.linear import linearise
from isolator.numerics.rk4 import BY_TIME
from isolator.scenario.definitions import SIGNALS
from isolator.simulation.actuation import ForceHistory, lag_constants
from isolator.simulation.closed_loop import controller_factor, controller_law
from isolator.simulation.discrete_controller import DiscreteController, ScheduleEntry
from isolator.simulation.lag_steps import held_interval
from isolator.simulation.stepping import rk4_stepper
from sampled_loops import RATE, dynamic, geophone_data, names, pulse, settling


@pytest.fixture(scope="module")
def parked():
    return scenario_from_dict(geophone_data())


def linear_loop(s, ctrl: DiscreteController, forces: ForceHistory) -> tuple[np.ndarray, np.ndarray]:
    """The same loop in plain numpy: the linearised plant and the actuators' lag sampled exactly at the
    controller's rate (the command is constant between ticks), zero-order hold, clip, one-sample delay.
    Returns the tick times and the six signals there (6, ticks)."""
    lin = linearise(s)
    a, b, c, d = (np.asarray(getattr(lin.system, k)) for k in "ABCD")
    inputs, outputs = list(lin.system.input_labels), list(lin.system.output_labels)
    acts = [inputs.index(f"actuator:{x.name}") for x in s.actuators]
    sens = [outputs.index(f"s:{x.name}") for x in s.sensors]
    sig = [outputs.index(k) for k in SIGNALS]
    n, m, tau = a.shape[0], len(acts), 1.0 / (2 * np.pi * 200.0)
    limit = np.array([x.max_force for x in s.actuators])
    f = np.zeros((n + m, n + m))
    f[:n, :n], f[:n, n:], f[n:, n:] = a, b[:, acts], -np.eye(m) / tau
    g = np.vstack([np.zeros((n, m)), np.eye(m) / tau])
    big = expm(np.block([[f, g], [np.zeros((m, n + 2 * m))]]) / RATE)
    phi, gamma = big[: n + m, : n + m], big[: n + m, n + m:]
    ticks = np.arange(round(s.simulation.duration * RATE) + 1) / RATE
    z, xc, hold, pending = np.zeros(n + m), np.zeros(ctrl.states), np.zeros(m), np.zeros(m)
    ff = forces.command(ticks, ticks + 0.5 / RATE)
    out = np.empty((6, ticks.size))
    for k in range(ticks.size):
        out[:, k] = c[sig] @ z[:n] + d[sig][:, acts] @ z[n:]
        y = c[sens] @ z[:n] + d[sens][:, acts] @ z[n:]
        xc, u = ctrl.step(xc, y)
        hold, pending = (pending, u) if ctrl.delay else (u, u)
        z = phi @ z + gamma @ np.clip(hold + ff[k], -limit, limit)
    return ticks, out


@pytest.mark.parametrize(("delay", "quantity"), [(False, "velocity"), (True, "velocity"), (False, "acceleration")])
def test_the_compiled_loop_is_the_numpy_loop_on_the_linear_plant(parked, delay, quantity):
    """Accelerometers read the left limit at a tick: with the actuators' lag, the force is continuous there."""
    if quantity != "velocity":
        parked = scenario_from_dict(geophone_data(quantity=quantity))
    ctrl = dynamic(parked, delay)
    forces = pulse(parked)
    run = Simulator(parked).run(controller=ctrl, forces=forces)
    ticks, ref = linear_loop(parked, ctrl, forces)
    assert np.abs(run.actuator_forces).max() == pytest.approx(80.0)  # clipping binds
    scale = np.abs(ref).max(axis=1, keepdims=True)
    err = np.abs(run.signals - ref[:, ::2]).max(axis=1, keepdims=True) / scale
    assert err.max() < 5e-4, err.ravel()  # the linearisation's error
    times, ref_times = np.array([run.settling[k].time for k in SIGNALS]), settling(parked, run, ticks, ref)
    np.testing.assert_allclose(times, ref_times, atol=1e-3)
    if quantity != "velocity":
        return
    # the delay is one sample: the other loop is further off than the linearisation and the integration
    _, other = linear_loop(parked, dynamic(parked, not delay), forces)
    assert (np.abs(run.signals - other[:, ::2]).max(axis=1, keepdims=True) / scale).max() > 5 * err.max()


def test_a_delayed_command_acts_one_sample_later():
    """A weak static gain (the plant all but open-loop), actuators without lag: the force held over each
    interval is the gain times the readings at its start, or with delay at the previous tick."""
    data = geophone_data()
    for act in data["actuators"]:
        del act["bandwidth"]
    s = scenario_from_dict(data)
    static = {"A": np.zeros((0, 0)), "B": np.zeros((0, 12)), "C": np.zeros((12, 0)), "D": -1e-3 * np.eye(12)}
    applied = {}
    for delay in (False, True):
        captured = {}

        def spy(*args, captured=captured, original=loopmod.run_closed_loop):
            captured["out"] = original(*args)
            return captured["out"]

        with pytest.MonkeyPatch.context() as patch:
            patch.setattr(loopmod, "run_closed_loop", spy)
            Simulator(s).run(controller=DiscreteController(RATE, *names(s), **static, delay=delay), forces=pulse(s))
        applied[delay] = captured["out"][1][:, 0, Simulator(s).layout.actuator_slice][:, 1]  # y1: feedback alone
    now, later = applied[False], applied[True]
    assert later[0] == 0.0
    assert np.abs(now).max() > 1e-9
    np.testing.assert_allclose(later[1:], now[:-1], rtol=1e-4, atol=1e-6 * np.abs(now).max())
    assert np.abs(later - now).max() > 100 * np.abs(later[1:] - now[:-1]).max()


def test_a_scheduled_controller_reads_the_carriages_raw_positions():
    s = scenario_from_dict(geophone_data(parked=False, duration=12.0))
    sensors, actuators, carriages = names(s)
    zero = np.zeros((0, 0)), np.zeros((0, 12)), np.zeros((12, 0))
    points = [ScheduleEntry([0.0, 0.0], *zero, np.zeros((12, 12))),
              ScheduleEntry([0.05, 0.0], *zero, -2000.0 * np.eye(12))]
    ctrl = DiscreteController(RATE, sensors, actuators, carriages, schedule=points, schedule_carriage=0)
    run = Simulator(s).run(controller=ctrl)
    q = run.q[0]
    acting = np.abs(run.actuator_forces).max(axis=0) > 0
    # no force until the x-stage passes its raw position 0 (it starts at -0.7), then force
    assert not acting[q <= 0.0].any()
    assert acting[q > 0.01].all()
    # the weights are matrices()'s interpolation
    qs = np.array([[-1.0, 0.0], [0.0, 0.0], [0.01, 0.0], [0.05, 0.3], [0.2, 0.0], [np.nan, 0.0]])
    w = ctrl.schedule_weights(qs)
    for row, weights in zip(qs, w, strict=True):
        np.testing.assert_allclose(ctrl.matrices(row)[3], sum(wj * p.D for wj, p in zip(weights, points, strict=True)),
                                   rtol=1e-15, atol=1e-12)


def test_noise_is_seeded_reproducible_and_off_by_default(parked):
    sim = Simulator(parked)
    p = sim.parameters
    start, _ = sim.equilibria(p)
    ctrl = dynamic(parked)
    t = np.arange(4000) / RATE
    quiet = controller_law(parked, sim.model, p, start, ctrl).offsets(t)
    assert np.all(quiet == quiet[0])
    assert np.abs(quiet).max() < 1e-12  # the geophones read zero at rest
    one = controller_law(parked, sim.model, p, start, ctrl, noise=True, seed=1).offsets(t)
    again = controller_law(parked, sim.model, p, start, ctrl, noise=True, seed=1).offsets(t)
    other = controller_law(parked, sim.model, p, start, ctrl, noise=True, seed=2).offsets(t)
    np.testing.assert_array_equal(one, again)
    assert not np.allclose(one, other)
    sigma = np.array([x.noise for x in parked.sensors])
    np.testing.assert_allclose((one - quiet).std(axis=0), sigma, rtol=0.06)
    runs = [sim.run(controller=ctrl, noise=noise, seed=seed) for noise, seed in ((True, 1), (True, 1), (False, 1),
                                                                                  (False, 5))]
    np.testing.assert_array_equal(runs[0].signals, runs[1].signals)
    np.testing.assert_array_equal(runs[2].signals, runs[3].signals)  # no noise: the seed does not matter
    assert not np.array_equal(runs[0].signals, runs[2].signals)


def test_the_stepping_rate_is_a_multiple_of_both_rates(parked):
    settings = parked.simulation
    assert controller_factor(settings, 2000.0) == (2, 1)
    assert controller_factor(settings, 300.0) == (3, 10)
    assert controller_factor(settings, 1000.0) == (1, 1)
    with pytest.raises(ParameterError, match=r"^controller: its sample rate 1234\.57 Hz fits no stepping grid of "
                       r"simulation\.sample_rate 1000 Hz"):
        controller_factor(settings, 1234.567)


def _write(folder: Path, data: dict) -> Path:
    folder.mkdir()
    (folder / "controller.json").write_text(json.dumps(data))
    return folder


def test_command_line(tmp_path, capsys, parked):
    scenario = tmp_path / "parked.toml"
    scenario.write_text(tomli_w.dumps(geophone_data()))
    good = dynamic(parked).to_dict()
    ok = _write(tmp_path / "ok", good)
    status, out, err = run_command(["simulate", str(scenario), "--controller", str(ok), "--json", "--noise",
                                    "--seed", "3"], capsys)
    assert status == 0, err
    assert max(json.loads(out)["peak"].values()) > 0  # the noise moved the table
    renamed = dict(good, sensors=[*good["sensors"][:3], "v-elsewhere", *good["sensors"][4:]])
    cases = [
        (["--controller", str(_write(tmp_path / "renamed", renamed))],
         ("sensors[3]", "'v-elsewhere'", "'v-x2'")),
        (["--controller", str(_write(tmp_path / "shape", dict(good, actuators=good["actuators"][:-1])))],
         ("--controller", "C: must be 11 x 12")),
        (["--controller", str(_write(tmp_path / "carriages", dict(good, carriages=["x-stage"])))],
         ("controller.carriages", "has 1 where", "'y-stage'")),  # counts, never "has None" (issue 42, 15)
        (["--controller", str(tmp_path / "missing")], ("--controller", "missing/controller.json")),
        (["--controller", str(_write(tmp_path / "corrupt", {}))], ("--controller", "sample_rate: missing")),
        (["--controller", str(_write(tmp_path / "rate", dict(good, sample_rate=1234.567)))],
         ("1234.57 Hz", "1000 Hz")),
        (["--noise"], ("--noise", "--controller")),
    ]
    (tmp_path / "broken").mkdir()
    (tmp_path / "broken" / "controller.json").write_text("{not json")
    cases.append((["--controller", str(tmp_path / "broken")], ("--controller", "cannot read as JSON", "line 1")))
    for extra, words in cases:
        out_csv, plot = tmp_path / "r.csv", tmp_path / "r.png"
        status, _, lines = run_command(["simulate", str(scenario), "--out", str(out_csv), "--plot", str(plot),
                                        *extra], capsys)
        assert status == 2, (extra, lines)
        assert len(lines) == 1, lines
        assert lines[0].startswith("isolator: error: "), lines
        for word in words:
            assert word in lines[0], (word, lines[0])
        assert not out_csv.exists()
        assert not plot.exists()


def python_loop(law):
    """The loop the compiled one replaced (a Python iteration per interval calling the law, the lags' stage
    forces by lag_stages), for equality."""

    def run(scenario, model, grid, grid_inputs, p, start, substeps, forces, sampled, period):
        inputs = grid_inputs.copy()
        acts = model.layout.actuator_slice
        frac = np.arange(2 * substeps + 1) / (2 * substeps)
        times = grid.nodes[:-1, None] + np.diff(grid.nodes)[:, None] * frac
        mid = np.broadcast_to(((grid.nodes[:-1] + grid.nodes[1:]) / 2)[:, None], times.shape)
        commanded = None if forces is None else forces.command(times.ravel(), mid.ravel()).reshape(*times.shape, -1)
        ticks = grid.regular & ((np.cumsum(grid.regular) - 1) % period == 0)
        lagged = np.array([a.bandwidth is not None for a in scenario.actuators])
        stepper = rk4_stepper(model, substeps, bool(lagged.any()))
        n_a = len(scenario.actuators)
        limits, tau = np.array([a.max_force for a in scenario.actuators]), lag_constants(scenario)
        order = (2 * np.arange(substeps)[:, None] + np.array(BY_TIME)[None, :]).ravel()
        u, lag, x, motion = np.zeros(n_a), np.zeros(n_a), start.state.copy(), np.zeros(12)
        out = np.empty((grid.nodes.size - 1, x.size))
        law.reset()
        for i, h in enumerate(np.diff(grid.nodes)):
            if ticks[i]:
                u = np.asarray(law(float(grid.nodes[i]), motion), dtype=float)
            command = np.broadcast_to(u if commanded is None else commanded[i] + u, (times.shape[1], n_a))
            applied, taken, lag = held_interval(lag, command, order, substeps, h, tau, limits, lagged)
            inputs[i, :, acts] = applied
            stepped = inputs[i][order] if lagged.any() else inputs[i].copy()
            stepped[:, acts] = taken
            x, motion = stepper.step(x, stepped, float(h), p, start.state)
            out[i] = x
        return out, inputs

    return run


@pytest.mark.parametrize("bandwidth", [None, 50.0])
def test_state_feedback_laws_run_as_the_python_loop_ran_them(bandwidth, monkeypatch):
    data = active_dict(max_force=20.0, bandwidth=bandwidth)
    data["simulation"]["duration"] = 3.0
    s = make(data)
    lin = linearise(s)
    t = np.array([0.0, 0.3, 0.3, 0.5, 0.5, 3.0])
    f = np.zeros((12, t.size))
    f[2, 2:4] = 15.0
    forces = ForceHistory(t, f, tuple(a.name for a in s.actuators))
    for controller in (fb.skyhook(lin, 5e4), fb.lead(lin, 1e5, 2.0, 20.0, sample_rate=500.0)):
        law = fb.feedback_law(s, controller)
        compiled = Simulator(s).run(feedback=law, forces=forces)
        with monkeypatch.context() as patch:
            patch.setattr(loopmod, "run_closed_loop", python_loop(law))
            reference = Simulator(s).run(feedback=law, forces=forces)
        scale = np.abs(reference.signals).max(axis=1, keepdims=True)
        assert (np.abs(compiled.signals - reference.signals) / scale).max() < 1e-9
        np.testing.assert_allclose(compiled.actuator_forces, reference.actuator_forces, rtol=0, atol=1e-8)
        assert compiled.settling_time_max == pytest.approx(reference.settling_time_max, abs=1e-9)


def test_another_controller_of_the_same_shape_reuses_the_compiled_loop(parked):
    from isolator.simulation import sampled_loop

    sim, forces = Simulator(parked), pulse(parked)
    first = dynamic(parked)
    run = sim.run(controller=first, forces=forces)
    built = dict(sampled_loop._LOOPS)
    twice = DiscreteController(RATE, *names(parked), A=first.A, B=first.B, C=2 * first.C, D=2 * first.D)
    other = sim.run(controller=twice, forces=forces)
    assert built == sampled_loop._LOOPS  # the matrices are arguments of the compiled function
    assert not np.allclose(run.signals, other.signals, rtol=1e-3)
