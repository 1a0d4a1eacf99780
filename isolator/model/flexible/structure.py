"""What a top that bends adds to a model's structure: the kept modes and their shapes where things touch the top.

:class:`ElasticStructure` holds, as plain numbers, everything the equations need from the modal data of
``[table.flexible]`` (``docs/scenario-format.md``, "A top that bends"): the kept elastic modes' natural
frequencies and damping ratios, the elastic translation per unit modal coordinate at each isolator's and
actuator's attachment point, and, for each carriage riding the top, its feet's mean translation along its
travel as a Chebyshev series in the carriage's coordinate (so that the equations, written in casadi, have it
and its first two derivatives exactly). It is part of :class:`~isolator.model.parameters.ParameterLayout`, so
a model is built (and compiled) once per structure; a rigid top has none and pays nothing.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.polynomial import chebyshev

from isolator.errors import ScenarioError
from isolator.scenario.definitions import Scenario

__all__ = ["CarriageShape", "ElasticStructure", "feet_translation", "point_shape"]

#: how closely the Chebyshev series of a carriage's feet translation follows the interpolated shapes (relative
#: to the largest translation of the modes along the travel): the interpolant is C1 and piecewise cubic, so a
#: series converges slowly past this; the finite-element shapes themselves are no closer
FIT_TOLERANCE = 1e-4
#: the highest degree tried for that series
MAX_DEGREE = 48
#: samples along a carriage's line on which the reach of its feet over the face is searched, per metre
_SCAN_PER_METRE = 2000


def feet_translation(data: Any, position: np.ndarray, feet: tuple[tuple[float, float], ...] | None,
                     what: str) -> np.ndarray:
    """The mean elastic translation of a thing's feet per unit of each modal coordinate, (3, modes), in the modal
    file's units (mass-normalised: m/sqrt(kg)); :meth:`ModalData.point_translation` transposed.

    Parameters
    ----------
    data : ModalData
        The kept modes (:mod:`isolator.scenario.flexible`).
    position : ndarray (3,)
        Where the thing stands on the top, table frame [m]; its height picks the face.
    feet : tuple of (x, y) or None
        Offsets of its feet from ``position`` [m] (None: one foot at ``position``).
    what : str
        The thing, for errors (a foot off the face).
    """
    return np.ascontiguousarray(np.asarray(data.point_translation(position, feet, what), dtype=float).T)


def point_shape(table: Any, position: Any, feet: Any, what: str) -> np.ndarray | None:
    """The elastic translation of a point fixed to the top per unit modal coordinate (3, modes), table frame
    (:func:`feet_translation` of ``table.flexible``'s modes); None on a rigid top."""
    flexible = getattr(table, "flexible", None)
    if flexible is None:
        return None
    feet = None if feet is None else tuple((float(f[0]), float(f[1])) for f in feet)
    return _point_shape(flexible, tuple(float(v) for v in position), feet, what).copy()


@lru_cache(maxsize=256)
def _point_shape(flexible: Any, position: tuple[float, ...], feet: tuple[tuple[float, float], ...] | None,
                 what: str) -> np.ndarray:
    """:func:`point_shape`, made once per top and point (every run places the scenario's points)."""
    return feet_translation(flexible.data, np.asarray(position, dtype=float), feet, what)


@dataclass(frozen=True)
class CarriageShape:
    """The mean translation of a carriage's feet along its travel: ``Psi(q) = sum_k C_k T_k(s)``,
    ``s = (2 q - lo - hi) / (hi - lo)``.

    Attributes
    ----------
    root : int
        The carriage riding the top whose coordinate ``q`` moves the feet (the carriage itself, or the ancestor
        whose parent is the table).
    domain : tuple of float
        ``(lo, hi)`` [m]: the stretch of ``q`` over which every foot is on the face (the series' interval).
    coefficients : tuple of float
        ``C`` of shape (degree + 1, 3, modes), flattened.
    """

    root: int
    domain: tuple[float, float]
    coefficients: tuple[float, ...]

    def array(self, n_modes: int) -> np.ndarray:
        """The coefficients (degree + 1, 3, modes)."""
        return np.asarray(self.coefficients, dtype=float).reshape(-1, 3, n_modes)

    def values(self, q: np.ndarray, n_modes: int) -> np.ndarray:
        """``Psi`` (N, 3, modes) at coordinates ``q`` (N,) [m]."""
        lo, hi = self.domain
        s = (2.0 * np.asarray(q, dtype=float) - lo - hi) / (hi - lo)
        return np.moveaxis(chebyshev.chebval(s, self.array(n_modes)), -1, 0)

    def series(self, n_modes: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The series of ``Psi``, ``dPsi/dq`` and ``d2Psi/dq2`` in ``s``, each (degree + 1, 3, modes)
        (``numpy.polynomial.chebyshev.chebder``, a zero series where the degree is too low; made once)."""
        return _series(self, n_modes)

    def along(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, n_modes: int
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``Psi``, ``dPsi/dt = Psi_q q'`` and ``d2Psi/dt2 = Psi_qq q'^2 + Psi_q q''``, each (N, 3, modes), at
        coordinates ``q`` (N,) [m] moving at ``qd`` [m/s] and ``qdd`` [m/s^2]: the series of :meth:`series` summed
        through one Chebyshev-Vandermonde matrix (the sums the equations' Clenshaw recurrence makes)."""
        lo, hi = self.domain
        s = (2.0 * np.asarray(q, dtype=float) - lo - hi) / (hi - lo)
        out, vander = [], chebyshev.chebvander(s, self.array(n_modes).shape[0] - 1)
        for series in self.series(n_modes):
            out.append((vander[:, : series.shape[0]] @ series.reshape(series.shape[0], -1)).reshape(-1, 3, n_modes))
        psi, first, second = out
        qd, qdd = np.asarray(qd, dtype=float)[:, None, None], np.asarray(qdd, dtype=float)[:, None, None]
        return psi, first * qd, second * qd * qd + first * qdd


@lru_cache(maxsize=64)
def _series(shape: CarriageShape, n_modes: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    lo, hi = shape.domain
    coeffs, scale = shape.array(n_modes), 2.0 / (hi - lo)
    first = chebyshev.chebder(coeffs, 1, scl=scale) if coeffs.shape[0] > 1 else np.zeros((1, 3, n_modes))
    second = chebyshev.chebder(coeffs, 2, scl=scale) if coeffs.shape[0] > 2 else np.zeros((1, 3, n_modes))
    for array in (coeffs, first, second):
        array.setflags(write=False)
    return coeffs, first, second


@dataclass(frozen=True)
class ElasticStructure:
    """The numbers a model of a bending top is built with (hashable; equal for the same modes and geometry).

    Attributes
    ----------
    digest : str
        Of the modal data and the geometry the shapes were taken at (names the compiled code).
    frequencies, damping : tuple of float
        Natural frequencies [Hz] and damping ratios of the kept elastic modes.
    isolators, actuators : tuple of tuple of float
        The elastic translation at each attachment point per unit modal coordinate, (3, modes) flattened.
    carriages : tuple of CarriageShape
        One per carriage (a carriage on a carriage rides its table-level ancestor's feet).
    source : FlexibleTop
        The scenario's ``[table.flexible]`` the numbers come from (for shapes at other points; not compared).
    """

    digest: str
    frequencies: tuple[float, ...]
    damping: tuple[float, ...]
    isolators: tuple[tuple[float, ...], ...]
    actuators: tuple[tuple[float, ...], ...]
    carriages: tuple[CarriageShape, ...]
    source: Any = field(default=None, compare=False, hash=False, repr=False)

    def __hash__(self) -> int:
        """The digest's (the structure keys every cache of a model, and its shapes are long)."""
        return hash(self.digest)

    def shape_at(self, position: Any, feet: Any = None, what: str = "point") -> np.ndarray:
        """The elastic translation per modal coordinate (3, modes) of a point fixed to the top at ``position``
        (table frame) [m], the mean over its ``feet``."""
        return feet_translation(self.source.data, np.asarray(position, dtype=float), feet, what)

    @property
    def n_modes(self) -> int:
        return len(self.frequencies)

    def shape_matrix(self, flat: tuple[float, ...]) -> np.ndarray:
        """A flattened (3, modes) shape as an array."""
        return np.asarray(flat, dtype=float).reshape(3, self.n_modes)

    @property
    def roots(self) -> tuple[int, ...]:
        """The carriages whose coordinates move feet over the top, in order."""
        return tuple(sorted({c.root for c in self.carriages}))

    @classmethod
    def of(cls, scenario: Scenario) -> ElasticStructure | None:
        """The structure of a scenario's bending top (None for a rigid top).

        Raises
        ------
        ScenarioError
            A foot off the top's face anywhere along a carriage's travel, naming the carriage.
        """
        flexible = getattr(scenario.table, "flexible", None)
        if flexible is None:
            return None
        carriages = tuple((c.parent, tuple(c.axis), tuple(c.origin), _feet_of(c), c.name, (float(lo), float(hi)))
                          for c, (lo, hi) in zip(scenario.carriages, scenario.travel(), strict=True))
        return _build(flexible, tuple(tuple(iso.position) for iso in scenario.isolators),
                      tuple(tuple(act.position) for act in scenario.actuators), carriages)


def _feet_of(thing: Any) -> tuple[tuple[float, float], ...] | None:
    feet = getattr(thing, "feet", None)
    return None if feet is None else tuple((float(f[0]), float(f[1])) for f in feet)


@lru_cache(maxsize=16)
def _build(flexible: Any, isolators: tuple, actuators: tuple, carriages: tuple) -> ElasticStructure:
    data = flexible.data
    names = [c[4] for c in carriages]
    iso = tuple(tuple(feet_translation(data, np.array(p), None, f"isolators[{k}].position").ravel())
                for k, p in enumerate(isolators))
    act = tuple(tuple(feet_translation(data, np.array(p), None, f"actuators[{k}].position").ravel())
                for k, p in enumerate(actuators))
    shapes: dict[int, CarriageShape] = {}
    parents = [-1 if c[0] == "table" else names.index(c[0]) for c in carriages]
    for i, (_, axis, origin, feet, name, travel) in enumerate(carriages):
        if parents[i] == -1:
            shapes[i] = _carriage_shape(data, i, np.array(axis), np.array(origin), feet,
                                        f"carriages[{i}] ({name}).feet", travel)
    out = []
    for i in range(len(carriages)):
        root = i
        while parents[root] != -1:
            root = parents[root]
        out.append(shapes[root])
    geometry = (data.digest, isolators, actuators, [c[:4] for c in carriages], [s.domain for s in out])
    digest = hashlib.sha256(repr(geometry).encode()).hexdigest()[:16]
    return ElasticStructure(digest, tuple(float(f) for f in data.frequencies), tuple(float(z) for z in data.damping),
                            iso, act, tuple(out), flexible)


def _carriage_shape(data: Any, index: int, axis: np.ndarray, origin: np.ndarray,
                    feet: tuple[tuple[float, float], ...] | None, what: str,
                    travel: tuple[float, float]) -> CarriageShape:
    """Fit the feet's mean translation along the carriage's line over the stretch where every foot is on the
    face; the travel must lie inside it."""
    face = data.face_for(float(origin[2]))
    offsets = np.zeros((1, 2)) if not feet else np.asarray(feet, dtype=float)
    reach = 2.0 * float(np.max(np.abs(data.nodes[:, :2]))) + float(np.max(np.abs(offsets), initial=0.0)) + 1.0
    direction = axis[:2]
    if np.linalg.norm(direction) < 1e-12:  # moves vertically: the feet stay where they are
        lo, hi = travel[0] - 1.0, travel[1] + 1.0
    else:
        q = np.linspace(-reach, reach, int(2 * reach * _SCAN_PER_METRE) + 1)
        inside = np.ones(q.size, dtype=bool)
        for off in offsets:
            xy = origin[None, :2] + direction[None, :] * q[:, None] + off[None, :]
            inside &= np.asarray(data.inside(xy, face), dtype=bool)
        start = int(np.argmin(np.abs(q - 0.5 * (travel[0] + travel[1]))))
        if not inside[start]:
            _off_face(what, travel)
        left, right = start, start
        while left > 0 and inside[left - 1]:
            left -= 1
        while right < q.size - 1 and inside[right + 1]:
            right += 1
        lo, hi = float(q[left]), float(q[right])
        if travel[0] < lo - 1e-9 or travel[1] > hi + 1e-9:
            _off_face(what, travel, (lo, hi))
    if hi - lo < 1e-9:
        _off_face(what, travel)
    nodes = np.cos(np.pi * (np.arange(2 * MAX_DEGREE + 1) + 0.5) / (2 * MAX_DEGREE + 1))[::-1]
    q_nodes = 0.5 * (lo + hi) + 0.5 * (hi - lo) * nodes
    values = _line_shape(data, face, origin, axis, offsets, q_nodes, what)  # (N, 3, n)
    scale = max(float(np.max(np.abs(values))), 1e-300)
    check = np.linspace(-1.0, 1.0, 4 * MAX_DEGREE + 1)
    check_values = _line_shape(data, face, origin, axis, offsets, 0.5 * (lo + hi) + 0.5 * (hi - lo) * check, what)
    for degree in range(4, MAX_DEGREE + 1, 4):
        coeffs = chebyshev.chebfit(nodes, values.reshape(nodes.size, -1), degree)
        fitted = chebyshev.chebval(check, coeffs).T.reshape(check_values.shape)
        if np.max(np.abs(fitted - check_values)) <= FIT_TOLERANCE * scale:
            break
    n = values.shape[2]
    return CarriageShape(index, (lo, hi), tuple(coeffs.reshape(-1, 3, n).ravel().tolist()))


def _line_shape(data: Any, face: str, origin: np.ndarray, axis: np.ndarray, offsets: np.ndarray, q: np.ndarray,
                what: str) -> np.ndarray:
    """The feet's mean translation (N, 3, modes) with the carriage at coordinates ``q`` (N,)."""
    xy = origin[None, None, :2] + axis[None, None, :2] * q[:, None, None] + offsets[None, :, :]  # (N, feet, 2)
    shapes = np.asarray(data.translation(xy.reshape(-1, 2), face, what), dtype=float)  # (N feet, n, 3)
    return np.swapaxes(shapes.reshape(q.size, offsets.shape[0], *shapes.shape[1:]).mean(axis=1), 1, 2)


def _off_face(what: str, travel: tuple[float, float], on: tuple[float, float] | None = None) -> None:
    where = f"; its feet stay on the top for q in [{on[0]:.4g}, {on[1]:.4g}] m" if on is not None else ""
    raise ScenarioError(f"{what}: a foot leaves the top's face along the carriage's travel "
                        f"(q from {travel[0]:.4g} to {travel[1]:.4g} m){where}")
