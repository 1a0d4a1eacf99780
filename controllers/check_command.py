"""``isolator check-controller``: is a controller stable on a table, and if not, which mode grows.

Registered with the ``isolator`` command by :func:`controllers.cli.register`. The sampled loop of
``DIR/controller.json`` (hold, discrete controller, actuators' lags, delay) on the scenario's linear model with
the carriages at their start or at ``--position`` (:func:`isolator.analysis.closed_loop.check_controller`, the
loop ``isolator simulate --controller`` checks and the designs' robustness check closes), and its disk margin
at the actuators (:func:`controllers.feedback.loop_margins.sampled_margins`). Exit status 0 when stable, 3
when not (``docs/scenario-format.md``, "Controllers on a bending top").
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

from isolator.analysis.closed_loop import SampledLoop, check_controller
from isolator.cli.helpers import parse_positions, read_controller
from isolator.scenario.reader import load_scenario

__all__: list[str] = []  # a command-line entry point: registered by controllers.cli, not a library name


def register(sub: Any) -> None:
    """Add ``check-controller`` to the ``isolator`` command's subparsers."""
    chk = sub.add_parser(
        "check-controller", help="is a controller (controller.json) stable on a table, and if not, which mode grows",
        description="Close the sampled loop of DIR/controller.json (zero-order hold, the discrete controller, the "
        "actuators' lags, the delay) on the scenario's linear model (a bending top's elastic modes included) "
        "with the carriages at their start or at --position, exactly as 'isolator simulate --controller' runs "
        "it. Exit status 0 when every closed-loop eigenvalue is inside the unit circle; 3 when not, with one "
        "line naming the growing oscillation's frequency and the open-loop mode it comes from.",
    )
    chk.add_argument("controller", type=Path, metavar="DIR", help="folder of controller.json (or the file)")
    chk.add_argument("scenario", help="scenario file or bundled name with the controller's sensors and actuators")
    chk.add_argument("--position", action="append", default=None, metavar="NAME=Q",
                     help="park a carriage at Q metres (within its travel; repeatable; default: every carriage "
                     "at its start); a scheduled controller is taken at these positions")
    chk.add_argument("--json", action="store_true", help="print JSON instead of text")
    chk.set_defaults(handler=_check_controller)


def _json(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def loop_report(loop: SampledLoop, actuators: tuple[str, ...]) -> dict[str, Any]:
    """JSON-ready: ``stable``, ``spectral_radius``, ``frequency_hz``, ``mode`` (the open-loop mode of the largest
    eigenvalue), ``mode_frequency_hz`` and, for a stable loop, ``disk_margin`` (multiloop, at the actuators;
    null when unstable) with its frequency and each actuator's loop-at-a-time disk margin."""
    from controllers.feedback.loop_margins import sampled_margins

    name, f_mode = loop.growing_mode()
    lin = loop.lin
    out: dict[str, Any] = {
        "stable": loop.stable, "spectral_radius": loop.spectral_radius, "frequency_hz": loop.frequency_hz,
        "mode": name, "mode_frequency_hz": _json(f_mode), "sample_rate": loop.sample_rate,
        "positions": {c.name: float(q) for c, q in zip(lin.scenario.carriages, lin.positions, strict=True)},
        "disk_margin": None, "disk_frequency_hz": None, "loop_disk_margins": None}
    if loop.stable:
        margins = sampled_margins(loop)
        out["disk_margin"] = _json(margins.disk_margin)
        out["disk_frequency_hz"] = _json(margins.disk_frequency)
        out["loop_disk_margins"] = {a: _json(float(v)) for a, v in zip(actuators, margins.loop_disk_margin,
                                                                          strict=True)}
    return out


def _check_controller(args: argparse.Namespace) -> int:
    controller = read_controller(args.controller, "controller")
    scenario = load_scenario(args.scenario)
    loop = check_controller(scenario, controller, parse_positions(args.position), key="--position")
    data = loop_report(loop, tuple(a.name for a in scenario.actuators))
    status = 0 if loop.stable else 3
    if args.json:
        print(json.dumps(data, indent=2))
        return status
    print(loop.describe())
    if loop.stable:
        margin = data["disk_margin"]
        print(f"disk margin at the actuators: {margin:.4g} (at {data['disk_frequency_hz']:.4g} Hz)"
              if margin is not None else "disk margin at the actuators: unlimited")
    return status
