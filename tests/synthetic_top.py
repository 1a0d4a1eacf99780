"""A synthetic bending top for the model's tests: smooth analytic mode shapes on a rectangular top, mass-orthogonal
to the rigid translations and rotations of a homogeneous box (so the top's own weight does not load them), in the
interface the model reads (``ModalData``: ``frequencies``, ``damping``, ``digest``, ``face_for``, ``inside``,
``translation``), held in the scenario as a real :class:`FlexibleTop` whose :class:`ModalData` samples them on a
grid (``Table.flexible`` takes nothing else). Not a finite-element model: the plate tests use ``isolator
plate-modes``."""

from __future__ import annotations

import dataclasses
import hashlib

import numpy as np

from isolator import load_scenario
from isolator.errors import ScenarioError
from isolator.scenario.definitions import Scenario, Table
from isolator.scenario.flexible import FlexibleTop, ModalData


class SyntheticModes:
    """Three modes of a ``lx`` x ``ly`` x ``t`` top of mass ``mass``: a twist ``xy``, bending along x and along
    y (Legendre ``P2``), each mass-normalised on the box; the faces move in-plane with the bending slopes."""

    def __init__(self, lx: float = 2.0, ly: float = 1.0, t: float = 0.3, mass: float = 4400.0,
                 frequencies: tuple[float, ...] = (150.0, 220.0, 310.0), zeta: float = 0.01) -> None:
        self.lx, self.ly, self.t, self.mass = lx, ly, t, mass
        self.frequencies = np.array(frequencies, dtype=float)
        self.damping = np.full(len(frequencies), zeta)
        self.nodes = np.array([[x, y, z] for x in (-lx / 2, lx / 2) for y in (-ly / 2, ly / 2)
                               for z in (-t / 2, t / 2)])
        self.digest = hashlib.sha256(repr((lx, ly, t, mass, frequencies, zeta)).encode()).hexdigest()
        self.n_modes = len(frequencies)
        # mean squares over the box of x y (= 1/9 in normalised coordinates) and P2 (= 1/5)
        self.amplitude = np.array([3.0, np.sqrt(5.0), np.sqrt(5.0)])[: self.n_modes] / np.sqrt(mass)

    def face_for(self, z: float) -> str:
        return "top" if z > 0 else "bottom"

    def inside(self, xy: np.ndarray, face: str) -> np.ndarray:
        xy = np.asarray(xy, float).reshape(-1, 2)
        return (np.abs(xy[:, 0]) <= self.lx / 2 + 1e-3) & (np.abs(xy[:, 1]) <= self.ly / 2 + 1e-3)

    def translation(self, xy: np.ndarray, face: str, what: str) -> np.ndarray:
        xy = np.asarray(xy, float).reshape(-1, 2)
        if not self.inside(xy, face).all():
            raise ScenarioError(f"{what}: a foot off the top's {face} face")
        x, y = xy[:, 0] / (self.lx / 2), xy[:, 1] / (self.ly / 2)
        out = np.zeros((xy.shape[0], self.n_modes, 3))
        a = self.amplitude
        out[:, 0, 2] = a[0] * x * y
        if self.n_modes > 1:
            out[:, 1, 2] = a[1] * (1.5 * x**2 - 0.5)
        if self.n_modes > 2:
            out[:, 2, 2] = a[2] * (1.5 * y**2 - 0.5)
        return out


def synthetic_flexible(modes: SyntheticModes, grid: tuple[int, int] = (21, 11)) -> FlexibleTop:
    """``modes`` as the scenario holds a bending top: a :class:`FlexibleTop` whose :class:`ModalData` samples the
    analytic shapes on a grid of both faces (interpolated between the nodes as any modal file is)."""
    x, y = np.meshgrid(np.linspace(-modes.lx / 2, modes.lx / 2, grid[0]),
                       np.linspace(-modes.ly / 2, modes.ly / 2, grid[1]), indexing="ij")
    xy = np.column_stack([x.ravel(), y.ravel()])
    nodes = np.vstack([np.column_stack([xy, np.full(len(xy), h)]) for h in (modes.t / 2, -modes.t / 2)])
    shapes = modes.translation(xy, "top", "the synthetic top's grid")  # (nodes of a face, modes, 3)
    data = ModalData(path="synthetic top", frequencies=modes.frequencies, damping=modes.damping, nodes=nodes,
                     translations=np.concatenate([shapes, shapes]).transpose(1, 0, 2), rotations=None,
                     thickness=modes.t)
    return FlexibleTop(modes="synthetic top", data=data, damping=float(modes.damping[0]))


def with_synthetic_top(scenario: Scenario | str = "paper-table-3-2", **modes: object) -> Scenario:
    """``scenario`` with the synthetic bending top (its ``table.size`` and ``mass``)."""
    sc = load_scenario(scenario) if isinstance(scenario, str) else scenario
    t = sc.table
    size = t.size if t.size is not None else (2.0, 1.0, 0.3)
    data = SyntheticModes(size[0], size[1], size[2], t.mass, **modes)  # type: ignore[arg-type]
    return dataclasses.replace(sc, table=dataclasses.replace(t, flexible=synthetic_flexible(data)))


def without_top_modes(scenario: Scenario) -> Scenario:
    """The same scenario with a rigid top."""
    t = scenario.table
    return dataclasses.replace(scenario, table=Table(t.mass, t.inertia, t.size))
