"""``isolator sequence``: run a scenario's step-and-settle ``[sequence]`` (or a raster built by ``--pattern``)
and print the per-step table, the total time and the throughput."""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

from isolator.cli.helpers import figure_path, output_path, save_figure, scenario_argument, use_agg, written
from isolator.errors import ParameterError, ScenarioError
from isolator.model.variants import MODEL_KINDS
from isolator.scenario.definitions import Scenario
from isolator.scenario.reader import load_scenario
from isolator.scenario.sequence import parse_pattern, raster_steps
from isolator.scenario.validation import validate_scenario

__all__ = ["DEFAULT_SEQUENCE", "UNSETTLED_STATUS", "register", "with_pattern"]

#: the exit status when a step does not settle within ``[simulation] duration``
UNSETTLED_STATUS = 4
#: the scenario ``isolator sequence`` runs when none is named
DEFAULT_SEQUENCE = "paper-table-3-2-sequence"


def register(sub: Any) -> None:
    """Add ``isolator sequence`` to the ``isolator`` command's subparsers."""
    seq = sub.add_parser(
        "sequence", help="step-and-settle: per-step move, settle and measure times, total time, throughput",
        description="Run the scenario's [sequence]: each step moves the carriages (S-curves at their limits), "
        "waits until every [[windows]] holds for 'measure' seconds, then the next step starts. Prints the "
        "per-step table, the total time and the throughput; exit status 4 (naming the step) when a step does "
        "not settle within [simulation] duration.",
    )
    scenario_argument(seq, f"scenario file or bundled name with a [sequence] (default: {DEFAULT_SEQUENCE})")
    seq.add_argument("--model", choices=MODEL_KINDS, default="exact",
                     help="exact rigid-body model or the paper's small-angle model")
    seq.add_argument("--out", type=Path, metavar="FILE.csv",
                     help="write the steps: step,start,stop,settled,end,move,settle [s]")
    seq.add_argument("--response", type=Path, metavar="FILE.csv",
                     help="write the response: t, the six table signals, q:<carriage>, <point>:x/y/z, step")
    seq.add_argument("--plot", type=Path, metavar="FILE.png",
                     help="write the figure (deviation from each step's settled position, window, phases)")
    seq.add_argument("--json", action="store_true", help="print JSON instead of the table")
    seq.add_argument("--pattern", action="append", default=None, metavar="NAME=START:STOP:COUNT",
                     help="replace the [sequence]'s steps by a serpentine raster: the first pattern's carriage "
                     "sweeps a row (COUNT positions from START to STOP m, inclusive), the second steps once per "
                     "row (repeat the option; measure, start and initial stay the [sequence]'s)")
    seq.set_defaults(handler=_sequence)


def with_pattern(scenario: Scenario, patterns: list[str]) -> Scenario:
    """``scenario`` with its ``[sequence]`` steps replaced by the serpentine raster of ``patterns``
    (:func:`~isolator.scenario.sequence.raster_steps`); a :class:`ParameterError` naming ``--pattern``."""
    if scenario.sequence is None:
        raise ParameterError(f"--pattern: the scenario '{scenario.name}' has no [sequence]; --pattern replaces a "
                             "[sequence]'s steps and keeps its measure, start and initial positions "
                             "(docs/scenario-format.md)")
    names = [c.name for c in scenario.carriages]
    for text in patterns:
        name, _ = parse_pattern(text)
        if name not in names:
            raise ParameterError(f"--pattern: unknown carriage '{name}' (carriages: {', '.join(names)})")
    steps = raster_steps(patterns)
    try:
        return validate_scenario(replace(scenario, sequence=replace(scenario.sequence, steps=steps)))
    except ScenarioError as exc:
        raise ParameterError(f"--pattern: {exc}") from None


def _sequence(args: argparse.Namespace) -> int:
    from isolator.simulation.sequence import run_sequence

    out = output_path(args.out, "--out", (".csv",)) if args.out else None
    response = output_path(args.response, "--response", (".csv",)) if args.response else None
    plot = figure_path(args.plot, "--plot")
    scenario = load_scenario(args.scenario or DEFAULT_SEQUENCE)
    if args.pattern:
        scenario = with_pattern(scenario, args.pattern)
    result = run_sequence(scenario, args.model)
    if out:
        result.write_steps(out)
    if response:
        result.write_response(response)
    if plot:
        use_agg()
        save_figure(result.plot(), plot)
    if args.json:
        print(json.dumps(result.to_dict(), indent=2))
    else:
        print(result.summary())
        for label, path in (("steps", out), ("response", response), ("figure", plot)):
            if path is not None:
                print(written(label, path))
    if result.unsettled is not None:
        print(f"isolator: error: step {result.unsettled} did not settle within the run's "
              f"{result.duration:g} s ([simulation] duration); later steps did not run", file=sys.stderr)
        return UNSETTLED_STATUS
    return 0
