"""The plant FMUs in FMPy (issue 43 item 3): the passive table's (``paper-table-3-2``) and the geophone table's
(``paper-table-3-2-geophones``: twelve actuators with a 200 Hz lag, twelve geophones) Co-Simulation ``doStep``
loop, 7 s at 1 ms communication steps, a sine command on two actuators set before every step; and their Model
Exchange interface under FMPy's CVode (rtol 1e-6, output every 1 ms). Time per simulated second, alternating the
two tables in one process.

    python benchmarks/bench_fmu.py            # --rounds 5 --seconds 7
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

STEP = 1e-3
TABLES = ("paper-table-3-2", "paper-table-3-2-geophones")


def build(name: str, folder: Path) -> Path:
    """The scenario's FMU, written into ``folder``."""
    from isolator import load_scenario
    from isolator.fmu import write_fmu

    return write_fmu(load_scenario(name), folder / f"{name.replace('-', '_')}.fmu")


def do_steps(path: Path, seconds: float, unzip: Path, inputs: bool = True) -> float:
    """Wall time [s] of ``seconds`` of 1 ms ``doStep`` calls (initialisation not counted); with ``inputs``, two
    inputs set before every step: with actuators, a 7 Hz and a 3 Hz sine command (the second clipped at 500 N),
    without, the floor's x and y at rest (the same host calls)."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(path))
    folder = extract(str(path), unzipdir=str(unzip))
    refs = {v.name: v.valueReference for v in md.modelVariables}
    forced = [refs[n] for n in ("f:z1", "f:x2") if n in refs and inputs]
    still = [refs[n] for n in ("floor:x", "floor:y") if inputs and not forced]
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=folder, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="bench")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    steps = round(seconds / STEP)
    t0 = time.perf_counter()
    for k in range(steps):
        t = k * STEP
        if forced:
            fmu.setReal(forced, [300.0 * np.sin(2 * np.pi * 7.0 * t), 700.0 * np.sin(2 * np.pi * 3.0 * t)])
        elif still:
            fmu.setReal(still, [0.0 * np.sin(t), 0.0 * np.sin(t)])
        fmu.doStep(currentCommunicationPoint=t, communicationStepSize=STEP)
    wall = time.perf_counter() - t0
    fmu.terminate()
    fmu.freeInstance()
    return wall


def model_exchange(path: Path, seconds: float) -> float:
    """Wall time [s] of FMPy's CVode over the Model Exchange interface, ``seconds`` simulated."""
    from fmpy import simulate_fmu

    t0 = time.perf_counter()
    simulate_fmu(str(path), fmi_type="ModelExchange", stop_time=seconds, output_interval=STEP,
                 relative_tolerance=1e-6)
    return time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--seconds", type=float, default=7.0)
    parser.add_argument("--no-me", action="store_true", help="the Co-Simulation loop only")
    parser.add_argument("--no-inputs", action="store_true", help="no command set before the steps (zero forces)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        paths = {name: build(name, folder) for name in TABLES}
        cs: dict[str, list[float]] = {name: [] for name in TABLES}
        me: dict[str, list[float]] = {name: [] for name in TABLES}
        for r in range(args.rounds):
            for name in TABLES if r % 2 == 0 else TABLES[::-1]:
                cs[name].append(do_steps(paths[name], args.seconds, folder / f"unzip-{name}-{r}",
                                            not args.no_inputs) / args.seconds)
                if not args.no_me:
                    me[name].append(model_exchange(paths[name], args.seconds) / args.seconds)
    passive, active = TABLES
    print("| table | Co-Simulation doStep, 1 ms [ms per simulated s] | Model Exchange, CVode [ms per simulated s] |")
    print("|---|---|---|")
    for name in TABLES:
        m = f"{1e3 * statistics.median(me[name]):.2f}" if me[name] else "-"
        print(f"| {name} | {1e3 * statistics.median(cs[name]):.2f} ({1e3 * min(cs[name]):.2f}-"
              f"{1e3 * max(cs[name]):.2f}) | {m} |")
    print(f"\ngeophones / passive, Co-Simulation (medians of per-round ratios): "
          f"{statistics.median(a / p for a, p in zip(cs[active], cs[passive], strict=True)):.2f}")
    if me[passive]:
        print(f"geophones / passive, Model Exchange: "
              f"{statistics.median(a / p for a, p in zip(me[active], me[passive], strict=True)):.2f}")


if __name__ == "__main__":
    main()
