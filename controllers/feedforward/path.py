"""The table's quasi-static path as the carriages move, and what the table needs along it.

The carriages' weight moving across the table tilts it quasi-statically: the
static equilibrium follows the carriages. The feedforward leaves the table on
that path (holding the tilt is the leveling valves' job) and cancels the rest:
the carriages' inertial reaction plus the small force that moves the table
along the path (:func:`path_demand`).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.spatial.transform import Rotation

from isolator.analysis.linear import LinearModel
from isolator.model.equilibrium import air_in_groups, closed_rest_states, static_equilibrium
from isolator.model.linearisation import build_linearisation
from isolator.model.parameters import ParameterLayout
from isolator.model.rotations import pose_rotation
from isolator.model.signals import table_signals
from isolator.scenario.definitions import Scenario
from isolator.simulation.simulator import Simulator

from .wrench import allocation_matrix, reaction_wrench

__all__ = ["QS_SPACING", "PathDemand", "QuasiStaticPath", "path_demand", "quasi_static_path"]

#: spacing of the static equilibria that trace the quasi-static path [s]
QS_SPACING = 0.02


def _orientations(rot0: np.ndarray, rotation_vectors: np.ndarray) -> np.ndarray:
    """``exp([phi]x) R0`` for rotation vectors (N, 3), shape (N, 3, 3)."""
    return Rotation.from_rotvec(rotation_vectors).as_matrix() @ rot0


@dataclass(frozen=True)
class QuasiStaticPath:
    """The table's static equilibrium as the carriages move, traced in time.

    Attributes
    ----------
    segments : list of (float, float, CubicSpline)
        Per stretch between profile breakpoints: start, end [s] and a spline of
        the six signals (displacement [m], rotation vector [rad]) from the
        initial equilibrium.
    """

    segments: list[tuple[float, float, CubicSpline]]

    def __call__(self, t: np.ndarray, piece_time: np.ndarray | None = None, nu: int = 0) -> np.ndarray:
        """Signals (nu = 0) or their ``nu``-th time derivative at ``t``, shape (N, 6)."""
        t = np.asarray(t, dtype=float)
        sel = t if piece_time is None else np.asarray(piece_time, dtype=float)
        out = np.zeros((t.size, 6))
        for k, (a, b, spline) in enumerate(self.segments):
            last = k == len(self.segments) - 1
            mask = (sel >= a) & ((sel < b) | last)
            if k == 0:
                mask |= sel < a
            if mask.any():
                out[mask] = spline(np.clip(t[mask], a, b), nu)
                if nu > 0:  # held before the first and after the last stretch
                    out[mask & ((t < a) | (t > b))] = 0.0
        return out


def quasi_static_path(scenario: Scenario, spacing: float = QS_SPACING) -> QuasiStaticPath:
    """Trace the static equilibrium along the carriages' planned motion.

    Static equilibria (Newton, exact model) every ``spacing`` seconds within
    each stretch between profile breakpoints, splined per stretch (the path
    is smooth within a stretch; its acceleration may jump at a breakpoint).
    Pneumatic tables: the rest with each group's air as at the start (the
    valves re-level more slowly than the stage moves).
    """
    sim = Simulator(scenario)
    model, p = sim.model, sim.parameters
    start = static_equilibrium(model, p, scenario.initial_positions(), check=False)
    air = None if sim.layout.pneumatic is None else air_in_groups(model, start.state[None, :], p)
    t_end = scenario.simulation.duration
    stop = scenario.stop_time if math.isfinite(scenario.stop_time) else t_end
    cuts = sorted({0.0, *[b for b in scenario.breakpoints if 0 < b < min(stop, t_end)], min(stop, t_end)})
    segments = []
    for a, b in itertools.pairwise(cuts):
        if b <= a:
            continue
        count = max(4, math.ceil((b - a) / spacing) + 1)
        knots = np.linspace(a, b, count)
        mid = np.full(count, 0.5 * (a + b))
        q = np.array([c.profile.evaluate(knots, mid)[0] for c in scenario.carriages]).T
        if air is None:
            states = np.array([static_equilibrium(model, p, qk, check=False).state for qk in q])
        else:  # pneumatic: the air each group holds at the start stays; the valves level later
            states = np.array([closed_rest_states(model, p, qk, air)[0] for qk in q])
        signals = table_signals(states, start.state).T
        segments.append((a, b, CubicSpline(knots, signals, axis=0)))
    if not segments:  # nothing moves
        segments.append((0.0, t_end, CubicSpline([0.0, max(t_end, 1.0)], np.zeros((2, 6)), axis=0)))
    return QuasiStaticPath(segments)


@dataclass(frozen=True)
class PathDemand:
    """What the table needs along its quasi-static path at a set of times.

    Attributes
    ----------
    wrench : ndarray (N, 6)
        The cancelling wrench: the carriages' inertial reaction plus
        ``M z_qs'' + C z_qs'`` [N, N m], world axes about the mass centre.
    allocation : ndarray (N, 6, n_actuators)
        Wrench per unit actuator force with the table on its path.
    mass, damping, stiffness : ndarray (N, 6, 6)
        The exact model linearised on the path, the carriages where (and as
        fast as) they are: the coupling terms change as a carriage crosses.
    """

    wrench: np.ndarray
    allocation: np.ndarray
    mass: np.ndarray
    damping: np.ndarray
    stiffness: np.ndarray


def path_demand(
    scenario: Scenario, lin: LinearModel, path: QuasiStaticPath, times: np.ndarray, sides: np.ndarray
) -> PathDemand:
    """The cancelling wrench and the linearised table along the quasi-static path.

    Parameters
    ----------
    times : ndarray (N,)
        [s]
    sides : ndarray (N,)
        Times that pick the profile piece at each time (one-sided at breakpoints).
    """
    layout = ParameterLayout.of(scenario)
    signals = path(times, sides)
    rot = _orientations(pose_rotation(lin.equilibrium.pose[3:6]), signals[:, 3:])
    n = len(scenario.carriages)
    c = np.zeros((3 * n, times.size))
    for i, carriage in enumerate(scenario.carriages):
        q, v, _ = carriage.profile.evaluate(times, sides)
        c[i], c[n + i] = q, v
    pose = np.vstack([lin.equilibrium.pose[:3, None] + signals[:, :3].T,
                      Rotation.from_matrix(rot).as_euler("ZYX")[:, ::-1].T,
                      np.repeat(lin.equilibrium.pose[6:, None], times.size, axis=1)])  # pneumatic: rest pressures
    mapped = build_linearisation(layout).map(times.size, "serial")
    mass, damping, stiffness = (
        np.asarray(m, dtype=float).reshape(6, times.size, 6).transpose(1, 0, 2)
        for m in mapped(pose, c, layout.pack(scenario))[:3]
    )
    accel, rate = path(times, sides, 2), path(times, sides, 1)
    wrench = reaction_wrench(scenario, times, sides, rot)
    wrench += np.einsum("nij,nj->ni", mass, accel) + np.einsum("nij,nj->ni", damping, rate)
    return PathDemand(wrench, allocation_matrix(scenario, rot), mass, damping, stiffness)
