"""The bending top's dataclasses: the modal data as read and checked (:class:`ModalData`) and the scenario's
``[table.flexible]`` (:class:`FlexibleTop`)."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from isolator.errors import ParameterError, ScenarioError
from isolator.scenario.flexible.faces import FACES, TOLERANCE, FaceInterpolant, check_face, face_nodes, face_values
from isolator.scenario.flexible.faces import is_single_layer as _single
from isolator.scenario.flexible.rigid_check import RigidCheck
from isolator.scenario.names import escaped

__all__ = ["FlexibleTop", "ModalData"]


def _frozen(value: Any, shape: tuple[int | None, ...], name: str, where: str) -> np.ndarray:
    """``value`` as a read-only float array of ``shape`` (None: any length), finite; else a ScenarioError."""
    array = np.array(value, dtype=float)
    if array.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, array.shape, strict=True)):
        want = "(" + ", ".join("n" if s is None else str(s) for s in shape) + ")"
        raise ScenarioError(f"{where}: {name} must have the shape {want}, got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ScenarioError(f"{where}: {name} must be finite (found NaN or infinity)")
    array.setflags(write=False)
    return array


@dataclass(frozen=True, eq=False)
class ModalData:
    """The free-free elastic modes of the top kept from a modal file, checked (arrays read-only).

    Equal, and hashed, by a digest of the arrays (not by ``path``). Read one with
    :func:`~isolator.scenario.flexible.load_modal_data`.

    Attributes
    ----------
    path : str
        The file, as messages show it.
    frequencies : ndarray, shape (n,)
        The kept elastic modes' natural frequencies, ascending, >= 1 Hz [Hz].
    damping : ndarray, shape (n,)
        Their viscous damping ratios (the file's, else ``table.flexible.damping``).
    nodes : ndarray, shape (N, 3)
        The nodes in the table frame (the file's origin at ``table.flexible.origin``) [m].
    translations : ndarray, shape (n, N, 3)
        Mass-normalised translations (``phi^T M phi = 1``) [m/sqrt(kg)].
    rotations : ndarray, shape (n, N, 3) or None
        Mass-normalised rotations [rad/sqrt(kg)], if the file gives them.
    thickness : float
        The top's thickness (``[table] size`` z; the faces of a single layer lie +-t/2 from it) [m].
    rigid : RigidCheck or None
        The mass, mass centre and inertia the file's six rigid modes give; None when it has none.
    labels : tuple of str
        Each node's name in messages (``node 17``), default its position in the file.
    """

    path: str
    frequencies: np.ndarray
    damping: np.ndarray
    nodes: np.ndarray
    translations: np.ndarray
    rotations: np.ndarray | None
    thickness: float
    rigid: RigidCheck | None = None
    labels: tuple[str, ...] = ()
    _digest: str = field(init=False, repr=False)
    _faces: dict[str, FaceInterpolant] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        where = f"'{escaped(self.path, 120)}'"
        frequencies = _frozen(self.frequencies, (None,), "frequencies", where)
        n = frequencies.size
        if n == 0:
            raise ScenarioError(f"{where}: no elastic mode (a mode of 1 Hz or more) to keep")
        nodes = _frozen(self.nodes, (None, 3), "nodes", where)
        values = {"frequencies": frequencies, "nodes": nodes,
                  "damping": _frozen(self.damping, (n,), "damping", where),
                  "translations": _frozen(self.translations, (n, len(nodes), 3), "translations", where),
                  "rotations": None if self.rotations is None else
                  _frozen(self.rotations, (n, len(nodes), 3), "rotations", where)}
        for name, value in values.items():
            object.__setattr__(self, name, value)
        if self.labels and len(self.labels) != len(nodes):
            raise ScenarioError(f"{where}: {len(self.labels)} labels for {len(nodes)} nodes")
        single = _single(nodes)
        if single and self.rotations is None:
            raise ScenarioError(f"{where}: its nodes form a single layer (all within 1 mm of z = "
                                f"{nodes[0, 2]:.6g} m, a shell's mid-surface) but it gives no rotations "
                                "(rx, ry, rz): the faces of a single layer need them")
        if single and not (np.isfinite(self.thickness) and self.thickness > 0):
            raise ScenarioError(f"{where}: a single layer of nodes needs the top's thickness ([table] size z), "
                                f"got {self.thickness}")
        for face in FACES:
            check_face(nodes, face, where, self.labels)
        digest = hashlib.sha256()
        for array in (frequencies, values["damping"], nodes, values["translations"], values["rotations"]):
            digest.update(b"none" if array is None else repr(array.shape).encode() + array.tobytes())
        digest.update(repr(float(self.thickness)).encode())
        object.__setattr__(self, "_digest", digest.hexdigest())
        object.__setattr__(self, "_faces", {})

    @property
    def n_modes(self) -> int:
        """The number of kept elastic modes."""
        return int(self.frequencies.size)

    @property
    def digest(self) -> str:
        """The SHA-256 of the arrays and the thickness (hex): equal data, equal digest."""
        return self._digest

    def __eq__(self, other: object) -> bool:
        return isinstance(other, ModalData) and other.digest == self.digest

    def __hash__(self) -> int:
        return hash(self._digest)

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        state["_faces"] = {}  # the interpolants are built again where they are used
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)

    def face_for(self, z: float) -> str:
        """``"top"`` if ``z`` (table frame) [m] lies above the mid-height of the nodes, else ``"bottom"``."""
        mid = 0.5 * (float(self.nodes[:, 2].max()) + float(self.nodes[:, 2].min()))
        return "top" if float(z) > mid else "bottom"

    def _face(self, face: str) -> FaceInterpolant:
        if face not in FACES:
            raise ParameterError(f"face: must be 'top' or 'bottom', got {escaped(repr(face), 40)}")
        if face not in self._faces:
            xy = self.nodes[face_nodes(self.nodes, face), :2]
            values = face_values(self.translations, self.rotations, self.nodes, self.thickness, face)
            self._faces[face] = FaceInterpolant(xy, values)
        return self._faces[face]

    def inside(self, xy: Any, face: str) -> np.ndarray:
        """Whether each point ``(x, y)`` [m] (k, 2) lies on the face: within 1 mm of its nodes' outline; (k,)."""
        return self._face(face).nearest(_points(xy))[1] <= TOLERANCE

    def translation(self, xy: Any, face: str, what: str) -> np.ndarray:
        """Each kept mode's translation of the face at points of the top, C1 interpolation.

        Parameters
        ----------
        xy : array_like, shape (k, 2)
            The points in the table frame [m].
        face : {"top", "bottom"}
        what : str
            What the points are, named in errors (``carriages[0] (x-stage).feet[1]``).

        Returns
        -------
        ndarray, shape (k, n, 3)
            [m/sqrt(kg)]

        Raises
        ------
        ScenarioError
            A point farther than 1 mm outside the face's nodes, naming ``what`` and the point.
        """
        points = _points(xy)
        interpolant = self._face(face)
        _, distance = interpolant.nearest(points)
        far = np.flatnonzero(distance > TOLERANCE)
        if far.size:
            k = int(far[0])
            box = self.nodes[face_nodes(self.nodes, face), :2]
            lo, hi = box.min(axis=0), box.max(axis=0)
            raise ScenarioError(
                f"{what}: (x, y) = ({points[k, 0]:.4g}, {points[k, 1]:.4g}) m lies {distance[k] * 1e3:.4g} mm "
                f"outside the {face} face of the top's nodes in '{escaped(self.path, 120)}' (x {lo[0]:.4g} to "
                f"{hi[0]:.4g} m, y {lo[1]:.4g} to {hi[1]:.4g} m; within 1 mm of their outline needed)")
        return interpolant(points).reshape(len(points), self.n_modes, 3)

    def point_translation(self, position: Any, feet: Any, what: str) -> np.ndarray:
        """Each mode's elastic translation of a thing standing on the top at ``position`` (table frame) [m]: the
        mean over its ``feet`` ((x, y) offsets [m]; None: one foot at the position) of the face translation,
        on the top face if the position lies above the nodes' mid-height, else the bottom one; (n, 3)."""
        p = np.asarray(position, dtype=float)
        offsets = np.zeros((1, 2)) if feet is None else np.asarray(feet, dtype=float).reshape(-1, 2)
        return self.translation(p[:2] + offsets, self.face_for(float(p[2])), what).mean(axis=0)


def _points(xy: Any) -> np.ndarray:
    points = np.asarray(xy, dtype=float)
    if points.ndim == 1 and points.size == 2:
        points = points.reshape(1, 2)
    if points.ndim != 2 or points.shape[1] != 2 or not np.all(np.isfinite(points)):
        raise ParameterError(f"xy: must be finite (x, y) points, shape (k, 2), got shape {points.shape}")
    return points


@dataclass(frozen=True)
class FlexibleTop:
    """A top that bends: ``[table.flexible]``, its modal data loaded and checked.

    Equal, and hashed, by the modal data alone (the keys that chose it are kept to write the scenario back).
    Build one with :func:`~isolator.scenario.flexible.load_flexible`.

    Attributes
    ----------
    modes : str
        The modal file as the scenario names it (relative to the scenario file's folder).
    data : ModalData
        The kept elastic modes.
    count : int or None
        Keep the lowest ``count`` elastic modes (None: every one).
    max_frequency : float or None
        And only those up to this frequency [Hz].
    damping : float
        Modal damping ratio where the file gives none.
    origin : tuple of float
        Where the file's origin lies in the table frame (axes parallel) [m].
    """

    modes: str = field(compare=False)
    data: ModalData
    count: int | None = field(default=None, compare=False)
    max_frequency: float | None = field(default=None, compare=False)
    damping: float = field(default=0.01, compare=False)
    origin: tuple[float, float, float] = field(default=(0.0, 0.0, 0.0), compare=False)
