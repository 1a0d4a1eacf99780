"""``isolator controller``: design an output-feedback controller, check it over the travel, export it as C.

Registered with the ``isolator`` command by :func:`controllers.cli.register`. The controller is designed
(:func:`controllers.feedback.design_controller`), checked closed-loop, sampled, with the actuators' lag and
the delay, at the carriages' extreme and middle positions and over the isolators' uncertainty
(:func:`controllers.feedback.check_robustness`), and only then written: ``controller.json`` (with the
robustness report under ``"robustness"``), ``controller.h`` and ``controller.c``. A refused design
writes nothing.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from isolator.cli.helpers import output_folder, report
from isolator.errors import ParameterError
from isolator.scenario.reader import load_scenario

__all__: list[str] = []  # a command-line entry point: registered by controllers.cli, not a library name

#: the scenario ``isolator controller`` designs for when none is named
DEFAULT_SCENARIO = "paper-table-3-2-geophones"


def register(sub: Any) -> None:
    """Add ``controller`` to the ``isolator`` command's subparsers."""
    ctl = sub.add_parser(
        "controller", help="design an output-feedback controller from the sensors, check it, export it as C",
        description="Design a discrete controller from the scenario's [[sensors]] to its [[actuators]] (skyhook, "
        "LQG or H-infinity), optionally gain-scheduled over a carriage's travel; check the sampled loop (actuator "
        "lag and delay included) at the carriages' extreme and middle positions and over the isolators' "
        "uncertainty, reporting margins and the worst case; refuse a design that is unstable anywhere, naming "
        "where; else write controller.h, controller.c (C99) and controller.json into --out.",
    )
    ctl.add_argument("scenario", nargs="?", default=None,
                     help=f"scenario file or bundled name with [[sensors]] and [[actuators]] (default: "
                     f"{DEFAULT_SCENARIO})")
    ctl.add_argument("--method", choices=["skyhook", "lqg", "hinf"], required=True,
                     help="skyhook: collocated velocity feedback through the geophone high-pass; lqg: Kalman filter "
                     "and LQR on the table's velocities; hinf: H-infinity output feedback (needs slycot)")
    ctl.add_argument("--sample-rate", type=float, required=True, metavar="HZ",
                     help="the controller's rate (at least twice the table's highest mode)")
    ctl.add_argument("--out", type=Path, required=True, metavar="DIR", help="folder for the three files")
    ctl.add_argument("--schedule", type=int, default=1, metavar="N",
                     help="design at N positions along the scheduling carriage's travel and interpolate (default "
                     "1: one design with every carriage at the middle of its travel)")
    ctl.add_argument("--schedule-carriage", default=None, metavar="NAME",
                     help="the carriage that schedules (default: the one moving the most mass the farthest)")
    ctl.add_argument("--delay", action="store_true",
                     help="design for one sample of computation delay (u_k acts from t_k+1)")
    ctl.add_argument("--uncertainty", default=None, metavar="SPEC",
                     help="check over isolator stiffness and damping varied within bounds, e.g. "
                     "'stiffness=+-20%%,damping=+-30%%' (default: nominal isolators only)")
    ctl.add_argument("--calibration-json", type=Path, default=None, metavar="FILE",
                     help="check over the 95 %% intervals of a calibration ('isolator calibrate --json' output)")
    ctl.add_argument("--gain", type=float, default=None, metavar="N_S_PER_M",
                     help="skyhook: damping per actuator (default: chosen per world axis by a search judged by the "
                     "simulated move's settling, the force limits and the margins)")
    ctl.add_argument("--highpass", type=float, default=None, metavar="HZ",
                     help="skyhook: the geophone loop's high-pass corner (default: a fifth of the lowest mode)")
    ctl.add_argument("--max-velocity", type=float, default=None, metavar="M_PER_S",
                     help="lqg and hinf: the acceptable table velocity (and angular velocity, rad/s) (default: lqg "
                     "chosen per axis by a search as for --gain, hinf 0.01)")
    ctl.add_argument("--fmu", action="store_true",
                     help="also write controller.fmu: the controller as an FMI 2.0 Co-Simulation FMU (inputs "
                     "y:<sensor>, q:<carriage>; outputs u:<actuator>; one step per sample); needs a C compiler")
    ctl.add_argument("--json", action="store_true", help="print JSON instead of text")
    ctl.set_defaults(handler=_controller)


def _writable_folder(path: Path) -> None:
    """Refuse an ``--out`` that cannot become a folder, without making anything."""
    if path.exists() and not path.is_dir():
        raise ParameterError(f"--out: '{path}' is a file, not a folder")
    for above in (path, *path.parents):
        if above.exists():
            if not above.is_dir():
                raise ParameterError(f"--out: cannot make '{path}': '{above}' is a file, not a folder")
            if not os.access(above, os.W_OK | os.X_OK):
                raise ParameterError(f"--out: cannot write into '{above}' (permission denied)")
            return


#: the design settings each method takes from the command line: option -> keyword
_SETTINGS = {"skyhook": {"--gain": "gain", "--highpass": "highpass_hz"}, "lqg": {"--max-velocity": "max_velocity"},
             "hinf": {"--max-velocity": "max_velocity"}}


def _options(args: argparse.Namespace) -> dict[str, float]:
    given = {"--gain": args.gain, "--highpass": args.highpass, "--max-velocity": args.max_velocity}
    allowed = _SETTINGS[args.method]
    options: dict[str, float] = {}
    for option, value in given.items():
        if value is None:
            continue
        if option not in allowed:
            raise ParameterError(f"{option}: not a setting of --method {args.method} (it takes "
                                 f"{', '.join(allowed)})")
        options[allowed[option]] = value
    if "max_velocity" in options:
        options["max_rate"] = options["max_velocity"]
    return options


class _Progress:
    """The robustness check's progress on stderr, one line per tenth, once it has taken 2 s."""

    def __init__(self) -> None:
        self.start = time.perf_counter()

    def __call__(self, done: int, total: int) -> None:
        if time.perf_counter() - self.start > 2.0 and (done == total or done % max(total // 10, 1) == 0):
            print(f"  robustness: {done}/{total} cases", file=sys.stderr, flush=True)


def _search_line(settings: Any) -> list[str]:
    """The line on the weights a search chose (none without a search)."""
    search = settings.get("search")
    if not search or not search["chosen"]:
        return []
    chosen = ", ".join(f"{k} " + "/".join(f"{x:.3g}" for x in (v if isinstance(v, list) else [v]))
                       for k, v in search["chosen"].items())
    ratio = (f"settles the move in {search['settling'] / search['passive_settling']:.3g} of the passive time"
             if search["settling"] is not None and search["passive_settling"] else "")
    return [f"weights chosen by a search of {search['candidates']} designs ({chosen}): {ratio}".rstrip(": ")]


def _controller(args: argparse.Namespace) -> int:
    from controllers.feedback import (
        check_robustness,
        design_controller,
        parse_uncertainty,
        uncertainty_from_calibration,
        write_c,
        write_controller_fmu,
    )

    _writable_folder(args.out)
    if args.fmu:
        from isolator.fmu.package import c_compiler

        c_compiler()  # before the design and its check
    if args.uncertainty is not None and args.calibration_json is not None:
        raise ParameterError("--uncertainty: give either bounds or --calibration-json, not both")
    uncertainty = (parse_uncertainty(args.uncertainty) if args.uncertainty is not None else
                   uncertainty_from_calibration(args.calibration_json) if args.calibration_json is not None else None)
    scenario = load_scenario(args.scenario or DEFAULT_SCENARIO)
    controller = design_controller(scenario, args.method, args.sample_rate, delay=args.delay, schedule=args.schedule,
                                   schedule_carriage=args.schedule_carriage, options=_options(args))
    robustness = check_robustness(scenario, controller, uncertainty, progress=None if args.json else _Progress())
    robustness.raise_if_unstable()
    folder = output_folder(args.out, "--out")
    data = {**controller.to_dict(), "robustness": robustness.to_dict()}
    # the three files written beside each other first, then renamed: never a .json of one design beside
    # the .c of another
    with tempfile.TemporaryDirectory(dir=folder, prefix=".controller-") as scratch:
        staged = Path(scratch)
        (staged / "controller.json").write_text(json.dumps(data, indent=1, allow_nan=False) + "\n", encoding="utf-8")
        write_c(controller, staged)
        names: tuple[str, ...] = ("controller.json", "controller.h", "controller.c")
        if args.fmu:
            write_controller_fmu(controller, staged / "controller.fmu", key="--fmu", scenario=scenario)
            names += ("controller.fmu",)
        for name in names:
            os.replace(staged / name, folder / name)
    target, header, source = (folder / name for name in ("controller.json", "controller.h", "controller.c"))
    lines = [f"{args.method} controller: {len(controller.sensors)} sensors -> {len(controller.actuators)} actuators, "
             f"{controller.states} states, {controller.sample_rate:g} Hz"
             + (", one sample of delay" if controller.delay else "")
             + (f", scheduled over {controller.carriages[controller.schedule_carriage]} at "
                f"{len(controller.schedule)} points" if controller.schedule else ""),
             *_search_line(controller.settings), *robustness.summary()]
    return report(args.json, data, "\n".join(lines),
                  [("controller data", target), ("C header", header), ("C source", source),
                   ("FMU", folder / "controller.fmu" if args.fmu else None)])
