"""The ``isolator study`` subcommands, one per study with only its own options (registered with the
``isolator`` command)."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from isolator.cli.helpers import (
    check_run_memory,
    output_folder,
    scheduler_arguments,
    scheduler_client,
    seed,
    use_agg,
    written,
)
from isolator.errors import ParameterError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.scenario.random_sources import vc_spectrum
from isolator.scenario.reader import DEFAULT_SCENARIO, load_scenario

__all__ = ["CONTROL_SCENARIO", "PNEUMATIC_SCENARIO", "register"]

#: the pneumatic study's default scenario
PNEUMATIC_SCENARIO = "paper-table-3-2-pneumatic"
#: the control study's default scenario
CONTROL_SCENARIO = "paper-table-3-2-geophones"


def register(sub: Any) -> None:
    """Add ``study`` and its subcommands (``paper``, ``control``, ``profiles``, ``tradeoff``, ``pneumatic``,
    ``robustness``, ``calibration``)."""
    study = sub.add_parser("study", help="run a study that writes figures and a report",
                           description="Run a study; each writes its figures and report.md into --out.")
    studies = study.add_subparsers(dest="study", required=True, metavar="STUDY")

    paper = _study(studies, "paper", "reproduce Shin, Sun and Kim's figures and settling time", None)
    paper.set_defaults(handler=_paper)

    control = _study(studies, "control", "passive, feedforward, feedback and both on an active table",
                     f"scenario with [[actuators]] (default: {CONTROL_SCENARIO})")
    control.add_argument("--controller", choices=["skyhook", "lead", "lqr", "hinf"], default="skyhook",
                         help="the feedback design in the time runs (default skyhook)")
    control.add_argument("--feedforward", choices=["allocation", "optimal"], default="allocation",
                         help="the feedforward method (default allocation)")
    control.add_argument("--sample-rate", type=float, default=2000.0, metavar="HZ",
                         help="with [[sensors]]: the output-feedback designs' rate (default 2000)")
    control.add_argument("--floor", metavar="VC-X", default=None,
                         help="put the table on a floor at the limit of this vibration criterion (VC-A to VC-G; "
                         "replaces its [ground.spectrum]) for the error budget of the sensor-based designs")
    control.add_argument("--bending", action="store_true",
                         help="add the bending-top case: the default designs on the rigid and the bending top, the "
                         "corner's compliance, a stiff design the check refuses (always when the scenario's top "
                         "bends and has [[sensors]]; a rigid 2 x 1 x 0.3 m, 4400 kg table gets the bundled granite "
                         "top; --quick: skyhook only, its own gain)")
    control.set_defaults(handler=_control)

    profiles = _study(studies, "profiles", "the scenario's profile, input shapers, time-optimal and optimised "
                      "moves", f"scenario file or bundled name (default: {DEFAULT_SCENARIO})")
    profiles.set_defaults(handler=_profiles)

    tradeoff = _study(studies, "tradeoff", "isolator stiffness and damping: settling time against "
                      "transmissibility", f"scenario file or bundled name (default: {DEFAULT_SCENARIO})")
    _frequency(tradeoff)
    _workers(tradeoff)
    tradeoff.set_defaults(handler=_tradeoff)

    pneumatic = _study(studies, "pneumatic", "air springs' orifice and damping-chamber volume: transmissibility "
                       "peaks, settling and leveling, the optimal orifice",
                       f"scenario with pneumatic isolators (default: {PNEUMATIC_SCENARIO})")
    _frequency(pneumatic)
    _workers(pneumatic)
    pneumatic.set_defaults(handler=_pneumatic)

    robustness = _study(studies, "robustness", "Monte Carlo over manufacturing tolerances: the settling time's "
                        "spread for the paper, ZVD and optimised profiles, and which tolerances matter",
                        f"scenario file or bundled name (default: {DEFAULT_SCENARIO})")
    robustness.add_argument("--tolerance", action="append", metavar="NAME=+-AMOUNT",
                            help="vary a parameter (layout name; [*] = every element) by a relative (+-5%%) or "
                            "absolute (+-0.002, its unit) tolerance; repeat for more (default: masses +-5%%, "
                            "stiffness +-10%%, damping +-20%%, isolator positions +-2 mm)")
    robustness.add_argument("--samples", type=int, default=200, metavar="N", help="machines drawn (default 200)")
    robustness.add_argument("--seed", type=seed, default=0, help="of the Latin-hypercube sampling (default 0)")
    where = robustness.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, default=None, metavar="N",
                       help="processes of the sweeps (default: the machine's cores)")
    scheduler_arguments(robustness, where)
    robustness.set_defaults(handler=_robustness)

    calibration = _study(studies, "calibration", "what calibration buys: profiles optimised on the datasheet and on "
                         "the calibrated model, both run on the true table",
                         "calibration file (default: the bundled example, SYNTHETIC records)")
    calibration.add_argument("--true", type=Path, metavar="TRUE.toml", dest="truth",
                             help="the true table's scenario (default: true.toml beside the calibration file)")
    calibration.add_argument("--fraction", type=float, default=0.01, metavar="F",
                             help="settling band: this fraction of the paper profile's peaks (default 0.01)")
    calibration.set_defaults(handler=_calibration)


def _workers(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--workers", type=int, default=None, metavar="N",
                        help="processes of the runs' sweep (default: the machine's cores)")


def _checked_workers(args: argparse.Namespace) -> int | None:
    if args.workers is not None and args.workers < 1:
        raise ParameterError(f"--workers: must be a whole number >= 1, got {args.workers}")
    return int(args.workers) if args.workers is not None else None


def _study(studies: Any, name: str, help_text: str, scenario_help: str | None) -> argparse.ArgumentParser:
    parser: argparse.ArgumentParser = studies.add_parser(name, help=help_text, description=help_text[0].upper()
                                                         + help_text[1:] + "; figures and report.md in --out.")
    if scenario_help is not None:
        parser.add_argument("scenario", nargs="?", default=None, help=scenario_help)
    parser.add_argument("--out", type=Path, required=True, metavar="DIR", help="output folder (made if missing)")
    parser.add_argument("--quick", action="store_true", help="shorter runs (for tests)")
    return parser


def _frequency(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--frequency", type=float, default=10.0, metavar="HZ",
                        help="frequency of the transmissibility figure (default 10 Hz)")


def _checked_frequency(args: argparse.Namespace) -> float:
    if not (math.isfinite(args.frequency) and args.frequency > 0):
        raise ParameterError(f"--frequency: must be a finite frequency > 0 Hz, got {args.frequency}")
    return float(args.frequency)


def _scenario(args: argparse.Namespace, default: str | None) -> Scenario:
    """The study's scenario, after its output folder is made; a run too long for memory refused up front."""
    output_folder(args.out, "--out")
    scenario = load_scenario(args.scenario or default)
    check_run_memory(scenario)
    use_agg()
    return scenario


def _paper(args: argparse.Namespace) -> int:
    from studies.paper import run_paper_study

    output_folder(args.out, "--out")
    use_agg()
    print(written("report", run_paper_study(args.out, quick=args.quick, progress=True)))
    return 0


def _bending_lines(case: Any) -> None:
    """The bending-top case in a few lines: each design's settling and disk margin, the stiff design's check."""
    for d in case.designs:
        settled = "n/a" if d.settling is None else f"{d.settling:.3g} s"
        print(f"{d.method + ' (' + d.top + ')':>18}: settling {settled}, disk margin {d.margin('disk_margin'):.3g}")
    stiff = case.stiff
    print(f"{'stiff design':>18}: " + (f"refused on the bending top, {stiff.bending.frequency_hz:.4g} Hz grows from "
                                       f"'{stiff.mode}' ({stiff.mode_hz:.4g} Hz)" if not stiff.bending.stable else
                                       "stable on the bending top"))


def _control(args: argparse.Namespace) -> int:
    from studies.control import run_control_study
    from studies.control_budget import on_floor

    if args.floor is not None:
        vc_spectrum(args.floor, "--floor")  # refused before the output folder is made
    scenario = _scenario(args, CONTROL_SCENARIO)
    if args.floor is not None:
        scenario = on_floor(scenario, args.floor, "--floor")
    control = run_control_study(args.out, scenario, args.controller, args.feedforward, sample_rate=args.sample_rate,
                                progress=True, bending=args.bending, quick=args.quick)
    for run in ("passive", "feedforward", "feedback", "both"):
        value = control.settling_time_max(run)
        settle, rate = control.window_cycle(run)
        window = "" if rate is None and settle is None else (
            f", window settling {'n/a' if settle is None else f'{settle:.3g} s'}"
            f"{'' if rate is None else f', {rate:.0f} moves per hour'}")
        why = control.unsettled_reason(run)
        print(f"{run:>12}: settling {f'n/a ({why})' if value is None else f'{value:.3g} s'}{window}")
    for design in control.sensors:
        value = design.settling_time_max
        budget = design.budget
        random = "" if budget is None or budget.passive is None or budget.closed is None else (
            f", random motion at {budget.point} {budget.closed.rms.max() * 1e9:.4g} nm RMS (passive "
            f"{budget.passive.rms.max() * 1e9:.4g} nm, worst axis), its sensors' noise "
            f"{budget.sensor_rms().max() * 1e9:.3g} nm")
        print(f"{design.method + ' (sensors)':>12}: settling {'n/a' if value is None else f'{value:.3g} s'}, "
              f"peak force {design.peak_force:.3g} N{random}")
    if control.bending is not None:
        _bending_lines(control.bending)
    print(written("report", args.out / "report.md"))
    return 0


def _tradeoff(args: argparse.Namespace) -> int:
    from studies.tradeoff import run_tradeoff_study

    frequency = _checked_frequency(args)
    stiffness = [0.5, 1.0, 2.0] if args.quick else None
    damping = [0.5, 1.0, 2.0, 4.0] if args.quick else None
    tradeoff = run_tradeoff_study(args.out, _scenario(args, None), stiffness, damping, reference_hz=frequency,
                                  workers=_checked_workers(args), progress=True)
    front = tradeoff.pareto()
    print(f"{len(front)} Pareto-optimal designs of {tradeoff.stiffness.size * tradeoff.damping.size}")
    if tradeoff.has_throughput:
        best = max(tradeoff.throughput_pareto(), key=lambda p: tradeoff.per_hour[p])
        print(f"most {tradeoff.rate_label}: {tradeoff.per_hour[best]:.1f} with stiffness "
              f"x{tradeoff.stiffness[best[0]]:.3g}, damping x{tradeoff.damping[best[1]]:.3g}")
    print(written("report", args.out / "report.md"))
    return 0


def _pneumatic(args: argparse.Namespace) -> int:
    from studies.pneumatic import run_pneumatic_study

    frequency = _checked_frequency(args)
    scenario = _scenario(args, PNEUMATIC_SCENARIO)
    diameters = ratios = None
    if args.quick:
        from studies.pneumatic import default_diameters

        own = default_diameters(scenario)
        diameters, ratios = own[[2, 7, 12]], [1.0, 2.0, 4.0]  # 0.52, 1 and 1.92 x the scenario's orifice
    pneumatic = run_pneumatic_study(args.out, scenario, diameters, ratios, reference_hz=frequency,
                                    workers=_checked_workers(args), progress=True)
    for o, c in zip(pneumatic.optima, pneumatic.closed_form, strict=True):
        print(f"N = {o.ratio:.3g}: optimal orifice {o.diameter * 1e3:.4g} mm, heave peak {o.peak:.4g} "
              f"(one-mass closed form {c.peak:.4g} with {c.diameter * 1e3:.4g} mm)")
    print(f"{len(pneumatic.pareto())} Pareto-optimal designs of {pneumatic.diameters.size * pneumatic.ratios.size}")
    print(written("report", args.out / "report.md"))
    return 0


def _calibration(args: argparse.Namespace) -> int:
    from studies.calibration import run_calibration_study

    output_folder(args.out, "--out")
    use_agg()
    if not (math.isfinite(args.fraction) and 0 < args.fraction < 1):
        raise ParameterError(f"--fraction: must be a fraction between 0 and 1, got {args.fraction}")
    study = run_calibration_study(args.out, args.scenario, args.truth, args.fraction, progress=True)
    for name, m in study.actual.items():
        settled = "n/a" if m.settling_time_max is None else f"{m.settling_time_max:.3g} s"
        print(f"{name:>10}: settling on the true table {settled}")
    print(written("report", args.out / "report.md"))
    return 0


def _robustness(args: argparse.Namespace) -> int:
    from controllers.profiles import ModelVariant, ProfileSettings
    from studies.robustness import parse_tolerances, run_robustness_study

    if args.samples < 1:
        raise ParameterError(f"--samples: must be a whole number >= 1, got {args.samples}")
    if args.workers is not None and args.workers < 1:
        raise ParameterError(f"--workers: must be a whole number >= 1, got {args.workers}")
    tolerances = parse_tolerances(args.tolerance)
    samples = min(args.samples, 12) if args.quick else args.samples
    settings = ProfileSettings(objective="settling", variants=(ModelVariant(),)) if args.quick else None
    with scheduler_client(args) as client:  # before any work or file
        scenario = _scenario(args, None)
        study = run_robustness_study(args.out, scenario, tolerances, samples, args.seed, args.workers,
                                     optimiser=settings, executor=None if client is None else client.get_executor(),
                                     progress=True)
    for name, m in study.methods.items():
        print(f"{name:>10}: settling P50 {m.percentile(50):.3g} s, P95 {m.percentile(95):.3g} s, "
              f"worst {m.worst:.3g} s")
    ranked = [(n, rho) for n, rho in study.ranking()[:3] if not math.isnan(rho)]
    top = ", ".join(f"{n} ({rho:+.2f})" for n, rho in ranked) or "too few machines to rank the tolerances"
    print(f"matters most: {top}")
    print(written("report", args.out / "report.md"))
    return 0


def _profiles(args: argparse.Namespace) -> int:
    from controllers.profiles import ROBUSTNESS_VARIANTS, ModelVariant
    from studies.profiles import run_profile_study

    scenario = _scenario(args, None)
    if scenario.sequence is not None:
        return _sequence_profiles(args, scenario)
    variants = (ModelVariant(),) if args.quick else ROBUSTNESS_VARIANTS
    profiles = run_profile_study(args.out, scenario, variants, source=args.scenario, progress=True)
    for name, m in profiles.methods.items():
        settle = "n/a" if m.settling_time_max is None else f"{m.settling_time_max:.3f} s"
        print(f"{name:>22}: move {m.move_time:.3f} s, settling {settle}")
    print(written("report", args.out / "report.md"))
    return 0


def _sequence_profiles(args: argparse.Namespace, scenario: Scenario) -> int:
    from studies.profiles_sequence import run_sequence_profile_study

    study = run_sequence_profile_study(args.out, scenario, source=args.scenario or DEFAULT_SCENARIO,
                                       samples=8 if args.quick else 32, progress=True)
    for name, run in study.runs.items():
        total = "did not settle" if run.total_time is None else f"total {run.total_time:.2f} s"
        rate = "" if run.throughput is None else f", {run.throughput:.0f} steps/h"
        print(f"{name:>22}: {total}{rate}")
    print(written("report", args.out / "report.md"))
    return 0


check_public(globals())
