"""Speed of the transient simulation on the paper's Table 3.2 case (12 s, 1 kHz).

Prints each figure and its ratio to baselines measured in the same run:
a plain numpy + scipy.solve_ivp implementation of the same equations, the
MuJoCo multibody check, and this toolkit's own RK4 stepping on the sample
grid (the method used before DOP853, still used for runs with actuator
forces or feedback). Run:  python benchmarks/bench_simulate.py

The compiled DOP853 loop of that run alone (issue 43 item 1), as a run calls it, with its probes only and
with no slot at all (the stepping alone): min and median of ``--loop-calls`` calls each, alternated:
python benchmarks/bench_simulate.py --loop
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from numpy_reference import NumpyTable
from timing import timed

import isolator.model.cache as modelcache
import isolator.model.equilibrium as eqmod
import isolator.simulation.batch as batchmod
import isolator.simulation.simulator as simmod
import isolator.simulation.stepping as stepping
from isolator import Simulator, load_scenario
from isolator.model.signals import table_signals
from isolator.numerics.step_plan import StepPlan
from isolator.validation.multibody import MujocoTable, mujoco_available
from studies.paper import relative_rms


def _clear_caches() -> None:
    for cache in (modelcache._MODELS, eqmod._SOLVERS):
        cache.clear()
    stepping.clear_caches()


def _reference(sc, stiffness: float = 1.0, damping: float = 1.0, rtol: float = 1e-12) -> np.ndarray:
    """The numpy + DOP853 solution with all isolators scaled, as table signals (6, samples)."""
    ref = NumpyTable(sc)
    ref.k = ref.k * stiffness  # uniform scaling leaves the preload shares unchanged
    ref.c = ref.c * damping
    _, states, y0 = ref.simulate(rtol=rtol, atol=1e-15)
    return table_signals(states, y0)


def _rate(
    sim: Simulator, k: np.ndarray, c: np.ndarray, workers: int, repeat: int
) -> tuple[float, float, object]:
    """Median and best runs per second of a batch over ``repeat`` tries, and the last result."""
    rates, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = sim.run_batch(k, c, workers=workers)
        rates.append(len(k) / (time.perf_counter() - t0))
    return float(np.median(rates)), max(rates), out


def loop_figures(sim: Simulator, calls: int) -> tuple[StepPlan, dict[str, tuple[float, float]]]:
    """The plan of ``sim``'s run, and the min and median [s] of its compiled loop over ``calls`` calls each: the
    full plan (its probes and output samples, written as a run writes them), its probes only, and no slots (the
    stepping)."""
    p = sim.parameters
    start, end = sim.equilibria(p)
    method = sim.method_of(start, end)
    plan, inputs, stepper = method.plan, sim.plan_inputs(method, p), stepping.dense_stepper(sim.model)
    final = stepper.signal_values(end.state, start.state)
    unused = np.full_like(plan.fraction, -1.0)
    plans = {"full plan": plan, "probes only": plan.probes_only(),
             "no slots": dataclasses.replace(plan, fraction=unused, sample_slots=plan.sample_slots[:0], probes=0)}
    times: dict[str, list[float]] = {name: [] for name in plans}
    for _ in range(calls):
        for name, each in plans.items():
            samples = np.zeros((6, each.sample_slots.size + 1))
            t0 = time.perf_counter()
            stepper.run_slots(start.state, each, inputs, p, start.state, with_states=True, final=final,
                              samples=samples)
            times[name].append(time.perf_counter() - t0)
    return plan, {name: (min(t), float(np.median(t))) for name, t in times.items()}


def print_loop_figures(sim: Simulator, calls: int) -> None:
    """Print :func:`loop_figures` with the plan's sizes."""
    plan, figures = loop_figures(sim, calls)
    print(f"compiled loop alone ({plan.steps} steps, {plan.per_step} slots per step, {plan.probes} probes, "
          f"{plan.sample_slots.size} samples; min / median of {calls} calls):")
    for name, (best, median) in figures.items():
        print(f"  {name:12s} {best * 1e3:6.3f} ms / {median * 1e3:6.3f} ms")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--batch", type=int, default=1000, help="runs in the batch figure")
    parser.add_argument("--repeat", type=int, default=30, help="repeats of the single-run timing")
    parser.add_argument("--batch-repeat", type=int, default=3, help="repeats of the batch timing")
    parser.add_argument("--loop", action="store_true", help="only the compiled loop's figures")
    parser.add_argument("--loop-calls", type=int, default=300, help="calls of each loop figure")
    args = parser.parse_args()
    sc = load_scenario("paper-table-3-2")
    if args.loop:
        sim = Simulator(sc)
        sim.run()
        print_loop_figures(sim, args.loop_calls)
        times = []
        for _ in range(args.loop_calls):
            t0 = time.perf_counter()
            sim.run()
            times.append(time.perf_counter() - t0)
        print(f"  whole run    {min(times) * 1e3:6.3f} ms / {float(np.median(times)) * 1e3:6.3f} ms")
        return

    with tempfile.TemporaryDirectory() as cache:
        os.environ["ISOLATOR_CACHE"] = cache
        _clear_caches()
        t0 = time.perf_counter()
        sim = Simulator(sc)
        sim.run()
        cold = time.perf_counter() - t0
    os.environ.pop("ISOLATOR_CACHE")
    _clear_caches()
    t0 = time.perf_counter()
    sim = Simulator(sc)
    sim.run()
    warm = time.perf_counter() - t0
    print(f"model build + first run, cold (casadi codegen + C/C++ compile): {cold * 1e3:8.1f} ms")
    print(f"model build + first run, warm compiled-model cache:          {warm * 1e3:8.1f} ms")

    start, end = sim.equilibria(sim.parameters)
    method = sim.method_for(max(start.max_frequency, end.max_frequency))
    plan = method.plan
    print(f"method: DOP853, {plan.steps} steps (longest {plan.length.max() * 1e3:.1f} ms), "
          f"{plan.evaluations} right-hand sides, {plan.per_step} sample slots per step "
          f"(RK4 on the sample grid: {4 * method.substeps * (sim.grid.nodes.size - 1)} right-hand sides)")

    times = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        response = sim.run()
        times.append(time.perf_counter() - t0)
    t_sim = float(np.median(times))
    print(f"simulation, exact model, 12 s at 1 kHz: median {t_sim * 1e3:6.2f} ms, best {min(times) * 1e3:6.2f} ms "
          f"(of {args.repeat})")
    print_loop_figures(sim, 10 * args.repeat)

    rk4 = simmod.Method(method.substeps)
    p = sim.parameters
    t_rk4, _ = timed(lambda: sim.run_method(p, *sim.equilibria(p), rk4), max(3, args.repeat // 3))
    print(f"baseline RK4 on the sample grid, same model, compiled:       {t_rk4 * 1e3:8.2f} ms   "
          f"ratio {t_rk4 / t_sim:6.1f}x slower")

    ref = _reference(sc)
    err = relative_rms(response.signals, ref)
    print(f"accuracy vs tight-tolerance reference (DOP853 rtol 1e-12): max rel. RMS {err.max():.2e} "
          f"(per signal {', '.join(f'{e:.1e}' for e in err)})")

    ref_model = NumpyTable(sc)
    t_np, (_t, states, y0) = timed(lambda: ref_model.simulate(rtol=1e-8, atol=1e-12), 1)
    sig = table_signals(states, y0)
    print(f"baseline numpy + solve_ivp DOP853 rtol 1e-8 (max rel. RMS {relative_rms(sig, ref).max():.1e}): "
          f"{t_np * 1e3:8.1f} ms   ratio {t_np / t_sim:6.1f}x slower")
    if mujoco_available():
        t_mj, _ = timed(lambda: MujocoTable(sc).simulate(rtol=1e-8, atol=1e-12), 1)
        print(f"baseline MuJoCo check, DOP853 rtol 1e-8:                   {t_mj * 1e3:8.1f} ms   "
              f"ratio {t_mj / t_sim:6.1f}x slower")

    rng = np.random.default_rng(1)
    k = rng.uniform(0.5, 2.0, args.batch)
    c = rng.uniform(0.5, 4.0, args.batch)
    sim.run_batch(k, c)  # warm-up: compiles the steppers and step plans the batch needs
    median2, best2, batch = _rate(sim, k, c, 2, args.batch_repeat)
    median1, _, _ = _rate(sim, k, c, 1, 1)
    ok = np.isfinite(batch.settling_time_max).sum()
    print(f"batch, {args.batch} runs, stiffness x0.5-2, damping x0.5-4, 2 threads: median {median2:6.0f} runs/s, "
          f"best {best2:6.0f} runs/s of {args.batch_repeat}  (1 thread {median1:5.0f} runs/s; "
          f"{ok} runs with a settling time)")
    lanes = batchmod.LANES
    batchmod.LANES = 1
    try:
        sim.run_batch(k[:50], c[:50])  # compiles the one-lane loop
        median_one, _, _ = _rate(sim, k, c, 2, 1)
    finally:
        batchmod.LANES = lanes
    print(f"baseline batch with one run per compiled call (no SIMD lanes), 2 threads: {median_one:6.0f} runs/s   "
          f"ratio {median2 / median_one:6.1f}x fewer")
    n_rk4 = max(20, args.batch // 10)
    original = simmod.Simulator.method_for
    simmod.Simulator.method_for = lambda self, omega, actuated=False: simmod.Method(
        self.substeps_for(omega))
    try:
        t0 = time.perf_counter()
        sim.run_batch(k[:n_rk4], c[:n_rk4], workers=2)
        rate_rk4 = n_rk4 / (time.perf_counter() - t0)
    finally:
        simmod.Simulator.method_for = original
    print(f"baseline batch with RK4 on the sample grid, 2 threads ({n_rk4} runs): {rate_rk4:6.0f} runs/s   "
          f"ratio {median2 / rate_rk4:6.1f}x fewer")
    worst = []
    for ks, cs in ((2.0, 0.5), (0.5, 4.0), (2.0, 4.0)):
        run = sim.run(p=sim.scaled_parameters(ks, cs))
        worst.append((ks, cs, relative_rms(run.signals, _reference(sc, ks, cs)).max()))
    print("batch corners vs tight-tolerance reference: "
          + ", ".join(f"k x{ks:g} c x{cs:g}: {e:.1e}" for ks, cs, e in worst))


if __name__ == "__main__":
    main()
