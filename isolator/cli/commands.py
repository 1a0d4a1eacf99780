"""The plant's subcommands: simulate, modes, transmissibility, stability, criteria, scenarios."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from isolator.analysis.linear import LinearModel, linearise
from isolator.cli.budget_command import register as register_budget
from isolator.cli.calibrate_command import register as register_calibrate
from isolator.cli.compliance_command import register as register_compliance
from isolator.cli.helpers import (
    check_memory,
    count,
    default_output,
    figure_path,
    output_path,
    parse_positions,
    read_controller,
    report,
    save_figure,
    scenario_argument,
    seed,
    use_agg,
)
from isolator.cli.plate_command import register as register_plate_modes
from isolator.cli.sequence_command import register as register_sequence
from isolator.errors import ParameterError
from isolator.model.variants import MODEL_KINDS
from isolator.scenario.definitions import Scenario
from isolator.scenario.files import parse_json, read_input_text
from isolator.scenario.names import escaped
from isolator.scenario.reader import bundled_scenarios, load_scenario
from isolator.simulation.band import Band, parse_half_widths
from isolator.simulation.discrete_controller import DiscreteController
from isolator.simulation.elastic_method import ELASTIC_CHOICES

__all__ = ["register"]


def register(sub: Any) -> None:
    """Add the plant's subcommands to the ``isolator`` command's subparsers."""
    sim = sub.add_parser(
        "simulate",
        help="simulate the carriages' transients and report peaks and settling times",
        description="Simulate a scenario from its initial static equilibrium; print peaks, "
        "final values and settling times per signal, and write a figure.",
    )
    scenario_argument(sim)
    sim.add_argument("--model", choices=MODEL_KINDS, default="exact",
                     help="exact rigid-body model or the paper's small-angle model")
    sim.add_argument("--elastic", choices=ELASTIC_CHOICES, default="auto",
                     help="a bending top's modes: quasi-static when at least ten times above the table's motion "
                     "(auto; runs with actuators acting keep them dynamic), always in the state (dynamic: "
                     "explicit steps that resolve them, slow), or always quasi-static")
    sim.add_argument("--out", type=Path, metavar="FILE.csv", help="write the response table")
    sim.add_argument("--plot", type=Path, metavar="FILE.png",
                     help="figure path (default: <scenario name>.png, none with --json)")
    sim.add_argument("--json", action="store_true", help="print a JSON summary instead of the table")
    sim.add_argument("--forces", type=Path, metavar="FILE.csv",
                     help="actuator forces file (t and one column per actuator, N)")
    sim.add_argument("--controller", type=Path, metavar="DIR",
                     help="run the discrete controller of DIR/controller.json (isolator controller's output) on the "
                     "scenario's sensors and actuators")
    sim.add_argument("--allow-unstable", action="store_true",
                     help="with --controller: run a controller whose sampled loop on the scenario's linear model is "
                     "unstable (checked first as 'isolator check-controller' does; refused with exit status 3 "
                     "without this option)")
    sim.add_argument("--noise", action="store_true",
                     help="with --controller: add each sensor's noise to its readings (white of its 'noise' RMS "
                          "per sample, or with its 'noise_psd' spectrum [SI^2/Hz] below half the controller's rate)")
    sim.add_argument("--seed", type=seed, default=0, metavar="N", help="seed of --noise (default 0)")
    band = sim.add_mutually_exclusive_group()
    band.add_argument("--band", metavar="x=M,y=M,z=M,rx=RAD,ry=RAD,rz=RAD",
                      help="settling band: six absolute half-widths [m, rad], e.g. a study's 'band' column "
                      "(default: the scenario's [settling] rule, 5 percent of each signal's own peak)")
    band.add_argument("--band-json", type=Path, metavar="FILE.json",
                      help="settling band from a JSON file: a study's band object (or an object with a 'band' key)")

    sim.set_defaults(handler=_simulate)

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
    trans.add_argument("--points", type=count, default=1000, help="frequencies, log-spaced (default 1000)")

    stab = sub.add_parser(
        "stability", help="rocking-stiffness margin over the carriages' travel",
        description="Check, before any simulation, that the table stands wherever the carriages go; "
        "exit status 3 when it would tip.",
    )
    scenario_argument(stab)
    stab.add_argument("--json", action="store_true", help="print JSON instead of text")

    crit = sub.add_parser(
        "criteria", help="one-third-octave table velocity from a floor spectrum, and its VC class",
        description="Pass a floor vibration spectrum through the parked table and rate a point "
        "against the VC curves (VC-A 50 µm/s ... VC-G 0.78 µm/s, 1-80 Hz).",
    )
    _linear_arguments(crit)
    crit.add_argument("--spectrum", type=Path, metavar="FILE.csv",
                      help="floor spectrum CSV (frequency_hz and x, y, z columns); default: [ground.spectrum]")
    crit.add_argument("--kind", choices=["third-octave", "psd"], default="third-octave",
                      help="band RMS velocities [m/s] or a velocity PSD [(m/s)^2/Hz] (default third-octave)")
    crit.add_argument("--point", default=None, help="a [[points]] name (default: the mass centre)")
    crit.add_argument("--plot", type=Path, metavar="FILE.png", help="write the figure against the VC curves")

    modes.set_defaults(handler=_modes)
    trans.set_defaults(handler=_transmissibility)
    stab.set_defaults(handler=_stability)
    crit.set_defaults(handler=_criteria)
    sub.add_parser("scenarios", help="list the bundled scenarios").set_defaults(handler=_scenarios)
    register_sequence(sub)
    register_calibrate(sub)
    register_budget(sub)
    register_compliance(sub)
    register_plate_modes(sub)


def _scenarios(args: argparse.Namespace) -> int:
    for name, path in sorted(bundled_scenarios().items()):
        print(f"{name}\t{escaped(path)}")
    return 0


def _linear_arguments(parser: argparse.ArgumentParser) -> None:
    scenario_argument(parser)
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--time", type=float, metavar="T",
                       help="park the carriages where their profiles are at T seconds (default: their start)")
    where.add_argument("--position", action="append", default=None, metavar="NAME=Q",
                       help="park carriage NAME at Q metres (repeatable; the others at their start)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of text")


def _linearised(args: argparse.Namespace) -> tuple[Scenario, LinearModel]:
    scenario = load_scenario(args.scenario)
    return scenario, linearise(scenario, positions=parse_positions(args.position), time=args.time)


def _modes(args: argparse.Namespace) -> int:
    use_agg()
    from isolator.analysis.modes import modes, modes_over_travel

    figure_path(args.plot, "--plot")
    figure_path(args.travel, "--travel")
    scenario, lin = _linearised(args)
    if args.travel and not scenario.carriages:
        raise ParameterError(f"--travel: the scenario '{scenario.name}' has no [[carriages]] to travel")
    result = modes(lin)
    if args.plot:
        save_figure(result.plot(title=f"Modes of {scenario.name}"), args.plot)
    if args.travel:
        travel = modes_over_travel(scenario)
        save_figure(travel.plot(title=f"Modes of {scenario.name} as the stage travels"), args.travel)
    return report(args.json, result.to_dict(), result.summary(), [("figure", args.plot), ("figure", args.travel)])


def _transmissibility(args: argparse.Namespace) -> int:
    use_agg()
    from isolator.analysis.transmissibility import compliance, default_frequencies, transmissibility

    if args.points < 2:
        raise ParameterError(f"--points: must be >= 2, got {args.points}")
    figure_path(args.plot, "--plot")
    _, lin = _linearised(args)
    check_memory(args.points * 16 * (lin.system.nstates ** 2 + 8 * 36), f"--points: {args.points:.3g} frequencies",
                 "ask for fewer")
    f = default_frequencies(lin, args.points)
    result = compliance(lin, f) if args.compliance else transmissibility(lin, f)
    if args.plot:
        save_figure(result.plot(), args.plot)
    return report(args.json, result.to_dict(), result.summary(), [("figure", args.plot)], indent=None)


def _stability(args: argparse.Namespace) -> int:
    from isolator.analysis.stability import stability

    report = stability(load_scenario(args.scenario))
    print(json.dumps(report.to_dict(), indent=2) if args.json else report.describe())
    return 0 if report.stable else 3


def _criteria(args: argparse.Namespace) -> int:
    use_agg()
    from isolator.analysis.vibration import vibration_criteria
    from isolator.scenario.tables import load_spectrum

    figure_path(args.plot, "--plot")
    _, lin = _linearised(args)
    spectrum = load_spectrum(args.spectrum, args.kind, key="--spectrum") if args.spectrum else None
    result = vibration_criteria(lin, spectrum, point=args.point)
    if args.plot:
        save_figure(result.plot(), args.plot)
    text = (f"floor: {result.floor_class}; table at {result.point}: {result.table_class} "
            f"(largest band RMS {result.table_max * 1e6:.3g} µm/s over 1-80 Hz)")
    return report(args.json, result.to_dict(), text, [("figure", args.plot)])


def _band_option(args: argparse.Namespace) -> Band | None:
    """The band of ``--band`` or ``--band-json`` (None: the scenario's rule)."""
    if args.band is not None:
        return parse_half_widths(args.band, "--band")
    if args.band_json is None:
        return None
    text = read_input_text(args.band_json, "--band-json", error=ParameterError)
    data = parse_json(text, f"--band-json: '{escaped(args.band_json, 120)}'")
    if isinstance(data, dict) and isinstance(data.get("band"), dict):
        data = data["band"]
    return Band.from_dict(data, "--band-json")


def _controller_option(args: argparse.Namespace) -> DiscreteController | None:
    """The controller of ``--controller DIR`` (None without it); ``--noise`` and ``--allow-unstable`` only with
    one."""
    if args.controller is None:
        if args.noise:
            raise ParameterError("--noise: adds sensor noise to a controller's readings; give --controller DIR")
        if args.allow_unstable:
            raise ParameterError("--allow-unstable: runs an unstable controller's loop; give --controller DIR")
        return None
    return read_controller(args.controller, "--controller")


def _simulate(args: argparse.Namespace) -> int:
    from isolator.simulation.simulator import Simulator

    out = output_path(args.out, "--out", (".csv",)) if args.out else None
    plot = figure_path(args.plot, "--plot")
    scenario = load_scenario(args.scenario)
    forces = None
    if args.forces:
        from isolator.simulation.actuation import load_forces

        forces = load_forces(args.forces, scenario, key="--forces")
    if plot is None and not args.json:
        plot = figure_path(default_output(scenario.name, ".png"), "--plot")
    leveling = windows = None
    if plot is not None:  # the figures beside it, checked before the run too
        if scenario.is_pneumatic:
            leveling = figure_path(plot.with_name(f"{plot.stem}-leveling{plot.suffix}"), "--plot")
        if scenario.windows:
            windows = figure_path(plot.with_name(f"{plot.stem}-windows{plot.suffix}"), "--plot")
    controller = _controller_option(args)
    if controller is not None:  # the sampled loop at the carriages' start, as isolator check-controller checks it
        from isolator.analysis.closed_loop import check_controller

        loop = check_controller(scenario, controller)
        if not loop.stable and not args.allow_unstable:
            print(f"isolator: error: --controller: {escaped(loop.describe())} (give --allow-unstable to run it "
                  "anyway)", file=sys.stderr)
            return 3
    response = Simulator(scenario, args.model, args.elastic).run(
        forces=forces, band=_band_option(args), controller=controller, noise=args.noise, seed=args.seed)
    if out:
        response.to_csv(out)
    if plot is not None:
        use_agg()
        save_figure(response.plot(), plot)
        if leveling is not None and response.pneumatic is not None:
            save_figure(response.plot_leveling(), leveling)
        if windows is not None and response.windows is not None:
            save_figure(response.plot_windows(), windows)
    outputs = [("response table", out), ("figure", plot), ("pressures and heights", leveling),
               ("settling windows", windows)]
    return report(args.json, response.to_dict(), response.summary(), outputs)
