"""``isolator fmu``: the table as an FMI 2.0 FMU (Model Exchange and Co-Simulation) for Simulink, Modelica tools,
FMPy or a hardware-in-the-loop rig (``docs/scenario-format.md``, "The table as an FMU")."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from isolator.cli.helpers import output_path, scenario_argument
from isolator.errors import ParameterError
from isolator.scenario.names import escaped
from isolator.scenario.reader import load_scenario

__all__ = ["parse_sets", "register"]


def register(sub: Any) -> None:
    """Add ``isolator fmu`` to the ``isolator`` command's subparsers."""
    p = sub.add_parser(
        "fmu", help="export the table as an FMI 2.0 FMU (Model Exchange and Co-Simulation)",
        description="Write the scenario's table as one FMI 2.0 FMU with both interfaces: inputs f:<actuator> "
        "(commands, clipped and lagged as in the simulation), floor:x/y/z and floor:vx/vy/vz, with "
        "--carriages inputs q:/v:/a:<carriage>; outputs x, y, z, rx, ry, rz, s:<sensor>, <point>:x/y/z; the "
        "--parameters as FMU parameters. It starts at the static equilibrium of its parameters' values; "
        "a binary for this platform and the C sources are inside. Needs a C compiler.",
    )
    scenario_argument(p)
    p.add_argument("--out", type=Path, required=True, metavar="FILE.fmu", help="the FMU to write")
    p.add_argument("--carriages", choices=("profiles", "inputs"), default="profiles",
                   help="the carriages move by the scenario's profiles (default) or by inputs q:, v:, a:<carriage>")
    p.add_argument("--parameters", default="", metavar="NAME,...",
                   help="parameters of the FMU, named as isolator sweep --set takes them "
                   "(isolators[*].stiffness.z: one value for every isolator; isolators[0].stiffness.z)")
    p.add_argument("--set", action="append", default=[], dest="sets", metavar="NAME=VALUE",
                   help="change a value before exporting (as isolator sweep --set names it); repeat for more")
    p.set_defaults(handler=_fmu)


def parse_sets(texts: list[str], option: str = "--set") -> dict[str, float]:
    """``NAME=VALUE`` texts as a mapping; a :class:`ParameterError` naming ``option`` for a malformed one."""
    out: dict[str, float] = {}
    for text in texts:
        name, sep, value = text.partition("=")
        try:
            number = float(value)
        except ValueError:
            number = math.nan
        if not sep or not name.strip() or not math.isfinite(number):
            raise ParameterError(f"{option}: expected NAME=VALUE with a finite number, got {text!r}")
        out[name.strip()] = number
    return out


def _fmu(args: argparse.Namespace) -> int:
    from isolator.fmu import write_fmu

    out = output_path(args.out, "--out", (".fmu",))
    scenario = load_scenario(args.scenario)
    names = [n.strip() for n in args.parameters.split(",") if n.strip()]
    written = write_fmu(scenario, out, args.carriages, names, parse_sets(args.sets),
                        keys={"out": "--out", "parameters": "--parameters", "changes": "--set"})
    print(f"wrote {escaped(written)}")
    return 0
