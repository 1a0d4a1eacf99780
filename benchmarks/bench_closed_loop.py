"""Speed of a run with an exported controller: the compiled closed loop against a Python-callback loop.

The bundled ``paper-table-3-2-geophones`` scenario (12 geophones, 12 actuators with a 200 Hz lag), its
carriages twice as fast so that they stop within a 7 s run, 1 kHz output, with a 36-state controller at
2 kHz (per geophone/actuator pair: skyhook damping through a band-pass, three states; Tustin). The loop
steps at 2 kHz. Baseline, in the same run: the loop as the toolkit ran it before the compiled one (a
Python loop over the grid intervals calling a compiled RK4 interval, the controller a Python callback
per tick reading the sensors with ``sensor_signals``, clip and lag in numpy), kept here as a compact
reference. Both give the same run (the difference is printed). Run:
``python benchmarks/bench_closed_loop.py [--repeat N]``
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
import tomllib
from pathlib import Path

import control
import numpy as np

import isolator.simulation.closed_loop as loopmod
from controllers.feedback import from_statespace
from isolator import Simulator, scenario_from_dict
from isolator.numerics.rk4 import BY_TIME
from isolator.scenario.reader import bundled_scenarios
from isolator.simulation.actuation import lag_constants
from isolator.simulation.lag_steps import held_interval
from isolator.simulation.sensors import sensor_signals
from isolator.simulation.stepping import rk4_stepper

sys.path.insert(0, str(Path(__file__).resolve().parent))


def scenario():  # type: ignore[no-untyped-def]
    data = tomllib.loads(Path(bundled_scenarios()["paper-table-3-2-geophones"]).read_text())
    data["simulation"]["duration"] = 7.0
    data["carriages"][0]["profile"]["velocity"] = 0.4
    data["carriages"][1]["profile"]["velocity"] = 0.2
    return scenario_from_dict(data)


def controller(s, rate: float = 2000.0):  # type: ignore[no-untyped-def]
    """36 states: per pair, -c s/(s + 2 pi 0.5) * (2 pi 300)/(s + 2 pi 300) * (2 pi 400)/(s + 2 pi 400)."""
    w0, w1, w2 = 2 * np.pi * 0.5, 2 * np.pi * 300.0, 2 * np.pi * 400.0
    channel = control.ss(control.tf([-2000.0 * w1 * w2, 0.0], np.polymul([1.0, w0], np.polymul([1.0, w1], [1.0, w2]))))
    system = channel
    for _ in range(11):
        system = control.append(system, channel)
    return from_statespace(system, rate, [x.name for x in s.sensors], [a.name for a in s.actuators],
                           [c.name for c in s.carriages])


def python_loop(scenario, model, grid, grid_inputs, p, start, substeps, forces, law, period):  # type: ignore[no-untyped-def]
    """The reference: one Python iteration per grid interval, the controller a callback at the ticks."""
    ctrl = CURRENT["controller"]
    acts = model.layout.actuator_slice
    inputs = grid_inputs.copy()
    times = grid.nodes[:-1, None] + np.diff(grid.nodes)[:, None] * np.linspace(0.0, 1.0, 2 * substeps + 1)
    ticks = grid.regular[:-1] & ((np.cumsum(grid.regular[:-1]) - 1) % period == 0)
    lagged = np.array([a.bandwidth is not None for a in scenario.actuators])
    stepper = rk4_stepper(model, substeps, bool(lagged.any()))
    limits, tau = np.array([a.max_force for a in scenario.actuators]), lag_constants(scenario)
    order = (2 * np.arange(substeps)[:, None] + np.array(BY_TIME)[None, :]).ravel()
    x, xc, u, lag = start.state.copy(), ctrl.reset(), np.zeros(12), np.zeros(12)
    c0 = grid_inputs[0, 0].copy()
    rest = sensor_signals(scenario, model, grid.nodes[:1], x[None], c0[None], p, start.state)[:, 0]
    out = np.empty((grid.nodes.size - 1, x.size))
    for i, h in enumerate(np.diff(grid.nodes)):
        if ticks[i]:
            y = sensor_signals(scenario, model, grid.nodes[i:i + 1], x[None], inputs[i - 1, -1][None] if i else
                               c0[None], p, start.state)[:, 0] - rest
            xc, u = ctrl.step(xc, y)
        command = np.broadcast_to(u, (times.shape[1], 12))
        applied, taken, lag = held_interval(lag, command, order, substeps, h, tau, limits, lagged)
        inputs[i, :, acts] = applied
        stepped = inputs[i][order] if lagged.any() else inputs[i].copy()
        stepped[:, acts] = taken
        x, _ = stepper.step(x, stepped, float(h), p, start.state)
        out[i] = x
    return out, inputs


CURRENT: dict[str, object] = {}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=20)
    args = parser.parse_args()
    s = scenario()
    ctrl = controller(s)
    CURRENT["controller"] = ctrl
    sim = Simulator(s)
    t = time.perf_counter()
    run = sim.run(controller=ctrl)
    first = time.perf_counter() - t
    print(f"first closed-loop run (builds and compiles the loop, or loads it): {1e3 * first:8.1f} ms")
    loop_times: list[float] = []
    cpu_times: list[float] = []  # the thread's CPU time: what the loop costs when the machine is not shared
    compiled = loopmod.run_closed_loop

    def timed_loop(*a, **k):  # type: ignore[no-untyped-def]
        t0, c0 = time.perf_counter(), time.thread_time()
        result = compiled(*a, **k)
        loop_times.append(time.perf_counter() - t0)
        cpu_times.append(time.thread_time() - c0)
        return result

    loopmod.run_closed_loop = timed_loop
    runs = []
    for _ in range(args.repeat):
        t = time.perf_counter()
        sim.run(controller=ctrl)
        runs.append(time.perf_counter() - t)
    loopmod.run_closed_loop = python_loop
    t = time.perf_counter()
    reference = sim.run(controller=ctrl)
    t_ref = time.perf_counter() - t
    loopmod.run_closed_loop = compiled
    intervals = reference.t.size * 2 - 2
    print(f"7 s closed loop, {ctrl.states}-state controller at {ctrl.sample_rate:g} Hz, {intervals} intervals at 2 kHz")
    print(f"compiled loop alone:            median {1e3 * statistics.median(loop_times):7.2f} ms, "
          f"best {1e3 * min(loop_times):7.2f} ms (of {args.repeat})")
    print(f"compiled loop alone, CPU time:  median {1e3 * statistics.median(cpu_times):7.2f} ms, "
          f"best {1e3 * min(cpu_times):7.2f} ms")
    print(f"whole Simulator.run:            median {1e3 * statistics.median(runs):7.2f} ms, "
          f"best {1e3 * min(runs):7.2f} ms")
    print(f"baseline Python-callback loop, whole run: {1e3 * t_ref:9.1f} ms   ratio "
          f"{t_ref / statistics.median(runs):6.1f}x slower (run), {t_ref / statistics.median(loop_times):6.1f}x "
          "(loop alone)")
    diff = np.abs(run.signals - reference.signals).max() / np.abs(reference.signals).max()
    print(f"same run: max |difference| of the six signals / their peak {diff:.1e}; settling "
          f"{run.settling_time_max:.4f} s vs {reference.settling_time_max:.4f} s")


if __name__ == "__main__":
    main()
