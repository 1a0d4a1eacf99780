"""``isolator compliance``: the table's compliance at a point, the datasheet's second curve."""

from __future__ import annotations

import argparse
import csv
from pathlib import Path
from typing import Any

import numpy as np

from isolator.cli.budget_command import parse_band
from isolator.cli.helpers import (
    count,
    figure_path,
    output_path,
    parse_positions,
    report,
    save_figure,
    scenario_argument,
    use_agg,
)
from isolator.errors import ParameterError
from isolator.scenario.output_files import atomic_output

__all__ = ["register"]


def register(sub: Any) -> None:
    """Add ``isolator compliance`` to the ``isolator`` command's subparsers."""
    comp = sub.add_parser(
        "compliance", help="compliance at a point of the top [m/N]: driving-point or cross, with the modes",
        description="The table on its isolators, the carriages parked at their start (or --position), the floor "
        "still: a unit force at the point --point along the world axis --axis, and the world displacement of the "
        "point --response (default the same) along that axis, in m/N. On a top that bends ([table.flexible]) "
        "its elastic modes add their peaks.",
    )
    scenario_argument(comp)
    comp.add_argument("--point", required=True, metavar="NAME", help="the [[points]] entry the force acts at")
    comp.add_argument("--axis", choices=["x", "y", "z"], default="z", help="world axis of force and response")
    comp.add_argument("--response", metavar="NAME", help="the [[points]] entry read (default: --point)")
    comp.add_argument("--band", metavar="LO:HI", help="frequencies [Hz] (default 1:2000)")
    comp.add_argument("--count", type=count, default=2000, metavar="N",
                      help="frequencies, log-spaced over the band, both ends included (default 2000)")
    comp.add_argument("--position", action="append", default=None, metavar="NAME=Q",
                      help="park carriage NAME at Q metres (repeatable; the others at their start)")
    comp.add_argument("--json", action="store_true", help="print JSON (frequency_hz, magnitude, phase_deg)")
    comp.add_argument("--out", type=Path, metavar="FILE.csv", help="write frequency_hz, magnitude, phase_deg")
    comp.add_argument("--plot", type=Path, metavar="FILE.png", help="write the log-log figure with the modes")
    comp.set_defaults(handler=_compliance)


def _compliance(args: argparse.Namespace) -> int:
    from isolator.analysis.linear import linearise
    from isolator.analysis.point_compliance import point_compliance
    from isolator.scenario.reader import load_scenario

    out = output_path(args.out, "--out", (".csv",)) if args.out else None
    plot = figure_path(args.plot, "--plot")
    band = parse_band(args.band) or (1.0, 2000.0)
    if not 0 < band[0] < band[1] or band[1] > 1e9:
        raise ParameterError(f"--band: expected 0 < LO < HI <= 1e9 Hz, got {band[0]:g}:{band[1]:g}")
    if args.count < 2 or args.count > 1_000_000:
        raise ParameterError(f"--count: must be from 2 to 1000000 frequencies, got {args.count}")
    scenario = load_scenario(args.scenario)
    lin = linearise(scenario, positions=parse_positions(args.position))
    result = point_compliance(lin, args.point, args.axis, args.response, np.geomspace(*band, args.count))
    if out is not None:
        header, rows = result.table()
        with atomic_output(out, newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(header)
            writer.writerows([[repr(float(v)) for v in row] for row in rows])
    if plot is not None:
        use_agg()
        save_figure(result.plot(title=f"Compliance of {scenario.name}"), plot)
    return report(args.json, result.to_dict(), result.summary(), [("compliance table", out), ("figure", plot)],
                  indent=None)
