"""The controllers' subcommands: feedforward, optimise-profile, controller and check-controller (for the
``isolator`` command)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from controllers import check_command, controller_command
from isolator.cli.helpers import check_run_memory, output_path, report, scenario_argument, use_agg
from isolator.errors import OptimisationError, ParameterError
from isolator.scenario.definitions import Scenario
from isolator.scenario.reader import load_scenario

if TYPE_CHECKING:
    from controllers.profiles import ProfileOptimisation

__all__ = ["register"]


def register(sub: Any) -> None:
    """Add ``feedforward``, ``optimise-profile``, ``controller`` and ``check-controller`` to the ``isolator``
    command's subparsers."""
    ff = sub.add_parser(
        "feedforward", help="actuator forces that cancel the carriages' reaction, and what they buy",
        description="Compute feedforward actuator forces from the planned carriage motion and compare "
        "the passive and controlled runs (settling band: 5 % of the passive peak per signal).",
    )
    ff.add_argument("scenario", nargs="?", default=None,
                    help="scenario file or bundled name with [[actuators]] (default: paper-table-3-2-active)")
    ff.add_argument("--method", choices=["allocation", "optimal"], default="allocation",
                    help="allocation: least squares of the reaction wrench over the actuators, within limits; "
                    "optimal: command histories optimised through the time-varying model, within force and "
                    "rate limits, accounting for the actuators' lag")
    ff.add_argument("--out", type=Path, metavar="FORCES.csv", help="write the forces file")
    ff.add_argument("--json", action="store_true", help="print JSON instead of text")

    opt = sub.add_parser(
        "optimise-profile", help="optimise the carriages' motion profiles to cut the settling or cycle time",
        description="Optimise each carriage's S-curve (or trapezoid) through the time-varying model with casadi "
        "and IPOPT, over model variants (isolator stiffness, damping and payload mass 15 % off), and compare "
        "with the scenario's own profiles by simulation. On a scenario with a [sequence], design every step's "
        "S-curves (limits within the carriages', start delays) for the least total time by the window rule on "
        "the exact model, and report the total time and throughput before and after.",
    )
    scenario_argument(opt)
    opt.add_argument("--objective", choices=["settling", "cycle"], default="settling",
                     help="settling: least residual vibration within the move-time limit; cycle: shortest move "
                     "that still settles at once")
    opt.add_argument("--max-move-time-increase", type=float, default=0.05, metavar="FRACTION",
                     help="longest move as a fraction over the scenario's (default 0.05)")
    opt.add_argument("--shape", choices=["scurve", "trapezoid"], default="scurve",
                     help="profile shape to design (default scurve)")
    opt.add_argument("--transcription", choices=["single", "multiple"], default="single",
                     help="single or multiple shooting (default single)")
    opt.add_argument("--nominal", action="store_true", help="optimise for the nominal model only")
    opt.add_argument("--out", type=Path, metavar="OPTIMISED.toml", help="write the scenario with the optimised "
                     "profiles")
    opt.add_argument("--json", action="store_true", help="print JSON instead of text")
    opt.add_argument("--samples", type=int, default=None, metavar="N",
                     help="with a [sequence]: designs tried per distinct move and profile family in the first "
                     "round (default 32)")

    ff.set_defaults(handler=_feedforward)
    controller_command.register(sub)
    check_command.register(sub)
    opt.set_defaults(handler=_optimise_profile,  # the parser's own defaults: a sequence refuses anything else
                     single_move_defaults={name: opt.get_default(name) for name in _SINGLE_MOVE_OPTIONS})


def _feedforward(args: argparse.Namespace) -> int:
    use_agg()
    from controllers.feedforward import compare_feedforward, feedforward_optimal

    out = output_path(args.out, "--out", (".csv",)) if args.out else None
    scenario = load_scenario(args.scenario or "paper-table-3-2-active")
    check_run_memory(scenario)
    feedforward = None
    if args.method == "optimal":
        feedforward = feedforward_optimal(scenario, progress=not args.json)
    result = compare_feedforward(scenario, feedforward)
    if out:
        result.feedforward.forces.to_csv(out)
    return report(args.json, result.to_dict(), result.summary(), [("forces file", out)])


def _optimise_profile(args: argparse.Namespace) -> int:
    use_agg()
    from controllers.profiles import (
        ROBUSTNESS_VARIANTS,
        ModelVariant,
        ProfileSettings,
        command_time,
        optimise_profiles,
        over_variants,
        write_scenario,
    )

    out = output_path(args.out, "--out", (".toml",)) if args.out else None
    scenario = load_scenario(args.scenario)
    check_run_memory(scenario)
    if scenario.sequence is not None:
        return _optimise_sequence(args, scenario, out)
    if args.samples is not None:
        raise ParameterError("--samples: designs the steps of a [sequence]; this scenario has none (leave it out)")
    settings = ProfileSettings(
        objective=args.objective, transcription=args.transcription, shape=args.shape,
        max_move_time_increase=args.max_move_time_increase,
        variants=(ModelVariant(),) if args.nominal else ROBUSTNESS_VARIANTS,
    )
    warning = None
    try:
        result = optimise_profiles(scenario, settings, progress=not args.json)
    except OptimisationError as exc:
        if getattr(exc, "result", None) is None:
            raise
        result, warning = exc.result, str(exc)  # type: ignore[attr-defined]
    start = command_time(scenario)
    spread = {
        "variants": [v.label for v in ROBUSTNESS_VARIANTS],
        "baseline": [m.settling_time_max for m in over_variants(scenario, "baseline", start)],
        "optimised": [m.settling_time_max for m in over_variants(result.scenario, "optimised", start)],
    }
    if out:
        write_scenario(args.scenario, result.designs, out)
    data = {**result.to_dict(), "robustness": spread}
    if warning:
        data["warning"] = warning
        print(f"isolator: warning: {warning}", file=sys.stderr)
    return report(args.json, data, _profile_summary(result, spread), [("optimised scenario", out)])


#: optimise-profile's options that design a single move (not for a sequence)
_SINGLE_MOVE_OPTIONS = ("objective", "shape", "transcription", "max_move_time_increase", "nominal")


def _optimise_sequence(args: argparse.Namespace, scenario: Scenario, out: Path | None) -> int:
    from controllers.profiles.sequence_design import optimise_sequence, write_sequence_scenario

    for name, default in args.single_move_defaults.items():
        if getattr(args, name) != default:
            option = "--" + name.replace("_", "-")
            raise ParameterError(f"{option}: designs a single move; a scenario with a [sequence] is designed for "
                                 "its total time (leave the option out)")
    samples = 32 if args.samples is None else args.samples
    if samples < 2:
        raise ParameterError(f"--samples: must be a whole number >= 2, got {samples}")
    result = optimise_sequence(scenario, samples=samples, progress=not args.json)
    if out:
        write_sequence_scenario(args.scenario, result.scenario, out)
    return report(args.json, result.to_dict(), result.summary(), [("optimised scenario", out)])


def _profile_summary(result: ProfileOptimisation, spread: dict[str, Any]) -> str:
    def num(value: float | None) -> str:
        return "n/a" if value is None else f"{value:.3f}"

    lines = [f"{'':>10} {'move [s]':>9} {'settling [s]':>13} {'cycle [s]':>10}"]
    for m in (result.baseline, result.optimised):
        lines.append(f"{m.label:>10} {m.move_time:>9.3f} {num(m.settling_time_max):>13} {num(m.cycle_time):>10}")
    for d in result.designs:
        text = ", ".join(f"{n} {float(v):.4g}" for n, v in zip(d.names, d.values, strict=True))
        lines.append(f"{d.name} ({d.shape}): {text}")
    for run in ("baseline", "optimised"):
        values = [v for v in spread[run] if v is not None]
        if values:
            lines.append(f"settling over model variants ({run}): {min(values):.3f} .. {max(values):.3f} s")
    lines.append(f"IPOPT {result.status}, {result.iterations} iterations, {result.build_time:.2f} s building, "
                 f"{result.solve_time:.2f} s solving")
    return "\n".join(lines)
