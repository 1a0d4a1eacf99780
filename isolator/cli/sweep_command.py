"""``isolator sweep``: many designs of one scenario, locally or through a Dask scheduler, streamed to a
file (:func:`isolator.sweep.sweep`)."""

from __future__ import annotations

import argparse
import math
import re
import shlex
import sys
from concurrent.futures import Executor
from pathlib import Path
from typing import Any

import numpy as np

from isolator.cli.helpers import (
    count,
    figure_path,
    output_path,
    save_figure,
    scenario_argument,
    scheduler_arguments,
    scheduler_client,
    seed,
    use_agg,
    written,
)
from isolator.errors import ExecutorError, ParameterError
from isolator.model.variants import MODEL_KINDS
from isolator.scenario.names import escaped
from isolator.sweep import METHODS, sweep
from isolator.sweep.designs import check_design_count
from isolator.sweep.output import SUFFIXES, read_columns, staging_path
from isolator.sweep.sweep import check_workers

__all__ = ["parse_values", "register"]


class _Swept(argparse.Action):
    """``--set`` and ``--scale`` into one list of (mode, text), in command-line order."""

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: Any,
                 option: str | None = None) -> None:
        swept = list(getattr(namespace, "swept", None) or [])
        namespace.swept = [*swept, (str(option).removeprefix("--"), str(values))]


def register(sub: Any) -> None:
    """Add ``isolator sweep`` to the ``isolator`` command's subparsers."""
    p = sub.add_parser(
        "sweep", help="run many designs (a grid, zipped lists or samples of any parameters); rows to a file",
        description="Run a scenario for many designs of any named parameters (--list prints a scenario's; [*] for "
        "every element, a vector's name for all its components) and write one row per design: the swept "
        "values, settling_time_max, settling:<signal>, peak:<signal>, status (ok, tipped, diverged, refused, "
        "invalid, unsettled: no settling time within the run, or a step of the [sequence] did not settle, failed: its "
        "chunk failed twice), reason, "
        "design, band:<signal> (the half-widths of the settling band), then the columns of the scenario's kind "
        "(pneumatic: dynamic_settling_time_max, leveling_time, supply_exhausted; [[windows]]: "
        "window_settling_time_max, moves_per_hour; a [sequence], instead of these: total_time, "
        "throughput_per_hour, unsettled_step), then transmissibility:<axis>@<f>Hz, mode:<k> and "
        "budget:<point>:<axis> (the passive error budget's RMS [m]). The sweep is described beside the file "
        "in <out>.sweep.json (scenario, model, band, sampling, extras): --resume refuses a file another sweep "
        "wrote.",
    )
    scenario_argument(p)
    p.add_argument("--set", action=_Swept, dest="swept", metavar="NAME=VALUES",
                   help="absolute values: START:STOP:COUNT (inclusive, like numpy.linspace), START:STOP:COUNT:log "
                   "(geometric), v1,v2,... or, with --samples, START:STOP; repeat for more names")
    p.add_argument("--scale", action=_Swept, dest="swept", metavar="NAME=VALUES",
                   help="factors on the scenario's values, written as for --set")
    p.add_argument("--zip", action="store_true", help="pair the lists (one length) instead of crossing them")
    p.add_argument("--samples", type=count, metavar="N", help="draw N designs over the ranges instead of a grid")
    p.add_argument("--method", choices=METHODS, default="sobol", help="sampling method (default: sobol)")
    p.add_argument("--seed", type=seed, default=0, help="seed of the sampling (default: 0)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=count, metavar="N", help="local worker processes (default: the cores)")
    scheduler_arguments(p, where)
    p.add_argument("--frequency", type=float, action="append", default=[], metavar="HZ",
                   help="add the x, y, z transmissibility at this frequency per design; repeat for more")
    p.add_argument("--modes", action="store_true", help="add the mode frequencies per design")
    p.add_argument("--budget", action="append", default=[], metavar="POINT:AXIS,...",
                   help="add the passive error budget's displacement RMS [m] at these [[points]] (table: the mass "
                   "centre of a scenario without points) and axes (x, y, z) per design, columns "
                   "budget:<point>:<axis> (isolator budget's value, default band); repeat or separate by commas")
    p.add_argument("--model", choices=MODEL_KINDS, default="exact", help="exact or the paper's small-angle model")
    p.add_argument("--chunk-size", type=count, metavar="N", help="designs per task (default: about four per worker)")
    p.add_argument("--out", type=Path, metavar="FILE.csv", help="the rows (.csv or .parquet); required unless --list")
    p.add_argument("--list", action="store_true",
                   help="print the names of the scenario's parameters that --set and --scale take, and exit")
    p.add_argument("--plot", type=Path, metavar="FILE.png",
                   help="write a figure: the largest settling time (a sequence: its total time) against the "
                   "swept values")
    again = p.add_mutually_exclusive_group()
    again.add_argument("--resume", action="store_true", help="continue the sweep whose rows --out holds")
    again.add_argument("--force", action="store_true", help="overwrite --out (and its .sweep.json)")
    p.set_defaults(handler=_sweep, swept=None)


def parse_values(text: str, option: str, sampled: bool) -> list[float]:
    """``NAME=...``'s values: ``START:STOP:COUNT[:log]``, ``v1,v2,...``, or with ``sampled`` ``START:STOP``.

    Raises
    ------
    ParameterError
        Naming ``option``: a non-number, COUNT < 1, a geometric range through zero, a range where a
        sampled one is needed.
    """
    def number(word: str, what: str) -> float:
        try:
            value = float(word)
        except ValueError:
            raise ParameterError(f"{option}: {what} must be a number, got '{word}'") from None
        if not math.isfinite(value):
            raise ParameterError(f"{option}: {what} must be finite, got '{word}'")
        return value

    if ":" not in text:
        if sampled:
            raise ParameterError(f"{option}: with --samples give a range START:STOP, got '{text}'")
        return [number(w.strip(), "each value") for w in text.split(",")]
    parts = text.split(":")
    if sampled:
        if len(parts) != 2:
            raise ParameterError(f"{option}: with --samples give a range START:STOP, got '{text}'")
        return [number(parts[0], "START"), number(parts[1], "STOP")]
    if len(parts) not in (3, 4) or (len(parts) == 4 and parts[3] != "log"):
        raise ParameterError(f"{option}: expected START:STOP:COUNT or START:STOP:COUNT:log, got '{text}'")
    start, stop = number(parts[0], "START"), number(parts[1], "STOP")
    try:
        n = count(parts[2])
    except argparse.ArgumentTypeError:
        n = 0
    if n < 1:
        raise ParameterError(f"{option}: COUNT must be a whole number >= 1, got '{parts[2]}'")
    check_design_count(n, 1, option)
    if len(parts) == 4:
        if start <= 0 or stop <= 0:
            raise ParameterError(f"{option}: a geometric range (:log) needs START and STOP > 0, got '{text}'")
        return [float(v) for v in np.geomspace(start, stop, n)]
    return [float(v) for v in np.linspace(start, stop, n)]


def _swept(args: argparse.Namespace) -> dict[str, dict[str, list[float]]]:
    out: dict[str, dict[str, list[float]]] = {"set": {}, "scale": {}}
    if not args.swept:
        raise ParameterError("--set, --scale: give at least one NAME=VALUES to sweep")
    for mode, text in args.swept:
        name, equals, values = text.partition("=")
        option = f"--{mode} {text}"
        if not equals or not name.strip():
            raise ParameterError(f"{option}: expected NAME=VALUES, e.g. 'isolators[*].stiffness.z=2e5:8e5:4'")
        if name.strip() in out["set"] or name.strip() in out["scale"]:
            raise ParameterError(f"{option}: '{name.strip()}' is swept twice")
        out[mode][name.strip()] = parse_values(values.strip(), option, args.samples is not None)
    return out


#: how :func:`isolator.sweep.sweep`'s messages name its arguments, and the options this command names them by
_WORDS = {"out: ": "--out: ", "samples: ": "--samples: ", "force=True": "--force", "resume=True": "--resume",
          "the same sweep": "the same command"}
#: a swept column as the API names it (``set['table.mass']``), as this command's option (``--set table.mass``)
_COLUMN = re.compile(r"\b(set|scale)\[(['\"])(.*?)\2\]")


def _options_named(message: str) -> str:
    """A message of :func:`isolator.sweep.sweep` in this command's words (``--force``, not ``force=True``)."""
    for api, cli in _WORDS.items():
        message = message.replace(api, cli)
    return _COLUMN.sub(lambda m: f"--{m.group(1)} {m.group(3)}", message)


def _rows_kept(out: Path) -> int:
    """The rows an interrupted sweep left in ``out`` (0 when there are none yet)."""
    try:
        return len(read_columns(out, ["design"]).get("design", ()))
    except (OSError, ValueError, StopIteration, ParameterError):
        return 0


def _resume_command(args: argparse.Namespace) -> str:
    """The command line that continues an interrupted sweep: this one with --resume instead of --force."""
    argv = getattr(args, "argv", None)
    if argv is None:
        return "the same command with --resume"
    words = [w for w in argv if w != "--force"]
    return shlex.join(["isolator", *words, *([] if "--resume" in words else ["--resume"])])


def _names(scenario: str | None) -> int:
    """``--list``: the scenario's parameter names, one a line, in the parameter vector's order."""
    from isolator.model.parameters import ParameterLayout
    from isolator.scenario.reader import load_scenario

    print("\n".join(ParameterLayout.of(load_scenario(scenario)).names))
    return 0


def _sweep(args: argparse.Namespace) -> int:
    if args.list:
        return _names(args.scenario)
    if args.out is None:
        raise ParameterError("--out: required: the file the rows go to (.csv or .parquet), or --list for the "
                             "parameter names")
    swept = _swept(args)
    if args.workers is not None:
        check_workers(args.workers, "--workers")
    out = output_path(args.out, "--out", SUFFIXES)
    figure = figure_path(args.plot, "--plot")
    if (out.exists() or staging_path(out).exists()) and not (args.resume or args.force):
        raise ParameterError(f"--out: '{out}' exists; --resume continues it, --force overwrites it")
    try:
        with scheduler_client(args) as client:
            executor: Executor | None = None if client is None else client.get_executor()
            result = sweep(args.scenario, swept["set"] or None, swept["scale"] or None, zip=args.zip,
                           samples=args.samples, method=args.method, seed=args.seed, model=args.model,
                           executor=executor, workers=args.workers, frequencies=args.frequency, modes=args.modes,
                           budget=",".join(args.budget) or None, out=out, resume=args.resume, force=args.force,
                           progress=True, chunk_size=args.chunk_size)
    except (ParameterError, ExecutorError) as exc:  # the API's words for its arguments, as this command's options
        raise type(exc)(_options_named(str(exc))) from None
    except KeyboardInterrupt as stop:  # Ctrl-C, or SIGTERM (the app's Terminated: exit status 143)
        how = "terminated" if type(stop).__name__ == "Terminated" else "interrupted"
        print(f"isolator: {how}: {_rows_kept(out)} row(s) kept in {escaped(out)}; continue with: "
              f"{escaped(_resume_command(args))}", file=sys.stderr)
        return 143 if how == "terminated" else 130
    print(result.summary())
    if figure is not None:
        from isolator.sweep.figure import plot_sweep

        use_agg()
        save_figure(plot_sweep(result), figure)
        print(written("figure", figure))
    return 0
