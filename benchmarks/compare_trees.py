"""Two source trees of the toolkit side by side in one run (issue 36): one 12 s transient (the same table again, and a
new table each run), a batch of 1,000 runs on one thread, and a 20,000-design ``isolator sweep`` end to end; and
(issue 43) ``isolator simulate --forces`` and ``--controller`` on the geophone table end to end, and the plant
FMUs' ``doStep`` loop in FMPy (the geophone and the passive table, 7 s at 1 ms); each tree in its own processes
with its own compiled-model cache, alternating, with wall and CPU times and whether the results are the same.

    git worktree add /tmp/old-7d06676 7d06676
    python benchmarks/compare_trees.py /tmp/old-7d06676 .          # --rounds 3 --designs 20000
    python benchmarks/compare_trees.py /tmp/old . --figures forces,controller,fmu
    git worktree remove /tmp/old-7d06676

The machine this project runs on is shared: each figure is given per round (the range) and as the median of
the rounds, wall time and the process's CPU time.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

SCALES = ("--scale", "isolators[*].stiffness=0.5:2", "--scale", "isolators[*].damping=0.5:4")


FIGURES = ("transient", "batch", "sweep", "forces", "controller", "fmu")


def fmu_child(out: str) -> None:
    """In a tree's own process: its plant FMUs of the passive and the geophone table, their ``doStep`` loops
    (7 s at 1 ms, alternating, three each) in ms per simulated second, and the geophone table's Model Exchange
    under CVode."""
    sys.path.insert(0, str(Path(__file__).parent))
    from bench_fmu import TABLES, build, do_steps, model_exchange

    with tempfile.TemporaryDirectory() as tmp:
        paths = {name: build(name, Path(tmp)) for name in TABLES}
        times: dict[str, list[float]] = {name: [] for name in TABLES}
        for r in range(3):
            for name in TABLES:
                times[name].append(do_steps(paths[name], 7.0, Path(tmp) / f"unzip-{name}-{r}", False) / 7.0)
        me = model_exchange(paths[TABLES[1]], 7.0) / 7.0
    Path(out + ".json").write_text(json.dumps({
        "fmu_passive_ms": 1e3 * statistics.median(times[TABLES[0]]),
        "fmu_geophones_ms": 1e3 * statistics.median(times[TABLES[1]]), "fmu_me_geophones_ms": 1e3 * me}))


def child(out: str) -> None:
    """In a tree's own process: the transient and the batch, their times and results."""
    from isolator import Simulator, load_scenario

    sim = Simulator(load_scenario("paper-table-3-2"))
    for _ in range(5):
        sim.run()
    wall, cpu = [], []
    for _ in range(20):
        t0, c0 = time.perf_counter(), time.process_time()
        sim.run()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    # a new table each run (issue 43): forty stiffness scalings, each run once, so that nothing a simulator keeps
    # of a parameter vector's rests is reused
    tables = [sim.scaled_parameters(s, 1.0) for s in np.linspace(0.8, 1.2, 40)]
    fresh, fresh_cpu = [], []
    for table in tables:
        t0, c0 = time.perf_counter(), time.process_time()
        sim.run(p=table)
        fresh.append(time.perf_counter() - t0)
        fresh_cpu.append(time.process_time() - c0)
    rng = np.random.default_rng(1)
    k, c = rng.uniform(0.5, 2.0, 1000), rng.uniform(0.5, 4.0, 1000)
    sim.run_batch(k[:100], c[:100], workers=1)  # compiles the four-lane loop and the plans
    rates, cpu_rates, batch = [], [], None
    for _ in range(3):
        t0, c0 = time.perf_counter(), time.process_time()
        batch = sim.run_batch(k, c, workers=1)
        rates.append(1000 / (time.perf_counter() - t0))
        cpu_rates.append(1000 / (time.process_time() - c0))
    assert batch is not None
    np.savez(out, settling=batch.settling_time, peak=batch.peak)
    Path(out + ".json").write_text(json.dumps({
        "run_ms": 1e3 * statistics.median(wall), "run_cpu_ms": 1e3 * statistics.median(cpu),
        "fresh_ms": 1e3 * statistics.median(fresh), "fresh_cpu_ms": 1e3 * statistics.median(fresh_cpu),
        "batch": statistics.median(rates), "batch_cpu": statistics.median(cpu_rates),
    }))


def _env(tree: Path, cache: Path) -> dict[str, str]:
    return dict(os.environ, PYTHONPATH=str(tree), ISOLATOR_CACHE=str(cache), MPLBACKEND="Agg")


def _sweep(tree: Path, cache: Path, designs: int, out: Path, workers: tuple[str, ...] = ()) -> tuple[float, float]:
    """Wall and CPU time [s] (this process's children: the command and its workers) of the sweep command."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "isolator.cli", "sweep", "paper-table-3-2", *SCALES, "--samples",
                    str(designs), "--out", str(out), "--force", *workers], env=_env(tree, cache), check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=tree)  # -m puts the folder first
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)


def _simulate(tree: Path, cache: Path, extra: list[str], work: Path) -> tuple[float, dict[str, float]]:
    """Wall time [s] of ``isolator simulate paper-table-3-2-geophones --json`` with ``extra`` (median of three
    fresh processes) and the peaks it printed."""
    walls, text = [], ""
    for _ in range(3):
        t0 = time.perf_counter()
        text = subprocess.run([sys.executable, "-m", "isolator.cli", "simulate", "paper-table-3-2-geophones", "--json",
                               *extra], env=_env(tree, cache), check=True, capture_output=True, text=True,
                              cwd=work).stdout
        walls.append(time.perf_counter() - t0)
    return statistics.median(walls), json.loads(text)["peak"]


def _columns(path: Path) -> dict[str, np.ndarray]:
    import csv

    with path.open() as handle:
        rows = list(csv.reader(handle))
    return {name: np.array(values) for name, *values in zip(*rows, strict=True)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("old", type=Path)
    parser.add_argument("new", type=Path)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--designs", type=int, default=20000)
    parser.add_argument("--figures", default=",".join(FIGURES), help=f"which, comma-separated: {', '.join(FIGURES)}")
    parser.add_argument("--controller", type=Path, help="a controller folder for --controller (default: a skyhook "
                                                        "at 2 kHz designed by the new tree)")
    args = parser.parse_args()
    chosen = set(args.figures.split(","))
    if chosen - set(FIGURES):
        parser.error(f"--figures: unknown {', '.join(sorted(chosen - set(FIGURES)))}")
    trees = {"old": args.old.resolve(), "new": args.new.resolve()}
    figures: dict[str, list[dict[str, float]]] = {"old": [], "new": []}
    peaks: dict[str, dict[str, dict[str, float]]] = {"old": {}, "new": {}}
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        caches = {tag: Path(os.environ.get(f"CACHE_{tag.upper()}", work / f"cache-{tag}")) for tag in trees}
        forces = controller = None
        if "forces" in chosen or "controller" in chosen:
            sys.path.insert(0, str(Path(__file__).parent))
            from bench_forces import write_forces

            forces = write_forces(work / "forces.csv")
            controller = args.controller.resolve() if args.controller else work / "controller"
            if args.controller is None and "controller" in chosen:
                subprocess.run([sys.executable, "-m", "isolator.cli", "controller", "paper-table-3-2-geophones",
                                "--method", "skyhook", "--sample-rate", "2000", "--out", str(controller)],
                               env=_env(trees["new"], caches["new"]), check=True, stdout=subprocess.DEVNULL, cwd=work)
        for tag, tree in trees.items():  # warm the compiled-model caches (not timed), in one process: before
            # 3bc8a92, two processes building one library could leave it without its symbol
            if "sweep" in chosen:
                _sweep(tree, caches[tag], 200, work / f"warm-{tag}.csv", ("--workers", "1"))
            for extra, figure in ((["--forces", str(forces)], "forces"), (["--controller", str(controller)],
                                                                           "controller")):
                if figure in chosen:
                    subprocess.run([sys.executable, "-m", "isolator.cli", "simulate", "paper-table-3-2-geophones",
                                    "--json", *extra], env=_env(tree, caches[tag]), check=True,
                                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=work)
        for r in range(args.rounds):
            for tag in (("old", "new") if r % 2 == 0 else ("new", "old")):
                tree = trees[tag]
                out = str(work / f"{tag}.npz")
                row: dict[str, float] = {}
                if {"transient", "batch"} & chosen:
                    subprocess.run([sys.executable, __file__, "--child", out], env=_env(tree, caches[tag]), check=True)
                    row |= json.loads(Path(out + ".json").read_text())
                if "sweep" in chosen:
                    row["sweep_s"], row["sweep_cpu_s"] = _sweep(tree, caches[tag], args.designs, work / f"{tag}.csv")
                if "forces" in chosen:
                    row["forces_s"], peaks[tag]["forces"] = _simulate(tree, caches[tag], ["--forces", str(forces)],
                                                                      work)
                if "controller" in chosen:
                    row["controller_s"], peaks[tag]["controller"] = _simulate(
                        tree, caches[tag], ["--controller", str(controller)], work)
                if "fmu" in chosen:
                    subprocess.run([sys.executable, __file__, "--fmu-child", out], env=_env(tree, caches[tag]),
                                   check=True, stderr=subprocess.DEVNULL)
                    row |= json.loads(Path(out + ".json").read_text())
                figures[tag].append(row)
                print(f"round {r + 1} {tag}: " + ", ".join(f"{k} {v:.4g}" for k, v in row.items()), flush=True)
        same_batch = None if "batch" not in chosen else all(  # 7d06676 judged settling before issue 26
            np.array_equal(np.load(work / "old.npz")[k], np.load(work / "new.npz")[k], equal_nan=True)
            for k in ("settling", "peak"))
        differ = None
        if "sweep" in chosen:
            old_rows, new_rows = _columns(work / "old.csv"), _columns(work / "new.csv")
            differ = [k for k, v in old_rows.items() if not np.array_equal(v, new_rows.get(k))]
    names = {"run_ms": "one 12 s transient, median of 20 [ms]", "run_cpu_ms": "  its CPU time [ms]",
             "fresh_ms": "one 12 s transient of a new table each run, median of 40 [ms]",
             "fresh_cpu_ms": "  its CPU time [ms]",
             "batch": "batch of 1,000, one thread [runs/s]", "batch_cpu": "  per CPU second [runs/s]",
             "sweep_s": f"isolator sweep of {args.designs} designs, end to end [s]",
             "sweep_cpu_s": "  its CPU time, all processes [s]",
             "forces_s": "simulate --forces, geophone table, end to end [s]",
             "controller_s": "simulate --controller (skyhook, 2 kHz), geophone table, end to end [s]",
             "fmu_passive_ms": "passive table's FMU, doStep at 1 ms [ms per simulated s]",
             "fmu_geophones_ms": "geophone table's FMU, doStep at 1 ms [ms per simulated s]",
             "fmu_me_geophones_ms": "geophone table's FMU, Model Exchange (CVode) [ms per simulated s]"}
    print(f"\n| figure | old {args.old} | new {args.new} | new / old (medians) |\n|---|---|---|---|")
    for key, label in names.items():
        if key not in figures["old"][0]:
            continue
        o, n = ([row[key] for row in figures[tag]] for tag in ("old", "new"))
        ratio = statistics.median(n) / statistics.median(o)
        print(f"| {label} | {statistics.median(o):.4g} ({min(o):.4g}-{max(o):.4g}) | "
              f"{statistics.median(n):.4g} ({min(n):.4g}-{max(n):.4g}) | {ratio:.3f} |")
    if "fmu_geophones_ms" in figures["new"][0]:
        for tag in ("old", "new"):
            ratios = [row["fmu_geophones_ms"] / row["fmu_passive_ms"] for row in figures[tag]]
            print(f"\n{tag}: the geophone table's FMU / the passive table's, per round: "
                  + ", ".join(f"{x:.2f}" for x in ratios))
    if same_batch is not None:
        print(f"\nbatch settling times and peaks identical: {same_batch}")
    if differ is not None:
        print(f"sweep columns identical: {not differ}" + (f" (differ: {', '.join(differ)})" if differ else ""))
    for figure, old_peaks in peaks["old"].items():
        new_peaks = peaks["new"][figure]
        worst = max(abs(new_peaks[k] - v) / abs(v) for k, v in old_peaks.items() if v)
        print(f"{figure}: the signals' peaks differ by at most {worst:.2g} of their value")
    print(f"load average at the end: {os.getloadavg()}")


if __name__ == "__main__":
    if len(sys.argv) > 2 and sys.argv[1] == "--child":
        child(sys.argv[2])
    elif len(sys.argv) > 2 and sys.argv[1] == "--fmu-child":
        fmu_child(sys.argv[2])
    else:
        main()
