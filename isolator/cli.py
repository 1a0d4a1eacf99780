"""The ``isolator`` command.

Every error a user can cause (bad scenario, unstable table, diverging run)
is printed as one line, ``isolator: error: ...``, with exit status 2.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Sequence
from pathlib import Path

from .errors import IsolatorError, OptimisationError, ScenarioError
from .loading import DEFAULT_SCENARIO, bundled_scenarios, load_scenario
from .model import MODEL_KINDS

__all__ = ["main"]


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="isolator",
        description="Pneumatic isolation tables carrying moving stages: transients, settling, "
        "modes, transmissibility, stability and vibration criteria.",
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
    sim.add_argument("--forces", type=Path, metavar="FILE.csv",
                     help="actuator forces file (t and one column per actuator, N)")

    study = sub.add_parser("study", help="run a study that writes figures and a report")
    study.add_argument("name", choices=["paper", "control", "profiles", "tradeoff"],
                       help="paper: reproduce Shin, Sun and Kim; control: passive, feedforward, feedback and both; "
                       "profiles: paper profile, input shapers, time-optimal and optimised moves; "
                       "tradeoff: isolator stiffness and damping, settling time against transmissibility")
    study.add_argument("scenario", nargs="?", default=None,
                       help="control: scenario with [[actuators]] (default: paper-table-3-2-active); "
                       f"profiles and tradeoff: (default: {DEFAULT_SCENARIO})")
    study.add_argument("--out", type=Path, required=True, metavar="DIR", help="output folder")
    study.add_argument("--quick", action="store_true", help="shorter runs (for tests)")
    study.add_argument("--controller", choices=["skyhook", "lead", "lqr", "hinf"], default="skyhook",
                       help="control: the feedback design in the time runs")
    study.add_argument("--feedforward", choices=["allocation", "optimal"], default="allocation",
                       help="control: the feedforward method")
    study.add_argument("--frequency", type=float, default=10.0, metavar="HZ",
                       help="tradeoff: frequency of the transmissibility figure (default 10 Hz)")

    modes = sub.add_parser(
        "modes", help="natural frequencies, damping ratios and mode shapes of the parked table",
        description="Linearise about a rest configuration and print the six rigid-body modes.",
    )
    _linear_arguments(modes)
    modes.add_argument("--plot", type=Path, metavar="FILE.png", help="write the mode-shape figure")
    modes.add_argument("--travel", type=Path, metavar="FILE.png",
                       help="write a figure of the modes as each carriage travels over its stroke")

    trans = sub.add_parser(
        "transmissibility", help="floor-to-table transmissibility (or compliance) per axis",
        description="Same-axis floor motion to table motion at the mass centre: peak, its frequency, "
        "and the frequency above which isolation starts.",
    )
    _linear_arguments(trans)
    trans.add_argument("--plot", type=Path, metavar="FILE.png", help="write the Bode plot")
    trans.add_argument("--compliance", action="store_true",
                       help="force / moment at the mass centre to table motion instead")
    trans.add_argument("--points", type=int, default=1000, help="frequencies, log-spaced (default 1000)")

    stab = sub.add_parser(
        "stability", help="rocking-stiffness margin over the carriages' travel",
        description="Check, before any simulation, that the table stands wherever the carriages go; "
        "exit status 3 when it would tip.",
    )
    stab.add_argument("scenario", nargs="?", default=None,
                      help=f"scenario file or bundled name (default: {DEFAULT_SCENARIO})")
    stab.add_argument("--json", action="store_true", help="print JSON instead of text")

    crit = sub.add_parser(
        "criteria", help="one-third-octave table velocity from a floor spectrum, and its VC class",
        description="Pass a floor vibration spectrum through the parked table and rate a point "
        "against the VC curves (VC-A 50 um/s ... VC-G 0.78 um/s, 1-80 Hz).",
    )
    _linear_arguments(crit)
    crit.add_argument("--spectrum", type=Path, metavar="FILE.csv",
                      help="floor spectrum CSV (frequency_hz and x, y, z columns); default: [ground.spectrum]")
    crit.add_argument("--kind", choices=["third-octave", "psd"], default="third-octave",
                      help="band RMS velocities [m/s] or a velocity PSD [(m/s)^2/Hz] (default third-octave)")
    crit.add_argument("--point", default=None, help="a [[points]] name (default: the mass centre)")
    crit.add_argument("--plot", type=Path, metavar="FILE.png", help="write the figure against the VC curves")

    ff = sub.add_parser(
        "feedforward", help="actuator forces that cancel the carriages' reaction, and what they buy",
        description="Compute feedforward actuator forces from the planned carriage motion and compare "
        "the passive and controlled runs (settling band: 5 %% of the passive peak per signal).",
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
        "and IPOPT, over model variants (isolator stiffness, damping and payload mass 15 %% off), and compare "
        "with the scenario's own profiles by simulation.",
    )
    opt.add_argument("scenario", nargs="?", default=None,
                     help=f"scenario file or bundled name (default: {DEFAULT_SCENARIO})")
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

    sub.add_parser("scenarios", help="list the bundled scenarios")
    return parser


def _feedforward(args: argparse.Namespace) -> int:
    from controllers.feedforward import compare_feedforward

    scenario = load_scenario(args.scenario or "paper-table-3-2-active")
    feedforward = None
    if args.method == "optimal":
        from controllers.optimal_feedforward import feedforward_optimal

        feedforward = feedforward_optimal(scenario, progress=not args.json)
    result = compare_feedforward(scenario, feedforward)
    if args.out:
        result.feedforward.forces.to_csv(args.out)
    return _report(args.json, result.to_dict(), result.summary(), [("forces file", args.out)])


def _optimise_profile(args: argparse.Namespace) -> int:
    from controllers.move_design import command_time
    from controllers.move_metrics import ROBUSTNESS_VARIANTS, ModelVariant, over_variants
    from controllers.profile_optimisation import ProfileSettings, optimise_profiles, write_scenario

    scenario = load_scenario(args.scenario)
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
    if args.out:
        write_scenario(args.scenario, result.designs, args.out)
    data = {**result.to_dict(), "robustness": spread}
    if warning:
        data["warning"] = warning
        print(f"isolator: warning: {warning}", file=sys.stderr)
    return _report(args.json, data, _profile_summary(result, spread), [("optimised scenario", args.out)])


def _profile_summary(result, spread: dict) -> str:
    def num(value: float | None) -> str:
        return "n/a" if value is None else f"{value:.3f}"

    lines = [f"{'':>10} {'move [s]':>9} {'settling [s]':>13} {'cycle [s]':>10}"]
    for m in (result.baseline, result.optimised):
        lines.append(f"{m.label:>10} {m.move_time:>9.3f} {num(m.settling_time_max):>13} {num(m.cycle_time):>10}")
    for d in result.designs:
        values = ", ".join(f"{n} {float(v):.4g}" for n, v in zip(d.names, d.values, strict=True))
        lines.append(f"{d.name} ({d.shape}): {values}")
    for run in ("baseline", "optimised"):
        values = [v for v in spread[run] if v is not None]
        if values:
            lines.append(f"settling over model variants ({run}): {min(values):.3f} .. {max(values):.3f} s")
    lines.append(f"IPOPT {result.status}, {result.iterations} iterations, {result.build_time:.2f} s building, "
                 f"{result.solve_time:.2f} s solving")
    return "\n".join(lines)


def _report(
    as_json: bool, data: dict, text: str, files: Sequence[tuple[str, Path | None]], indent: int | None = 2
) -> int:
    """Print the JSON, or the text followed by a ``label: path`` line per file written; exit status 0."""
    if as_json:
        print(json.dumps(data, indent=indent))
        return 0
    print(text)
    for label, path in files:
        if path is not None:
            print(f"{label}: {path}")
    return 0


def _linear_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scenario", nargs="?", default=None,
                        help=f"scenario file or bundled name (default: {DEFAULT_SCENARIO})")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--time", type=float, metavar="T",
                       help="park the carriages where their profiles are at T seconds (default: their start)")
    where.add_argument("--position", action="append", default=None, metavar="NAME=Q",
                       help="park carriage NAME at Q metres (repeatable; the others at their start)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of text")


def _linearised(args: argparse.Namespace):
    from .linear import linearise

    scenario = load_scenario(args.scenario)
    positions = None
    if args.position:
        positions = {}
        for item in args.position:
            name, sep, value = item.partition("=")
            try:
                positions[name.strip()] = float(value)
            except ValueError:
                raise ScenarioError(f"--position: expected NAME=Q with Q in metres, got '{item}'") from None
            if not sep:
                raise ScenarioError(f"--position: expected NAME=Q with Q in metres, got '{item}'")
    return scenario, linearise(scenario, positions=positions, time=args.time)


def _save(fig, path: Path) -> None:
    fig.savefig(path, dpi=120)
    import matplotlib.pyplot as plt

    plt.close(fig)


def _modes(args: argparse.Namespace) -> int:
    from .modes import modes, modes_over_travel

    scenario, lin = _linearised(args)
    result = modes(lin)
    if args.plot:
        _save(result.plot(title=f"Modes of {scenario.name}"), args.plot)
    if args.travel:
        _save(modes_over_travel(scenario).plot(title=f"Modes of {scenario.name} as the stage travels"), args.travel)
    return _report(args.json, result.to_dict(), result.summary(), [("figure", args.plot), ("figure", args.travel)])


def _transmissibility(args: argparse.Namespace) -> int:
    from .transmissibility import compliance, default_frequencies, transmissibility

    if args.points < 2:
        raise ScenarioError(f"--points: must be >= 2, got {args.points}")
    _, lin = _linearised(args)
    f = default_frequencies(lin, args.points)
    result = compliance(lin, f) if args.compliance else transmissibility(lin, f)
    if args.plot:
        _save(result.plot(), args.plot)
    return _report(args.json, result.to_dict(), result.summary(), [("figure", args.plot)], indent=None)


def _stability(args: argparse.Namespace) -> int:
    from .stability import stability

    report = stability(load_scenario(args.scenario))
    print(json.dumps(report.to_dict(), indent=2) if args.json else report.describe())
    return 0 if report.stable else 3


def _criteria(args: argparse.Namespace) -> int:
    from .loading import load_spectrum
    from .vibration import vibration_criteria

    _, lin = _linearised(args)
    spectrum = load_spectrum(args.spectrum, args.kind, key="--spectrum") if args.spectrum else None
    result = vibration_criteria(lin, spectrum, point=args.point)
    if args.plot:
        _save(result.plot(), args.plot)
    text = (f"floor: {result.floor_class}; table at {result.point}: {result.table_class} "
            f"(largest band RMS {result.table_max * 1e6:.3g} um/s over 1-80 Hz)")
    return _report(args.json, result.to_dict(), text, [("figure", args.plot)])


def _simulate(args: argparse.Namespace) -> int:
    from .simulation import simulate

    scenario = load_scenario(args.scenario)
    if args.forces:
        from .actuation import load_forces
        from .simulation import Simulator

        response = Simulator(scenario, args.model).run(forces=load_forces(args.forces, scenario, key="--forces"))
    else:
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
    return _report(args.json, response.to_dict(), response.summary(), [("response table", args.out), ("figure", plot)])


def _study(args: argparse.Namespace) -> int:
    import matplotlib

    matplotlib.use("Agg")
    if args.name == "paper":
        from studies.paper import run_paper_study

        report = run_paper_study(args.out, quick=args.quick)
        print(f"report: {report}")
    elif args.name == "control":
        from studies.control import run_control_study

        scenario = load_scenario(args.scenario or "paper-table-3-2-active")
        study = run_control_study(args.out, scenario, args.controller, args.feedforward)
        for run in ("passive", "feedforward", "feedback", "both"):
            value = study.settling_time_max(run)
            print(f"{run:>12}: settling {'n/a' if value is None else f'{value:.3g} s'}")
        print(f"report: {args.out / 'report.md'}")
    elif args.name == "tradeoff":
        from studies.tradeoff import run_tradeoff_study

        if not (math.isfinite(args.frequency) and args.frequency > 0):
            raise ScenarioError(f"--frequency: must be a finite frequency > 0 Hz, got {args.frequency}")
        grids = {"stiffness": [0.5, 1.0, 2.0], "damping": [0.5, 1.0, 2.0, 4.0]} if args.quick else {}
        study = run_tradeoff_study(args.out, load_scenario(args.scenario), reference_hz=args.frequency, **grids)
        front = study.pareto()
        print(f"{len(front)} Pareto-optimal designs of {study.stiffness.size * study.damping.size}")
        print(f"report: {args.out / 'report.md'}")
    elif args.name == "profiles":
        from controllers.move_metrics import ROBUSTNESS_VARIANTS, ModelVariant
        from studies.profiles import run_profile_study

        variants = (ModelVariant(),) if args.quick else ROBUSTNESS_VARIANTS
        profiles = run_profile_study(args.out, load_scenario(args.scenario), variants)
        for name, m in profiles.methods.items():
            settle = "n/a" if m.settling_time_max is None else f"{m.settling_time_max:.3f} s"
            print(f"{name:>22}: move {m.move_time:.3f} s, settling {settle}")
        print(f"report: {args.out / 'report.md'}")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``isolator`` command; returns the exit status."""
    args = _parser().parse_args(argv)
    try:
        if args.command == "simulate":
            return _simulate(args)
        if args.command == "study":
            return _study(args)
        handlers = {"modes": _modes, "transmissibility": _transmissibility, "stability": _stability,
                    "criteria": _criteria, "feedforward": _feedforward,
                    "optimise-profile": _optimise_profile}
        if args.command in handlers:
            if args.command != "stability":
                import matplotlib

                matplotlib.use("Agg")
            return handlers[args.command](args)
        if args.command == "scenarios":
            for name, path in sorted(bundled_scenarios().items()):
                print(f"{name}\t{path}")
            return 0
    except IsolatorError as exc:
        print(f"isolator: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into a command that stopped reading
        sys.stderr.close()
        return 0
    except KeyboardInterrupt:
        print("isolator: interrupted", file=sys.stderr)
        return 130
    return 1


if __name__ == "__main__":
    sys.exit(main())
