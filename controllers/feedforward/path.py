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
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.simulation.simulator import Simulator

from .wrench import allocation_matrix, reaction_wrench

__all__ = ["QS_SPACING", "AirDemand", "PathDemand", "QuasiStaticPath", "path_demand", "quasi_static_path"]

#: spacing of the static equilibria that trace the quasi-static path [s]
QS_SPACING = 0.02


def _orientations(rot0: np.ndarray, rotation_vectors: np.ndarray) -> np.ndarray:
    """``exp([phi]x) R0`` for rotation vectors (N, 3), shape (N, 3, 3)."""
    return Rotation.from_rotvec(rotation_vectors).as_matrix() @ rot0


def _piecewise(segments: list[tuple[float, float, CubicSpline]], t: np.ndarray, sel: np.ndarray, nu: int,
               width: int) -> np.ndarray:
    """Per-stretch splines at ``t`` (stretch picked by ``sel``), held before the first and after the last."""
    out = np.zeros((t.size, width))
    for k, (a, b, spline) in enumerate(segments):
        last = k == len(segments) - 1
        mask = (sel >= a) & ((sel < b) | last)
        if k == 0:
            mask |= sel < a
        if mask.any():
            out[mask] = spline(np.clip(t[mask], a, b), nu)
            if nu > 0:  # held before the first and after the last stretch
                out[mask & ((t < a) | (t > b))] = 0.0
    return out


@dataclass(frozen=True)
class QuasiStaticPath:
    """The table's static equilibrium as the carriages move, traced in time.

    Attributes
    ----------
    segments : list of (float, float, CubicSpline)
        Per stretch between profile breakpoints: start, end [s] and a spline of
        the six signals (displacement [m], rotation vector [rad]) from the
        initial equilibrium.
    air : list of (float, float, CubicSpline), optional
        Pneumatic tables: the same for the chamber pressures' change from the
        initial equilibrium [Pa] (the model's pressure states, in order), the
        air each group holds at the start kept.
    """

    segments: list[tuple[float, float, CubicSpline]]
    air: list[tuple[float, float, CubicSpline]] | None = None

    def __call__(self, t: np.ndarray, piece_time: np.ndarray | None = None, nu: int = 0) -> np.ndarray:
        """Signals (nu = 0) or their ``nu``-th time derivative at ``t``, shape (N, 6)."""
        t = np.asarray(t, dtype=float)
        sel = t if piece_time is None else np.asarray(piece_time, dtype=float)
        return _piecewise(self.segments, t, sel, nu, 6)

    def pressures(self, t: np.ndarray, piece_time: np.ndarray | None = None, nu: int = 0) -> np.ndarray:
        """Chamber pressures' change from the start [Pa] (nu = 0) or its ``nu``-th time derivative,
        shape (N, n_air); (N, 0) for spring-damper tables."""
        t = np.asarray(t, dtype=float)
        sel = t if piece_time is None else np.asarray(piece_time, dtype=float)
        if self.air is None:
            return np.zeros((t.size, 0))
        return _piecewise(self.air, t, sel, nu, self.air[0][2].c.shape[-1])


def quasi_static_path(scenario: Scenario, spacing: float = QS_SPACING) -> QuasiStaticPath:
    """Trace the static equilibrium along the carriages' planned motion.

    Static equilibria (Newton, exact model) every ``spacing`` seconds within
    each stretch between profile breakpoints, splined per stretch (the path
    is smooth within a stretch; its acceleration may jump at a breakpoint).
    Pneumatic tables: the rest with each group's air as at the start (the
    valves re-level more slowly than the stage moves).

    Parameters
    ----------
    scenario : Scenario
        The scenario (or a bundled scenario's name, or a TOML file's path).
    spacing : float
        Time between two equilibria [s].

    Returns
    -------
    QuasiStaticPath
        The path's splines per stretch (the table's pose [m, rad] at any time of the move).
    """
    sim = Simulator(scenario)
    model, p = sim.model, sim.parameters
    start = static_equilibrium(model, p, scenario.initial_positions(), check=False)
    air = None if sim.layout.pneumatic is None else air_in_groups(model, start.state[None, :], p)
    t_end = scenario.simulation.duration
    stop = scenario.stop_time if math.isfinite(scenario.stop_time) else t_end
    cuts = sorted({0.0, *[b for b in scenario.breakpoints if 0 < b < min(stop, t_end)], min(stop, t_end)})
    segments, pressures = [], []
    for a, b in itertools.pairwise(cuts):
        if b - a <= 1e-9 * max(1.0, abs(b)):  # a stop time given as the input reads (7.9) next to its breakpoint
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
        if air is not None:
            pressures.append((a, b, CubicSpline(knots, states[:, 13:] - start.state[13:], axis=0)))
    if not segments:  # nothing moves
        segments.append((0.0, t_end, CubicSpline([0.0, max(t_end, 1.0)], np.zeros((2, 6)), axis=0)))
        if air is not None:
            width = start.state.size - 13
            pressures.append((0.0, t_end, CubicSpline([0.0, max(t_end, 1.0)], np.zeros((2, width)), axis=0)))
    return QuasiStaticPath(segments, pressures if air is not None else None)


@dataclass(frozen=True)
class AirDemand:
    """A pneumatic table's chamber pressures along its quasi-static path (valves closed).

    With ``e`` the pressures' deviation from the path's quasi-static pressures
    ``p_qs`` [Pa], the force balance gains ``+ Kp e`` and

    ``e' = Pd d + Pv d' + Pp e + rate``,  ``rate = Pv z_qs' - p_qs'``:

    moving the table along its path at ``z_qs'`` squeezes the chambers at once
    (``Pv z_qs'``; at rest on the path the pressures do not change), while the
    quasi-static pressures, every group's chambers at one pressure, change only
    at ``p_qs'``; the difference drives the air off the path.

    ``Pp`` is taken at the path's rate: a chamber's squeeze ``-n p A s'/V`` is
    proportional to its pressure, so about the moving path ``de'/de`` gains
    ``diag(Pv z_qs' / p_qs)`` (at rest it has not). Small beside the orifices'
    and lines' flows, but the groups' air is a marginal mode: left out, the
    linear model's air drifts over a move (tens of Pa over the tests' 0.8 m
    stroke on air springs, a micrometre or two of heave).

    Attributes
    ----------
    kp : ndarray (N, 6, n_air)
    pd, pv : ndarray (N, n_air, 6)
    pp : ndarray (N, n_air, n_air)
    rate : ndarray (N, n_air)
        ``r`` [Pa/s]
    """

    kp: np.ndarray
    pd: np.ndarray
    pv: np.ndarray
    pp: np.ndarray
    rate: np.ndarray


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
    air : AirDemand, optional
        Pneumatic tables: the chamber pressures' part, linearised about the
        path's quasi-static pressures.
    """

    wrench: np.ndarray
    allocation: np.ndarray
    mass: np.ndarray
    damping: np.ndarray
    stiffness: np.ndarray
    air: AirDemand | None = None


def path_demand(
    scenario: Scenario, lin: LinearModel, path: QuasiStaticPath, times: np.ndarray, sides: np.ndarray
) -> PathDemand:
    """The cancelling wrench and the linearised table along the quasi-static path.

    Pneumatic tables are linearised about the path's quasi-static pressures
    (each group's air as at the start).

    Parameters
    ----------
    times : ndarray (N,)
        [s]
    sides : ndarray (N,)
        Times that pick the profile piece at each time (one-sided at breakpoints).
    scenario : Scenario
        The scenario, with ``[[actuators]]`` (or a bundled scenario's name, or a TOML file's path).
    lin : LinearModel
        The table linearised at rest (its structure and names).
    path : QuasiStaticPath
        From :func:`quasi_static_path`.

    Returns
    -------
    PathDemand
        At each time: the cancelling wrench [N, N m], the table's mass, stiffness and damping matrices along
        the path and the actuators' allocation matrix.
    """
    layout = ParameterLayout.of(scenario)
    signals = path(times, sides)
    rot = _orientations(pose_rotation(lin.equilibrium.pose[3:6]), signals[:, 3:])
    n = len(scenario.carriages)
    c = np.zeros((3 * n, times.size))
    for i, carriage in enumerate(scenario.carriages):
        q, v, _ = carriage.profile.evaluate(times, sides)
        c[i], c[n + i] = q, v
    gauge = np.repeat(lin.equilibrium.pose[6:, None], times.size, axis=1)
    if layout.pneumatic is not None and path.air is not None:  # every group's chambers at one pressure
        gauge = gauge + path.pressures(times, sides)[:, [g[0] for g in layout.pneumatic.groups]].T
    pose = np.vstack([lin.equilibrium.pose[:3, None] + signals[:, :3].T,
                      Rotation.from_matrix(rot).as_euler("ZYX")[:, ::-1].T, gauge])
    mapped = build_linearisation(layout).map(times.size, "serial")
    mats = [np.asarray(m, dtype=float) for m in mapped(pose, c, layout.pack(scenario))]
    mass, damping, stiffness = (_stacked(m, times.size) for m in mats[:3])
    accel, rate = path(times, sides, 2), path(times, sides, 1)
    wrench = reaction_wrench(scenario, times, sides, rot)
    wrench += np.einsum("nij,nj->ni", mass, accel) + np.einsum("nij,nj->ni", damping, rate)
    air = None
    if layout.pneumatic is not None:
        kp, pd, pv, pp = (_stacked(m, times.size) for m in mats[7:11])
        squeeze = np.einsum("nij,nj->ni", pv, rate)  # Pv z_qs': the chambers squeezed at the path's rate
        pressure_rate = squeeze.copy()
        pressures = lin.equilibrium.state[None, 13:]
        if path.air is not None:
            pressure_rate -= path.pressures(times, sides, 1)
            pressures = pressures + path.pressures(times, sides)
        # the squeeze term -n p A s'/V is proportional to the chamber's pressure: at the path's rate it adds
        # Pv z_qs' / p to Pp (without it the groups' air drifts in the linear model)
        pp = pp + np.einsum("ni,ij->nij", squeeze / pressures, np.eye(pp.shape[1]))
        air = AirDemand(kp, pd, pv, pp, pressure_rate)
    return PathDemand(wrench, allocation_matrix(scenario, rot), mass, damping, stiffness, air)


def _stacked(mapped: np.ndarray, count: int) -> np.ndarray:
    """A mapped casadi output (rows, count * columns) as (count, rows, columns)."""
    return mapped.reshape(mapped.shape[0], count, -1).transpose(1, 0, 2)


check_public(globals())
