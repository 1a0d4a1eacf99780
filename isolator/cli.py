"""The ``isolator`` command.

Every error a user can cause (bad scenario, unstable table, diverging run)
is printed as one line, ``isolator: error: ...``, with exit status 2.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

from .errors import IsolatorError
from .loading import DEFAULT_SCENARIO, bundled_scenarios, load_scenario
from .model import MODEL_KINDS

__all__ = ["main"]


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="isolator",
        description="Pneumatic isolation tables carrying moving stages: transients and settling.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    sim = sub.add_parser(
        "simulate",
        help="simulate the carriages' transients and report peaks and 5 %% settling times",
        description="Simulate a scenario from its initial static equilibrium; print peaks, "
        "final values and settling times per signal, and write a figure.",
    )
    sim.add_argument(
        "scenario", nargs="?", default=None,
        help=f"scenario file or bundled name (default: {DEFAULT_SCENARIO})",
    )
    sim.add_argument("--model", choices=MODEL_KINDS, default="exact",
                     help="exact rigid-body model or the paper's small-angle model")
    sim.add_argument("--out", type=Path, metavar="FILE.csv", help="write the response table")
    sim.add_argument("--plot", type=Path, metavar="FILE.png",
                     help="figure path (default: <scenario name>.png, none with --json)")
    sim.add_argument("--json", action="store_true", help="print a JSON summary instead of the table")

    study = sub.add_parser("study", help="run a study that writes figures and a report")
    study.add_argument("name", choices=["paper"], help="paper: reproduce Shin, Sun and Kim")
    study.add_argument("--out", type=Path, required=True, metavar="DIR", help="output folder")
    study.add_argument("--quick", action="store_true", help="shorter runs (for tests)")

    sub.add_parser("scenarios", help="list the bundled scenarios")
    return parser


def _simulate(args: argparse.Namespace) -> int:
    from .simulation import simulate

    scenario = load_scenario(args.scenario)
    response = simulate(scenario, model=args.model)
    if args.out:
        response.to_csv(args.out)
    plot = args.plot
    if plot is None and not args.json:
        plot = Path(f"{scenario.name}.png")
    if plot is not None:
        import matplotlib

        matplotlib.use("Agg")
        fig = response.plot()
        fig.savefig(plot, dpi=120)
    if args.json:
        print(json.dumps(response.to_dict(), indent=2))
    else:
        print(response.summary())
        if args.out:
            print(f"response table: {args.out}")
        if plot is not None:
            print(f"figure: {plot}")
    return 0


def _study(args: argparse.Namespace) -> int:
    import matplotlib

    matplotlib.use("Agg")
    if args.name == "paper":
        from studies.paper import run_paper_study

        report = run_paper_study(args.out, quick=args.quick)
        print(f"report: {report}")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``isolator`` command; returns the exit status."""
    args = _parser().parse_args(argv)
    try:
        if args.command == "simulate":
            return _simulate(args)
        if args.command == "study":
            return _study(args)
        if args.command == "scenarios":
            for name, path in sorted(bundled_scenarios().items()):
                print(f"{name}\t{path}")
            return 0
    except IsolatorError as exc:
        print(f"isolator: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("isolator: interrupted", file=sys.stderr)
        return 130
    return 1


if __name__ == "__main__":
    sys.exit(main())
