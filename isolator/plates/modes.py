"""The free-free modes of a homogeneous rectangular top, in the modal file the scenario contract reads.

``docs/scenario-format.md``, "A top that bends": a CSV of mass-normalised free-free modes, six rigid ones
first (so the file passes the contract's check of mass and mass centre), then the elastic ones.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from isolator.errors import ParameterError
from isolator.plates.kirchhoff import bending_modes
from isolator.plates.solid import solid_modes
from isolator.scenario.arguments import check_public
from isolator.scenario.flexible.synthetic import box_rigid_modes

__all__ = ["CSV_HEADER", "MODELS", "RIGID_LIMIT_HZ", "PlateModes", "check_plate_arguments", "plate_modes",
           "rigid_modes"]

#: the contract's CSV header (without ``,rx,ry,rz`` for a file of two faces)
CSV_HEADER = "mode,frequency_hz,damping,x,y,z,ux,uy,uz,rx,ry,rz"
#: the models :func:`plate_modes` takes
MODELS = ("plate", "solid")
#: modes below this frequency are rigid motions by the contract, Hz
RIGID_LIMIT_HZ = 1.0
#: default node spacing of the written grid, per model: the longer side over this (about 300 nodes on a
#: 2:1 top, one layer or two faces)
GRID_DIVISIONS = {"plate": 24, "solid": 16}
#: default element divisions along the longer side
ELEMENTS = 12

#: how the messages name the arguments (the command line passes its options' names)
_NAMES = {k: k for k in ("size", "mass", "young", "poisson", "count", "max_frequency", "elements", "honeycomb",
                         "grid", "model")}


@dataclass(frozen=True)
class PlateModes:
    """Free-free modes of a top: six rigid ones (frequency 0) then the elastic ones, mass-normalised.

    Attributes
    ----------
    nodes : numpy.ndarray
        Node positions (N, 3), m: a grid on the mid-surface (``z = 0``), or on the bottom then the top face
        (``z = -+t/2``); the top's centre at the origin.
    frequency_hz : numpy.ndarray
        Natural frequencies (n,), Hz; the first six (rigid) are 0.
    translations : numpy.ndarray
        Mode shapes' translations (n, N, 3) at the nodes, m/sqrt(kg).
    rotations : numpy.ndarray or None
        Mode shapes' rotations (n, N, 3) at the nodes, rad/sqrt(kg), of a single layer of nodes (a point
        at height ``z`` above the mid-surface moves by ``translation + rotation x (0, 0, z)``); None for the
        two faces of a solid model.
    mass : float
        The top's mass, kg.
    size : tuple of float
        Its length (x), width (y) and thickness (z), m.
    """

    nodes: np.ndarray
    frequency_hz: np.ndarray
    translations: np.ndarray
    rotations: np.ndarray | None
    mass: float
    size: tuple[float, float, float]

    @property
    def elastic(self) -> slice:
        """The elastic modes' index range (after the six rigid ones)."""
        return slice(6, None)

    def to_csv(self, path: str | os.PathLike[str]) -> Path:
        """Write the contract's CSV (``mode,frequency_hz,damping,x,y,z,ux,uy,uz,rx,ry,rz``, damping empty;
        without the rotations for two faces) atomically: a temporary file beside ``path``, renamed when complete.

        Parameters
        ----------
        path : str or os.PathLike
            The CSV file to write.

        Returns
        -------
        pathlib.Path
            The file written.
        """
        path = Path(path)
        xyz = [_text(c) for c in self.nodes.T]
        lines = [CSV_HEADER if self.rotations is not None else CSV_HEADER.removesuffix(",rx,ry,rz")]
        for i, f in enumerate(self.frequency_hz):
            frequency = "0.0" if f < RIGID_LIMIT_HZ else _text(np.array([f]), 10)[0]
            u = [_text(c) for c in self.translations[i].T]
            r = [] if self.rotations is None else [_text(c) for c in self.rotations[i].T]
            lines.extend(f"{i + 1},{frequency},," + ",".join(row) for row in zip(*xyz, *u, *r, strict=True))
        temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        try:
            temporary.write_text("\n".join(lines) + "\n", encoding="ascii")
            os.replace(temporary, path)
        finally:
            temporary.unlink(missing_ok=True)
        return path

    def plot(self, isolators: Any = None, feet: Any = None, title: str | None = None) -> Any:
        """The elastic mode shapes' figure (:func:`isolator.plates.plot_mode_shapes`).

        Parameters
        ----------
        isolators, feet : array_like, optional
            (x, y) positions to mark, m.
        title : str, optional
            The figure's title.

        Returns
        -------
        matplotlib.figure.Figure
            The figure.
        """
        from isolator.plates.figure import plot_mode_shapes

        e = self.elastic
        return plot_mode_shapes(self.nodes, self.translations[e], self.frequency_hz[e], isolators=isolators,
                                feet=feet, title=title)


def _text(values: np.ndarray, digits: int = 7) -> list[str]:
    """Numbers as short CSV text (exact zeros as ``0``)."""
    return [f"{v:.{digits}g}" if v else "0" for v in np.asarray(values, dtype=float)]


def check_plate_arguments(size: Any, mass: Any, young: Any, poisson: Any, count: Any = 20, max_frequency: Any = None,
                          elements: Any = None, honeycomb: Any = None, grid: Any = None, model: Any = "plate",
                          names: Mapping[str, str] | None = None) -> None:
    """Refuse a bad argument of :func:`plate_modes` with one :class:`~isolator.errors.ParameterError`.

    Parameters
    ----------
    size, mass, young, poisson, count, max_frequency, elements, honeycomb, grid, model
        As :func:`plate_modes` takes them.
    names : mapping of str to str, optional
        How the message names each argument (the command line gives its options' names).
    """
    key = {**_NAMES, **(names or {})}
    if model not in MODELS:
        raise ParameterError(f"{key['model']}: must be one of {', '.join(MODELS)}, got {model!r}")
    sizes = _numbers(size, 3, key["size"], "LX,LY,T")
    if any(s <= 0 for s in sizes):
        raise ParameterError(f"{key['size']}: every entry must be positive, m; got {_listed(sizes)}")
    _positive(mass, key["mass"], "kg")
    _positive(young, key["young"], "Pa")
    nu = _number(poisson, key["poisson"])
    if not -1.0 < nu < 0.5:
        raise ParameterError(f"{key['poisson']}: must lie between -1 and 0.5 (both excluded), got {nu:g}")
    _whole(count, key["count"], 1)
    if max_frequency is not None:
        _positive(max_frequency, key["max_frequency"], "Hz")
    if elements is not None:
        _whole(elements, key["elements"], 2)
    if honeycomb is not None:
        face = _positive(honeycomb, key["honeycomb"], "m")
        if model != "plate":
            raise ParameterError(f"{key['honeycomb']}: a honeycomb top is an equivalent plate: only with the "
                                 f"plate model, not {model!r}")
        if face >= sizes[2] / 2:
            raise ParameterError(f"{key['honeycomb']}: a face sheet must be thinner than half the thickness "
                                 f"{sizes[2]:g} m, got {face:g} m")
    if grid is not None:
        points = _numbers(grid, 2, key["grid"], "NX,NY")
        if any(p != int(p) or p < 2 for p in points):
            raise ParameterError(f"{key['grid']}: two whole numbers of nodes >= 2, got {_listed(points)}")


def _number(value: Any, name: str) -> float:
    if isinstance(value, bool):
        raise ParameterError(f"{name}: must be a number, got {value!r}")
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name}: must be a number, got {value!r}") from None
    if not math.isfinite(number):
        raise ParameterError(f"{name}: must be finite, got {number:g}")
    return number


def _positive(value: Any, name: str, unit: str) -> float:
    number = _number(value, name)
    if number <= 0:
        raise ParameterError(f"{name}: must be positive, {unit}; got {number:g}")
    return number


def _whole(value: Any, name: str, least: int) -> int:
    number = _number(value, name)
    if number != int(number) or number < least:
        raise ParameterError(f"{name}: must be a whole number >= {least}, got {number:g}")
    return int(number)


def _numbers(value: Any, n: int, name: str, form: str) -> list[float]:
    if isinstance(value, str) or not isinstance(value, Sequence | np.ndarray) or len(value) != n:
        raise ParameterError(f"{name}: must be {n} numbers ({form}), got {value!r}")
    return [_number(v, name) for v in value]


def _listed(values: Sequence[float]) -> str:
    return "[" + ", ".join(f"{v:g}" for v in values) + "]"


def rigid_modes(nodes: np.ndarray, mass: float, size: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """The six mass-normalised rigid modes of a homogeneous box centred at the origin, at ``nodes``.

    Translations ``e_k / sqrt(m)``; rotations about the principal axes ``w = e_k / sqrt(I_k)`` with
    ``I_x = m (ly^2 + t^2) / 12`` (and so on), moving a node ``p`` by ``w x p``.

    Parameters
    ----------
    nodes : numpy.ndarray
        Positions (N, 3), m.
    mass : float
        The box's mass, kg.
    size : sequence of float
        Its sides ``(lx, ly, t)``, m.

    Returns
    -------
    tuple of numpy.ndarray
        Translations (6, N, 3), m/sqrt(kg), and rotations (6, N, 3), rad/sqrt(kg).

    Examples
    --------
    >>> import numpy as np
    >>> u, r = rigid_modes(np.array([[1.0, 0.0, 0.0]]), 12.0, (2.0, 1.0, 1.0))
    >>> u[5, 0]  # a turn about z moves (1, 0, 0) along y: 1 / sqrt(12 (4 + 1) / 12)
    array([0.        , 0.4472136, 0.       ])
    """
    lx, ly, t = size
    inertia = mass / 12.0 * np.array([ly**2 + t**2, lx**2 + t**2, lx**2 + ly**2])
    return box_rigid_modes(np.asarray(nodes, dtype=float), mass, inertia, np.zeros(3))


def plate_modes(size: Sequence[float], mass: float, young: float, poisson: float, count: int = 20,
                max_frequency: float | None = None, elements: int | None = None, honeycomb: float | None = None,
                grid: Sequence[int] | None = None, model: str = "plate") -> PlateModes:
    """The free-free modes of a homogeneous rectangular top, as the scenario contract's modal file holds them.

    Two models, by finite elements (scikit-fem):

    - ``"plate"`` (default): a Kirchhoff plate (thin-plate bending) with the sections' rotatory inertia, on
      quintic C1 Argyris triangles (:mod:`isolator.plates.kirchhoff`), written as one layer of nodes (the
      mid-surface, ``z = 0``) with rotations, the contract's single-layer form (faces ``u + theta x (0, 0,
      +-t/2)``). A top is a plate: its modes within a controller's reach are bending and twisting ones, and
      this is exact for thin tops and a honeycomb's equivalent plate, and fast. Shear deformation is left
      out, so a thick top comes out stiff: a granite block of thickness 0.3 of its width has its twisting
      mode some 13 % high, its first bending mode 3 %, and misses its in-plane modes.
    - ``"solid"``: 3-D linear elasticity on triquadratic hexahedra (:mod:`isolator.plates.solid`), written as
      the top and bottom faces' nodes (translations only, the contract's two-face form). Every mode of a
      thick block (shear through the thickness, in-plane modes) is there; use it when ``t`` exceeds about a
      tenth of the shorter side. Slower (seconds), and not for thin plates (elements far flatter than long).

    The six rigid modes written are the exact ones of the homogeneous box (mass ``m``, inertia of a uniform
    box of the three sides, centre at the origin), which both models' mass matrices contain (the plate's
    through its rotatory inertia), so the elastic modes are mass-orthogonal to them: the table's mean axes.
    Each elastic mode's sign makes its first large translation (in the nodes' order, x, y, z at each, the
    first over a tenth of the largest) positive, a rule that survives the rounding of symmetric tops.

    Parameters
    ----------
    size : sequence of float
        Length (x), width (y) and thickness (z) of the top, m.
    mass : float
        The top's mass, kg (spread evenly).
    young : float
        Young's modulus, Pa: of the material, or with ``honeycomb`` of the face sheets.
    poisson : float
        Poisson's ratio (of the face sheets with ``honeycomb``), in (-1, 0.5).
    count : int, optional
        Elastic modes kept, the lowest (default 20).
    max_frequency : float, optional
        Keep only elastic modes up to this frequency, Hz.
    elements : int, optional
        Element divisions along the longer side (default 12; the other sides in proportion).
    honeycomb : float, optional
        ``"plate"`` only: a honeycomb (sandwich) top's face-sheet thickness, m: its equivalent plate has the
        two face sheets' rigidity ``D = E / (1 - nu^2) (tf^3 / 6 + tf (t - tf)^2 / 2)`` (the core's bending
        stiffness and its shear flexibility neglected, so its frequencies are upper bounds: a real core's
        shear lowers them, most for the higher modes) and ``mass`` (faces and core) spread evenly.
    grid : sequence of int, optional
        Nodes written along x and y on each layer (default: the longer side in 24 intervals for the
        plate, 16 for the solid's two faces, the shorter side at that spacing).
    model : {"plate", "solid"}, optional
        The model, above (default "plate").

    Returns
    -------
    PlateModes
        Six rigid modes and the elastic ones at a grid of nodes.

    Raises
    ------
    ParameterError
        A bad argument (named), or a top so flexible that an elastic mode falls below 1 Hz (it would be
        taken for a rigid one).

    Examples
    --------
    >>> top = plate_modes((2.0, 1.0, 0.3), 4400.0, 50e9, 0.25, count=4)
    >>> top.frequency_hz.round(1)
    array([  0. ,   0. ,   0. ,   0. ,   0. ,   0. , 193.2, 242.5, 509.2, 517.3])
    >>> top.translations.shape
    (10, 325, 3)
    """
    check_plate_arguments(size, mass, young, poisson, count, max_frequency, elements, honeycomb, grid, model)
    lx, ly, t = (float(s) for s in size)
    nx, ny = (int(g) for g in grid) if grid is not None else _grid(lx, ly, GRID_DIVISIONS[model])
    x, y = (a.ravel() for a in np.meshgrid(np.linspace(-lx / 2, lx / 2, nx), np.linspace(-ly / 2, ly / 2, ny)))
    divisions = int(elements or ELEMENTS)
    if model == "solid":
        solid = solid_modes(lx, ly, t, mass, young, poisson, int(count), divisions)
        frequency_hz = solid.frequency_hz
        nodes = np.concatenate([np.column_stack([x, y, np.full(x.size, z)]) for z in (-t / 2, t / 2)])
        elastic_u, elastic_r = solid.evaluate(nodes), None
    else:
        rigidity = young * t**3 / (12.0 * (1.0 - poisson**2)) if honeycomb is None else (
            young / (1.0 - poisson**2) * (honeycomb**3 / 6.0 + honeycomb * (t - honeycomb) ** 2 / 2.0))
        bending = bending_modes(lx, ly, t, mass, rigidity, poisson, int(count), divisions)
        frequency_hz = bending.frequency_hz
        nodes = np.column_stack([x, y, np.zeros(x.size)])
        w, dwdx, dwdy = bending.evaluate(x, y)
        elastic_u = np.stack([np.zeros_like(w), np.zeros_like(w), w], axis=-1)
        # u = w e_z + theta x (0, 0, z) = (-z w_x, -z w_y, w) (Kirchhoff): theta = (w_y, -w_x, 0)
        elastic_r = np.stack([dwdy, -dwdx, np.zeros_like(w)], axis=-1)
    if frequency_hz[0] < RIGID_LIMIT_HZ:
        raise ParameterError(f"size: the first elastic mode is at {frequency_hz[0]:.3g} Hz, below "
                             f"{RIGID_LIMIT_HZ:g} Hz where modal files hold rigid modes only: the top is too flexible")
    kept = np.arange(int(count))
    if max_frequency is not None:
        kept = kept[frequency_hz[kept] <= max_frequency]
        if not kept.size:
            raise ParameterError(f"max_frequency: no elastic mode up to {max_frequency:g} Hz (the first is at "
                                 f"{frequency_hz[0]:.4g} Hz)")
    sign = np.array([_sign(elastic_u[i]) for i in kept])[:, None, None]
    rigid_u, rigid_r = rigid_modes(nodes, mass, (lx, ly, t))
    rotations = None if elastic_r is None else np.concatenate([rigid_r, sign * elastic_r[kept]])
    return PlateModes(nodes, np.concatenate([np.zeros(6), frequency_hz[kept]]),
                      np.concatenate([rigid_u, sign * elastic_u[kept]]), rotations, float(mass), (lx, ly, t))


def _sign(translations: np.ndarray) -> float:
    """+1 or -1: the sign that makes a mode's first translation over a tenth of its largest positive."""
    flat = translations.ravel()
    return float(np.sign(flat[np.argmax(np.abs(flat) > 0.1 * np.abs(flat).max())]) or 1.0)


def _grid(lx: float, ly: float, divisions: int) -> tuple[int, int]:
    """Nodes along x and y: the longer side in ``divisions``, the shorter at that spacing (at least 3 nodes)."""
    spacing = max(lx, ly) / divisions
    return max(3, round(lx / spacing) + 1), max(3, round(ly / spacing) + 1)


check_public(globals())
