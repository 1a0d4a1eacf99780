"""Feedforward cancellation of the carriages' reaction on the table, from the planned motion.

What the actuators hold and what they leave: the carriages' weight moving
across the table tilts it quasi-statically (the static equilibrium follows
the carriages). Holding that tilt would take a standing force after every
move (Table 3.2: about 2,700 N m for the 400 kg stage moving 1.4 m, more
than four 500 N actuators at 1 m can give) and is the job of the isolators'
slow leveling valves. So the feedforward leaves the table on its
**quasi-static path** and cancels everything else: it supplies

* the carriages' inertial reaction, ``sum m_i a_i`` and ``sum m_i d_i x a_i``
  (their accelerations relative to the table, about its mass centre), and
* the small force that moves the table along its quasi-static path,
  ``M z_qs'' + C z_qs'`` (linearised mass and damping at the start),

allocated over the actuators by least squares within their force limits
(``method="allocation"``). What remains is the deviation from the
quasi-static path that the table would see with ideal actuators: second
order in the small rotations.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.optimize import lsq_linear
from scipy.spatial.transform import Rotation

from isolator.analysis.linear import LinearModel, linearise
from isolator.errors import ScenarioError
from isolator.model.equilibrium import static_equilibrium
from isolator.model.linearisation import build_linearisation
from isolator.model.parameters import ParameterLayout
from isolator.model.rotations import pose_rotation
from isolator.model.signals import table_signals
from isolator.scenario.definitions import SIGNALS, Scenario
from isolator.simulation.actuation import ForceHistory
from isolator.simulation.response import Response
from isolator.simulation.settling import settling_time
from isolator.simulation.simulator import Simulator
from isolator.simulation.time_grid import grid_breakpoints

__all__ = [
    "Feedforward",
    "FeedforwardComparison",
    "PathDemand",
    "allocation_matrix",
    "carriage_inertia_wrench",
    "compare_feedforward",
    "feedforward_allocation",
    "path_demand",
    "path_deviation",
    "quasi_static_path",
    "reaction_wrench",
    "settling_in_band",
]

#: spacing of the static equilibria that trace the quasi-static path [s]
QS_SPACING = 0.02


def _orientations(rot0: np.ndarray, rotation_vectors: np.ndarray) -> np.ndarray:
    """``exp([phi]x) R0`` for rotation vectors (N, 3), shape (N, 3, 3)."""
    return Rotation.from_rotvec(rotation_vectors).as_matrix() @ rot0


def allocation_matrix(scenario: Scenario, rot: np.ndarray) -> np.ndarray:
    """Wrench per unit actuator force, shape (..., 6, n_actuators).

    Rows: force [N] and moment about the table's mass centre [N m], world axes,
    with the table turned by ``rot`` (..., 3, 3) (table to world).
    """
    d = np.array([a.direction for a in scenario.actuators], dtype=float)  # (n, 3)
    p = np.array([a.position for a in scenario.actuators], dtype=float)
    arms = np.einsum("...ij,nj->...ni", rot, p)
    moments = np.cross(arms, d)
    force = np.broadcast_to(d, moments.shape)
    return np.swapaxes(np.concatenate([force, moments], axis=-1), -1, -2)


def reaction_wrench(scenario: Scenario, t: np.ndarray, piece_time: np.ndarray | None, rot: np.ndarray) -> np.ndarray:
    """The wrench that cancels the carriages' inertial reaction, (N, 6) [N, N m], world axes.

    ``sum m_i a_i`` and ``sum m_i d_i x a_i`` with ``d_i`` the carriage masses'
    positions and ``a_i`` their accelerations relative to the table, about its
    mass centre, turned by the table's orientation ``rot`` (N, 3, 3).
    """
    t = np.asarray(t, dtype=float)
    n = len(scenario.carriages)
    q = np.zeros((n, t.size))
    qdd = np.zeros((n, t.size))
    for i, c in enumerate(scenario.carriages):
        q[i], _, qdd[i] = c.profile.evaluate(t, piece_time)
    wrench = carriage_inertia_wrench(scenario, q, qdd)
    return np.hstack([np.einsum("nij,nj->ni", rot, wrench[:, :3]), np.einsum("nij,nj->ni", rot, wrench[:, 3:])])


def carriage_inertia_wrench(scenario: Scenario, q: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """``sum m_i a_i`` and ``sum m_i d_i x a_i`` in the table's axes, (N, 6) [N, N m].

    ``d_i`` are the carriage masses' positions about the table's mass centre
    at coordinates ``q`` (n, N) and ``a_i`` their accelerations relative to the
    table for coordinate accelerations ``qdd`` (n, N); a carriage's
    acceleration carries the carriages riding on it.
    """
    pos = scenario.carriage_positions(q)  # (n, 3, N)
    acc = scenario.carriage_positions(qdd) - scenario.carriage_positions(np.zeros_like(qdd))
    m = np.array([c.mass for c in scenario.carriages])[:, None, None]
    force = np.sum(m * acc, axis=0).T
    moment = np.sum(m * np.cross(pos, acc, axis=1), axis=0).T
    return np.hstack([force, moment])


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
    """
    sim = Simulator(scenario)
    model, p = sim.model, sim.parameters
    start = static_equilibrium(model, p, scenario.initial_positions(), check=False)
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
        states = np.array([static_equilibrium(model, p, qk, check=False).state for qk in q])
        signals = table_signals(states, start.state).T
        segments.append((a, b, CubicSpline(knots, signals, axis=0)))
    if not segments:  # nothing moves
        segments.append((0.0, t_end, CubicSpline([0.0, max(t_end, 1.0)], np.zeros((2, 6)), axis=0)))
    return QuasiStaticPath(segments)


@dataclass(frozen=True)
class Feedforward:
    """Feedforward actuator forces and what they were computed from.

    Attributes
    ----------
    forces : ForceHistory
        Commanded forces at the knots (samples and both sides of each breakpoint).
    wrench : ndarray (N, 6)
        The wrench asked of the actuators at the knots [N, N m].
    residual : ndarray (N, 6)
        What the allocation could not give (limits, directions) [N, N m].
    path : QuasiStaticPath
        The table's quasi-static path, which the forces leave alone.
    method : str
        ``"allocation"`` or ``"optimal"``.
    info : dict
        How the forces were found (for ``"optimal"``: solver status, iterations,
        knots, variables, time).
    """

    forces: ForceHistory
    wrench: np.ndarray
    residual: np.ndarray
    path: QuasiStaticPath
    method: str = "allocation"
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def max_force(self) -> dict[str, float]:
        """Largest |force| per actuator [N]."""
        return {n: float(np.max(np.abs(f), initial=0.0)) for n, f in zip(self.forces.names, self.forces.forces,
                                                                          strict=True)}


def _knots(scenario: Scenario) -> tuple[np.ndarray, np.ndarray]:
    """Sample times plus both sides of every breakpoint, with a time on the side to evaluate."""
    samples = scenario.simulation.sample_times()
    bps = grid_breakpoints(scenario.simulation, scenario.breakpoints)  # on the simulation's grid
    samples = samples[~np.isin(samples, bps)]
    eps = 1e-9
    times = np.concatenate([samples, bps, bps])
    sides = np.concatenate([samples, bps - eps, bps + eps])
    order = np.lexsort((sides, times))
    return times[order], sides[order]


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
    rot = _orientations(pose_rotation(lin.equilibrium.pose[3:]), signals[:, 3:])
    n = len(scenario.carriages)
    c = np.zeros((3 * n, times.size))
    for i, carriage in enumerate(scenario.carriages):
        q, v, _ = carriage.profile.evaluate(times, sides)
        c[i], c[n + i] = q, v
    pose = np.vstack([lin.equilibrium.pose[:3, None] + signals[:, :3].T,
                      Rotation.from_matrix(rot).as_euler("ZYX")[:, ::-1].T])
    mapped = build_linearisation(layout).map(times.size, "serial")
    mass, damping, stiffness = (
        np.asarray(m, dtype=float).reshape(6, times.size, 6).transpose(1, 0, 2)
        for m in mapped(pose, c, layout.pack(scenario))[:3]
    )
    accel, rate = path(times, sides, 2), path(times, sides, 1)
    wrench = reaction_wrench(scenario, times, sides, rot)
    wrench += np.einsum("nij,nj->ni", mass, accel) + np.einsum("nij,nj->ni", damping, rate)
    return PathDemand(wrench, allocation_matrix(scenario, rot), mass, damping, stiffness)


def feedforward_allocation(scenario: Scenario, limits: bool = True) -> Feedforward:
    """Instantaneous allocation of the cancelling wrench over the actuators.

    Parameters
    ----------
    scenario : Scenario
        With ``[[actuators]]``.
    limits : bool
        Respect each actuator's ``max_force`` (bounded least squares where the
        minimum-norm solution exceeds one); False: the unconstrained solution.

    Raises
    ------
    ScenarioError
        No actuators, or actuators that cannot produce a wrench in every direction
        (the allocation then leaves the unreachable part in ``residual``; only
        no actuators at all is an error).
    """
    if not scenario.actuators:
        raise ScenarioError("actuators: the scenario has no [[actuators]] for feedforward")
    lin = linearise(scenario)
    path = quasi_static_path(scenario)
    times, sides = _knots(scenario)
    demand = path_demand(scenario, lin, path, times, sides)
    wrench, b = demand.wrench, demand.allocation  # (N, 6), (N, 6, n)
    forces = np.einsum("nij,nj->ni", np.linalg.pinv(b), wrench)
    if limits:
        cap = np.array([a.max_force for a in scenario.actuators])
        for i in np.flatnonzero(np.any(np.abs(forces) > cap, axis=1)):
            forces[i] = lsq_linear(b[i], wrench[i], bounds=(-cap, cap)).x
    residual = wrench - np.einsum("nij,nj->ni", b, forces)
    names = tuple(a.name for a in scenario.actuators)
    return Feedforward(ForceHistory(times, forces.T, names), wrench, residual, path)


def path_deviation(run: Response, quasi_static: np.ndarray) -> dict[str, float]:
    """Largest |signal - quasi-static path| per signal of a run [m or rad], the path given at the
    run's samples, shape (6, N)."""
    dev = np.max(np.abs(run.signals - quasi_static), axis=1)
    return dict(zip(SIGNALS, (float(v) for v in dev), strict=True))


def settling_in_band(run: Response, band: dict[str, float]) -> dict[str, float | None]:
    """Settling time per signal [s] of a run in a given band per signal [m or rad], about the run's
    final value (None where the run cannot show it)."""
    final = run.final if run.final is not None else np.zeros(6)
    return {k: settling_time(run.t, run.signals[i], float(final[i]), run.stop_time, max(band[k], 1e-300))[0]
            for i, k in enumerate(SIGNALS)}


@dataclass(frozen=True)
class FeedforwardComparison:
    """The passive run against the run with feedforward, judged with one settling band.

    Attributes
    ----------
    passive, controlled : Response
    quasi_static : ndarray (6, N)
        The quasi-static path at the samples [m, rad].
    band : dict of str to float
        Per signal: 5 % of the passive run's peak [m or rad].
    settling : dict of str to dict
        ``passive`` and ``controlled``: settling time per signal [s] (None if
        the run cannot show it) in that band.
    feedforward : Feedforward
    """

    passive: Response
    controlled: Response
    quasi_static: np.ndarray
    band: dict[str, float]
    settling: dict[str, dict[str, float | None]]
    feedforward: Feedforward

    def deviation_peak(self, which: str) -> dict[str, float]:
        """Largest |signal - quasi-static path| per signal [m or rad] of ``passive`` or ``controlled``."""
        return path_deviation(self.passive if which == "passive" else self.controlled, self.quasi_static)

    def reduction_db(self) -> dict[str, float]:
        """Peak deviation from the quasi-static path, controlled over passive [dB] per signal."""
        p, c = self.deviation_peak("passive"), self.deviation_peak("controlled")
        return {k: 20 * math.log10(max(c[k], 1e-300) / p[k]) if p[k] > 0 else 0.0 for k in SIGNALS}

    def settling_time_max(self, which: str) -> float | None:
        values = self.settling[which].values()
        return None if any(v is None for v in values) else max(values)  # type: ignore[type-var]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``passive`` and ``controlled`` (``peak``, ``deviation_peak``,
        ``settling_time``, ``settling_time_max``), ``band``, ``reduction_db``, ``max_force``."""
        out: dict[str, Any] = {"name": self.passive.name, "method": self.feedforward.method}
        for which, r in (("passive", self.passive), ("controlled", self.controlled)):
            out[which] = {
                "peak": r.peak,
                "deviation_peak": self.deviation_peak(which),
                "settling_time": self.settling[which],
                "settling_time_max": self.settling_time_max(which),
            }
        out["band"] = self.band
        out["reduction_db"] = self.reduction_db()
        out["max_force"] = self.feedforward.max_force
        if self.feedforward.info:
            out["optimisation"] = self.feedforward.info
        return out

    def summary(self) -> str:
        """A text table per signal: deviation peaks, reduction, settling times."""
        red = self.reduction_db()
        dp, dc = self.deviation_peak("passive"), self.deviation_peak("controlled")
        lines = [
            f"{self.passive.name}: feedforward by {self.feedforward.method} (deviation from the quasi-static path; "
            "settling band 5 % of the passive peak)",
            f"{'signal':>6}  {'passive dev.':>12}  {'with ff':>12}  {'change':>9}  "
            f"{'settling passive':>16}  {'with ff':>8}",
        ]
        for k in SIGNALS:
            sp, sc = self.settling["passive"][k], self.settling["controlled"][k]
            unit = "urad" if k.startswith("r") else "um"
            lines.append(
                f"{k:>6}  {dp[k] * 1e6:>7.4g} {unit:<4}  {dc[k] * 1e6:>7.4g} {unit:<4}  {red[k]:>6.1f} dB  "
                f"{'-' if sp is None else f'{sp:.4g} s':>16}  {'-' if sc is None else f'{sc:.4g} s':>8}"
            )
        forces = self.feedforward.max_force.items()
        lines.append("largest actuator force: " + ", ".join(f"{n} {f:.0f} N" for n, f in forces))
        return "\n".join(lines)


def compare_feedforward(scenario: Scenario, feedforward: Feedforward | None = None) -> FeedforwardComparison:
    """Simulate the scenario without and with the feedforward forces.

    Both runs' settling times use one band per signal: 5 % of the passive
    run's peak (the issue's criterion), about the final static equilibrium.
    """
    ff = feedforward_allocation(scenario) if feedforward is None else feedforward
    sim = Simulator(scenario)
    passive = sim.run()
    controlled = sim.run(forces=ff.forces)
    qs = ff.path(passive.t).T
    band = {k: 0.05 * v for k, v in passive.peak.items()}
    settling = {"passive": settling_in_band(passive, band), "controlled": settling_in_band(controlled, band)}
    return FeedforwardComparison(passive, controlled, qs, band, settling, ff)
