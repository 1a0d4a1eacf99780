"""Two source trees of the toolkit side by side in one run (issue 36): one 12 s transient, a batch of 1,000
runs on one thread, and a 20,000-design ``isolator sweep`` end to end, each tree in its own processes with
its own compiled-model cache, alternating, with wall and CPU times and whether the results are the same.

    git worktree add /tmp/old-7d06676 7d06676
    python benchmarks/compare_trees.py /tmp/old-7d06676 .          # --rounds 3 --designs 20000
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
    args = parser.parse_args()
    trees = {"old": args.old.resolve(), "new": args.new.resolve()}
    figures: dict[str, list[dict[str, float]]] = {"old": [], "new": []}
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        caches = {tag: Path(os.environ.get(f"CACHE_{tag.upper()}", work / f"cache-{tag}")) for tag in trees}
        for tag, tree in trees.items():  # warm the compiled-model caches (not timed), in one process: before
            # 3bc8a92, two processes building one library could leave it without its symbol
            _sweep(tree, caches[tag], 200, work / f"warm-{tag}.csv", ("--workers", "1"))
        for r in range(args.rounds):
            for tag in (("old", "new") if r % 2 == 0 else ("new", "old")):
                tree = trees[tag]
                out = str(work / f"{tag}.npz")
                subprocess.run([sys.executable, __file__, "--child", out], env=_env(tree, caches[tag]), check=True)
                row = json.loads(Path(out + ".json").read_text())
                row["sweep_s"], row["sweep_cpu_s"] = _sweep(tree, caches[tag], args.designs, work / f"{tag}.csv")
                figures[tag].append(row)
                print(f"round {r + 1} {tag}: " + ", ".join(f"{k} {v:.4g}" for k, v in row.items()), flush=True)
        same_batch = all(  # 7d06676 judged settling before issue 26: its batch differs by design
np.array_equal(np.load(work / "old.npz")[k], np.load(work / "new.npz")[k], equal_nan=True)
                         for k in ("settling", "peak"))
        old_rows, new_rows = _columns(work / "old.csv"), _columns(work / "new.csv")
        same_sweep = {k: bool(np.array_equal(v, new_rows.get(k))) for k, v in old_rows.items()}
    names = {"run_ms": "one 12 s transient, median of 20 [ms]", "run_cpu_ms": "  its CPU time [ms]",
             "batch": "batch of 1,000, one thread [runs/s]", "batch_cpu": "  per CPU second [runs/s]",
             "sweep_s": f"isolator sweep of {args.designs} designs, end to end [s]",
             "sweep_cpu_s": "  its CPU time, all processes [s]"}
    print(f"\n| figure | old {args.old} | new {args.new} | new / old (medians) |\n|---|---|---|---|")
    for key, label in names.items():
        o, n = ([row[key] for row in figures[tag]] for tag in ("old", "new"))
        ratio = statistics.median(n) / statistics.median(o)
        print(f"| {label} | {statistics.median(o):.4g} ({min(o):.4g}-{max(o):.4g}) | "
              f"{statistics.median(n):.4g} ({min(n):.4g}-{max(n):.4g}) | {ratio:.3f} |")
    print(f"\nbatch settling times and peaks identical: {same_batch}")
    differ = [k for k, same in same_sweep.items() if not same]
    print(f"sweep columns identical: {not differ}" + (f" (differ: {', '.join(differ)})" if differ else ""))
    print(f"load average at the end: {os.getloadavg()}")


if __name__ == "__main__":
    if len(sys.argv) > 2 and sys.argv[1] == "--child":
        child(sys.argv[2])
    else:
        main()
