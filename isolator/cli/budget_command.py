"""``isolator budget``: the error budget of the parked table, passive or with an exported controller."""

from __future__ import annotations

import argparse
import math
import re
import sys
from pathlib import Path
from typing import Any

from isolator.cli.helpers import (
    figure_path,
    output_path,
    parse_positions,
    read_controller,
    report,
    save_figure,
    scenario_argument,
    use_agg,
)
from isolator.errors import ParameterError, ScenarioError
from isolator.scenario.names import escaped

__all__ = ["BUDGET_SCENARIO", "parse_band", "register"]

#: the scenario ``isolator budget`` runs without one: the bundled table with random sources
BUDGET_SCENARIO = "paper-table-3-2-budget"

#: an error's leading argument name and the option that gave it
_OPTIONS = {"band": "--band", "points": "--points", "positions": "--position", "controller": "--controller",
            "relative": "--relative"}
_OPTION = re.compile(r"^(band|points|positions|controller|relative)(?:\.([^:\s]+))?(?=[:.\[])")


def register(sub: Any) -> None:
    """Add ``isolator budget`` to the ``isolator`` command's subparsers."""
    bud = sub.add_parser(
        "budget", help="error budget: random motion at the points from the floor, forces and noise (RMS)",
        description="The random motion of the table's points (nm RMS), source by source: the floor "
        "([ground.spectrum], or vc = \"VC-C\"), [[disturbances]], the actuators' noise_psd and, with "
        "--controller, the sensors' noise through the exported controller's sampled loop. Prints each point "
        "and axis's RMS and its largest source; with --controller, warns (stderr) where the loop makes a point "
        "move more than the passive table.",
    )
    scenario_argument(bud, f"scenario file or bundled name (default: {BUDGET_SCENARIO}, the bundled table with "
                      "random sources)")
    bud.add_argument("--controller", type=Path, metavar="DIR",
                     help="an exported controller (DIR/controller.json) in the loop (default: the passive table)")
    bud.add_argument("--points", metavar="NAME,...", help="[[points]] names, comma-separated (default: all)")
    bud.add_argument("--quantity", choices=["displacement", "velocity", "acceleration"], default="displacement",
                     help="of the points' absolute motion (default displacement)")
    bud.add_argument("--band", metavar="LO:HI",
                     help="band integrated [Hz] (default 0.1:1000; with --controller up to just below half its rate)")
    bud.add_argument("--position", action="append", default=None, metavar="NAME=Q",
                     help="park carriage NAME at Q metres (repeatable; the others at their start)")
    bud.add_argument("--json", action="store_true", help="print JSON instead of text")
    bud.add_argument("--out", type=Path, metavar="FILE.csv", help="write each source's ASD and the cumulative RMS")
    bud.add_argument("--relative", action="append", default=None, metavar="A:B",
                     help="also the random elastic translation of point A relative to point B, table axes (a top "
                     "that bends: the tool against the part; zero on a rigid top); repeatable")
    bud.add_argument("--plot", type=Path, metavar="FILE.png", help="write the figure")
    bud.set_defaults(handler=_budget)


def parse_band(text: str | None, option: str = "--band") -> tuple[float, float] | None:
    """``LO:HI`` [Hz] as two numbers (None when not given); the budget checks their order and range."""
    if text is None:
        return None
    low, sep, high = text.partition(":")
    try:
        values = (float(low), float(high))
    except ValueError:
        raise ParameterError(f"{option}: expected LO:HI in Hz (e.g. 0.5:200), got '{text[:40]}'") from None
    if not sep or not all(math.isfinite(v) for v in values):
        raise ParameterError(f"{option}: expected LO:HI in Hz (e.g. 0.5:200), got '{text[:40]}'")
    return values


def _budget(args: argparse.Namespace) -> int:
    from isolator.analysis.budget import error_budget
    from isolator.scenario.reader import load_scenario

    out = output_path(args.out, "--out", (".csv",)) if args.out else None
    plot = figure_path(args.plot, "--plot")
    band = parse_band(args.band)
    points = None if args.points is None else [p.strip() for p in args.points.split(",")]
    if points is not None and not all(points):
        raise ParameterError(f"--points: expected NAME,... (comma-separated names), got '{args.points[:40]}'")
    scenario = load_scenario(args.scenario or BUDGET_SCENARIO)
    controller = None if args.controller is None else read_controller(args.controller, "--controller")
    try:
        budget = error_budget(scenario, controller, points, args.quantity, band, parse_positions(args.position),
                              args.relative or ())
    except ParameterError as exc:  # the API's argument names as the command's options
        raise ParameterError(_OPTION.sub(lambda m: _OPTIONS[m.group(1)] + (f" {m.group(2)}" if m.group(2) else ""),
                                         str(exc), count=1)) from None
    except ScenarioError as exc:
        if not str(exc).startswith("the scenario has no random source"):
            raise
        raise ScenarioError(f"{exc}; the bundled {BUDGET_SCENARIO} has ten (the command's default)") from None
    if out:
        budget.to_csv(out)
    if plot is not None:
        use_agg()
        spec = {}
        if args.quantity == "displacement":
            for w in scenario.windows:
                for axis in w.axes:
                    if w.point in budget.points:
                        spec[(w.point, axis)] = w.translation / (w.random or 1.0)
        save_figure(budget.plot(spec, title=f"Error budget of {scenario.name}"), plot)
    for line in budget.worse_lines():  # one line (stderr) per point and axis the loop makes worse
        print(f"isolator: warning: {escaped(line)}", file=sys.stderr)
    text = "\n".join(budget.summary_lines())
    return report(args.json, budget.to_dict(), text, [("budget table", out), ("figure", plot)])
