"""The ``isolator study`` subcommand (registered with the ``isolator`` command)."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from isolator.cli.helpers import use_agg
from isolator.errors import ParameterError
from isolator.scenario.reader import DEFAULT_SCENARIO, load_scenario

__all__ = ["PNEUMATIC_SCENARIO", "register"]

#: the pneumatic study's default scenario
PNEUMATIC_SCENARIO = "paper-table-3-2-pneumatic"


def register(sub: Any) -> None:
    """Add ``study`` to the ``isolator`` command's subparsers."""
    study = sub.add_parser("study", help="run a study that writes figures and a report")
    study.add_argument("name", choices=["paper", "control", "profiles", "tradeoff", "pneumatic"],
                       help="paper: reproduce Shin, Sun and Kim; control: passive, feedforward, feedback and both; "
                       "profiles: paper profile, input shapers, time-optimal and optimised moves; "
                       "tradeoff: isolator stiffness and damping, settling time against transmissibility; "
                       "pneumatic: air springs' orifice and damping-chamber volume, transmissibility peaks, "
                       "settling and leveling, the optimal orifice")
    study.add_argument("scenario", nargs="?", default=None,
                       help="control: scenario with [[actuators]] (default: paper-table-3-2-active); "
                       f"profiles and tradeoff: (default: {DEFAULT_SCENARIO}); "
                       f"pneumatic: with pneumatic isolators (default: {PNEUMATIC_SCENARIO})")
    study.add_argument("--out", type=Path, required=True, metavar="DIR", help="output folder")
    study.add_argument("--quick", action="store_true", help="shorter runs (for tests)")
    study.add_argument("--controller", choices=["skyhook", "lead", "lqr", "hinf"], default="skyhook",
                       help="control: the feedback design in the time runs")
    study.add_argument("--feedforward", choices=["allocation", "optimal"], default="allocation",
                       help="control: the feedforward method")
    study.add_argument("--frequency", type=float, default=10.0, metavar="HZ",
                       help="tradeoff and pneumatic: frequency of the transmissibility figure (default 10 Hz)")

    study.set_defaults(handler=_study)


def _study(args: argparse.Namespace) -> int:
    use_agg()
    if args.name == "paper":
        from studies.paper import run_paper_study

        report = run_paper_study(args.out, quick=args.quick)
        print(f"report: {report}")
    elif args.name == "control":
        from studies.control import run_control_study

        scenario = load_scenario(args.scenario or "paper-table-3-2-active")
        control = run_control_study(args.out, scenario, args.controller, args.feedforward)
        for run in ("passive", "feedforward", "feedback", "both"):
            value = control.settling_time_max(run)
            print(f"{run:>12}: settling {'n/a' if value is None else f'{value:.3g} s'}")
        print(f"report: {args.out / 'report.md'}")
    elif args.name == "tradeoff":
        from studies.tradeoff import run_tradeoff_study

        if not (math.isfinite(args.frequency) and args.frequency > 0):
            raise ParameterError(f"--frequency: must be a finite frequency > 0 Hz, got {args.frequency}")
        stiffness = [0.5, 1.0, 2.0] if args.quick else None
        damping = [0.5, 1.0, 2.0, 4.0] if args.quick else None
        tradeoff = run_tradeoff_study(args.out, load_scenario(args.scenario), stiffness, damping,
                                      reference_hz=args.frequency)
        front = tradeoff.pareto()
        print(f"{len(front)} Pareto-optimal designs of {tradeoff.stiffness.size * tradeoff.damping.size}")
        print(f"report: {args.out / 'report.md'}")
    elif args.name == "pneumatic":
        from studies.pneumatic import run_pneumatic_study

        if not (math.isfinite(args.frequency) and args.frequency > 0):
            raise ParameterError(f"--frequency: must be a finite frequency > 0 Hz, got {args.frequency}")
        scenario = load_scenario(args.scenario or PNEUMATIC_SCENARIO)
        diameters = ratios = None
        if args.quick:
            from studies.pneumatic import default_diameters

            own = default_diameters(scenario)
            diameters, ratios = own[[2, 7, 12]], [1.0, 2.0, 4.0]  # 0.52, 1 and 1.92 x the scenario's orifice
        pneumatic = run_pneumatic_study(args.out, scenario, diameters, ratios, reference_hz=args.frequency)
        for o, c in zip(pneumatic.optima, pneumatic.closed_form, strict=True):
            print(f"N = {o.ratio:.3g}: optimal orifice {o.diameter * 1e3:.4g} mm, heave peak {o.peak:.4g} "
                  f"(one-mass closed form {c.peak:.4g} with {c.diameter * 1e3:.4g} mm)")
        print(f"{len(pneumatic.pareto())} Pareto-optimal designs of {pneumatic.diameters.size * pneumatic.ratios.size}")
        print(f"report: {args.out / 'report.md'}")
    elif args.name == "profiles":
        from controllers.profiles import ROBUSTNESS_VARIANTS, ModelVariant
        from studies.profiles import run_profile_study

        variants = (ModelVariant(),) if args.quick else ROBUSTNESS_VARIANTS
        profiles = run_profile_study(args.out, load_scenario(args.scenario), variants)
        for name, m in profiles.methods.items():
            settle = "n/a" if m.settling_time_max is None else f"{m.settling_time_max:.3f} s"
            print(f"{name:>22}: move {m.move_time:.3f} s, settling {settle}")
        print(f"report: {args.out / 'report.md'}")
    return 0
