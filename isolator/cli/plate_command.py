"""``isolator plate-modes``: the free-free modes of a homogeneous (or honeycomb) rectangular top as the modal CSV
of ``[table.flexible]`` (``docs/scenario-format.md``, "A top that bends"), for users without a finite-element
model of their top."""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import Any

from isolator.cli.helpers import count, figure_path, output_path, save_figure, use_agg
from isolator.errors import ParameterError

__all__ = ["OPTION_NAMES", "register"]

#: how the messages name :func:`isolator.plates.plate_modes`'s arguments
OPTION_NAMES = {"size": "--size", "mass": "--mass", "young": "--young", "poisson": "--poisson", "count": "--count",
                "max_frequency": "--max-frequency", "elements": "--elements", "honeycomb": "--face-thickness",
                "model": "--model"}


def register(sub: Any) -> None:
    """Add ``isolator plate-modes`` to the ``isolator`` command's subparsers."""
    p = sub.add_parser(
        "plate-modes", help="write the free-free modes of a rectangular top (the modal CSV of [table.flexible])",
        description="Compute the free-free modes of a homogeneous rectangular top (a Kirchhoff plate with "
        "rotatory inertia, or a 3-D solid, by finite elements: scikit-fem) and write them as the modal CSV "
        "that [table.flexible] reads: the box's six rigid modes (frequency 0) and the lowest elastic ones, "
        "mass-normalised, on a grid of nodes (the plate's mid-surface with rotations, or the solid's two "
        "faces). A honeycomb top is its equivalent plate: give --face-thickness, with --young and --poisson "
        "those of the face sheets.",
    )
    p.add_argument("out", type=Path, metavar="OUT.csv", help="the modal CSV to write")
    p.add_argument("--size", required=True, metavar="LX,LY,T", help="length (x), width (y), thickness (z), m")
    p.add_argument("--mass", required=True, type=float, metavar="KG", help="the top's mass, kg")
    p.add_argument("--young", required=True, type=float, metavar="PA", help="Young's modulus, Pa")
    p.add_argument("--poisson", required=True, type=float, metavar="NU", help="Poisson's ratio, in (-1, 0.5)")
    p.add_argument("--count", type=count, default=20, metavar="N", help="elastic modes kept (default 20)")
    p.add_argument("--max-frequency", type=float, metavar="HZ", help="keep only elastic modes up to this, Hz")
    p.add_argument("--elements", type=count, metavar="N",
                   help="element divisions along the longer side (default 12)")
    p.add_argument("--face-thickness", type=float, metavar="M",
                   help="a honeycomb top: its face sheets' thickness, m (core's stiffness neglected)")
    p.add_argument("--model", choices=("plate", "solid"), default="plate",
                   help="plate: Kirchhoff bending, one layer of nodes with rotations (default; thin tops, "
                   "honeycomb); solid: 3-D elasticity, the two faces' nodes (thick tops: t over a tenth of the "
                   "shorter side, granite)")
    p.add_argument("--plot", type=Path, metavar="PNG", help="write the figure of the elastic mode shapes")
    p.set_defaults(handler=_plate_modes)


def _size(text: str) -> list[float]:
    """``LX,LY,T`` as three numbers; a :class:`ParameterError` naming ``--size`` otherwise."""
    parts = text.split(",")
    try:
        values = [float(part) for part in parts]
    except ValueError:
        values = []
    if len(values) != 3:
        raise ParameterError(f"--size: expected LX,LY,T (three numbers, m), got '{text}'")
    return values


def _plate_modes(args: argparse.Namespace) -> int:
    from isolator.plates import check_plate_arguments, plate_modes

    size = _size(args.size)
    check_plate_arguments(size, args.mass, args.young, args.poisson, args.count, args.max_frequency, args.elements,
                          args.face_thickness, model=args.model, names=OPTION_NAMES)
    out = output_path(args.out, "OUT.csv", (".csv",))
    plot = figure_path(args.plot, "--plot")
    try:
        top = plate_modes(size, args.mass, args.young, args.poisson, args.count, args.max_frequency, args.elements,
                          args.face_thickness, model=args.model)
    except ParameterError as exc:  # a top too flexible, or no mode below --max-frequency: named as an option
        message = str(exc)
        for name, option in OPTION_NAMES.items():
            if message.startswith(f"{name}:"):
                message = option + message[len(name):]
        raise ParameterError(message) from None
    temporary = None if plot is None else plot.with_name(f".{plot.stem}.{os.getpid()}.tmp{plot.suffix}")
    try:  # the figure drawn before either file is in place: a failure leaves neither
        if plot is not None and temporary is not None:
            use_agg()
            save_figure(top.plot(title=f"Elastic modes of a {size[0]:g} x {size[1]:g} x {size[2]:g} m top, "
                                 f"{args.mass:g} kg"), temporary)
        written = top.to_csv(out)
        if plot is not None and temporary is not None:
            os.replace(temporary, plot)
    finally:
        if temporary is not None:
            temporary.unlink(missing_ok=True)
    elastic = top.frequency_hz[top.elastic]
    print(f"{len(elastic)} elastic modes, {elastic[0]:.4g} to {elastic[-1]:.4g} Hz, and 6 rigid ones at "
          f"{len(top.nodes)} nodes")
    print(f"modes: {written}")
    if plot is not None:
        print(f"figure: {plot}")
    return 0
