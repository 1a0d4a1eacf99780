"""``isolator calibrate``: fit a scenario's parameters to measured records, write the fitted scenario."""

from __future__ import annotations

import argparse
import contextlib
import sys
from pathlib import Path
from typing import Any

from isolator.cli.helpers import figure_path, output_folder, output_path, report, save_figure, use_agg

__all__ = ["register"]


def register(sub: Any) -> None:
    """Add ``isolator calibrate`` to the ``isolator`` command's subparsers."""
    cal = sub.add_parser(
        "calibrate", help="fit isolator parameters to measured records (floor or move experiments)",
        description="Fit the calibration file's parameters (stiffness, damping, ...) to its records: floor "
        "experiments by their multi-input H1 against the linearised model, move experiments sample by sample "
        "against the time-varying model, all together, each weighted by its own noise. Prints each parameter "
        "with its 95 % interval and writes the fitted scenario. Refuses (exit 2, nothing written) when the "
        "records cannot tell some fitted parameters apart, naming them; and (exit 3, nothing written) when the "
        "fit does not explain an experiment's record within its noise (its weighted residual variance beyond "
        "the chi-square limit), naming the experiment, the ratio, the sensor that misfits most and a likely "
        "cause (a record in mm/s^2, a flipped sensor).",
    )
    cal.add_argument("calibration", type=Path, metavar="CALIBRATION.toml",
                     help="the calibration file, or a bundled one by name (table-3-2: SYNTHETIC records)")
    cal.add_argument("--out", type=Path, required=True, metavar="FITTED.toml",
                     help="write the fitted scenario (the scenario file with the fitted values)")
    cal.add_argument("--json", action="store_true", help="print JSON (parameters, identifiable, correlation, ...)")
    cal.add_argument("--plot", type=Path, metavar="FIT.png", help="write the figure (H1 or traces, parameters)")
    cal.add_argument("--report", type=Path, metavar="DIR", help="write DIR/report.md with the figure")
    cal.add_argument("--fit", nargs="+", metavar="NAME", help="fit only these of the file's fitted names")
    cal.add_argument("--allow-unidentifiable", action="store_true",
                     help="write the fit even when some parameters cannot be told apart (identifiable: false)")
    cal.add_argument("--accept-misfit", action="store_true",
                     help="write the fit even when it does not explain the records (fit_ok: false)")
    cal.set_defaults(handler=_calibrate)


def _calibrate(args: argparse.Namespace) -> int:
    from isolator.calibration import calibrate
    from isolator.calibration.report import write_report
    from isolator.errors import MisfitError

    wanted = [p for p in (args.out, args.plot, args.report / "report.md" if args.report else None) if p is not None]
    missing = [above for p in wanted for above in (p.parent, *p.parent.parents) if not above.exists()]
    out = output_path(args.out, "--out", (".toml",))
    plot = figure_path(args.plot, "--plot")
    folder = output_folder(args.report, "--report") if args.report else None
    show = not args.json and sys.stderr.isatty()  # a line per model evaluation, in a terminal only
    progress = (lambda line: print(f"  {line}", file=sys.stderr, flush=True)) if show else None
    try:
        result = calibrate(args.calibration, fit=args.fit, allow_unidentifiable=args.allow_unidentifiable,
                           progress=progress, accept_misfit=args.accept_misfit)
    except BaseException as exc:  # nothing written: the folders the output paths made are removed again
        for above in sorted(set(missing), key=lambda q: len(q.parts), reverse=True):
            with contextlib.suppress(OSError):
                above.rmdir()
        if isinstance(exc, MisfitError):
            print(f"isolator: error: {exc}", file=sys.stderr)
            return 3
        raise
    result.write_scenario(out)
    if plot is not None or folder is not None:
        use_agg()
    if plot is not None:
        save_figure(result.plot(), plot)
    if folder is not None:
        write_report(result, folder)
    written = None if folder is None else folder / "report.md"
    return report(args.json, result.to_dict(), result.summary(),
                  [("fitted scenario", out), ("figure", plot), ("report", written)])
