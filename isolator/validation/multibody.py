"""An independent multibody check of a scenario, built in MuJoCo.

The table is a free body, each carriage a body on a slide joint (chained as in
the scenario), and each isolator a force applied at a site on the table. The
carriages' joint motion is prescribed: at every instant MuJoCo gives the joint
space mass matrix and bias forces, and the table's accelerations follow from
the partition ``M_tt a_t = f_t - b_t - M_tc a_c`` with the carriages'
prescribed accelerations ``a_c``. The states are integrated with scipy's
DOP853 at tight tolerance, restarted at the profiles' breakpoints. MuJoCo also
finds its own static equilibria (a root of its accelerations), so that nothing
but the scenario is shared with the casadi model.

Needs the optional dependency ``mujoco`` (``pip install isolator[check]``).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import root

from isolator.errors import IsolatorError, ScenarioError
from isolator.model.signals import table_signals
from isolator.scenario.definitions import Isolator, Scenario

__all__ = ["MujocoTable", "MultibodyRun", "mujoco_available", "solve_piecewise"]


def mujoco_available() -> bool:
    """True when the ``mujoco`` package can be imported."""
    try:
        import mujoco  # noqa: F401
    except ImportError:
        return False
    return True


@dataclass(frozen=True)
class MultibodyRun:
    """Time histories from the MuJoCo check.

    Attributes
    ----------
    t : ndarray (N,)
        [s]
    signals : ndarray (6, N)
        x, y, z [m], rx, ry, rz [rad] from the initial equilibrium, as in
        :class:`isolator.Response`.
    states : ndarray (N, 13)
        Position, quaternion (w, x, y, z), velocity (world) and angular
        velocity (table frame) of the table.
    """

    t: np.ndarray
    signals: np.ndarray
    states: np.ndarray


def _vec(v: Iterable[float]) -> str:
    return " ".join(f"{float(x):.17g}" for x in v)


def _spring_dampers(scenario: Scenario) -> tuple[Isolator, ...]:
    """The scenario's isolators, which the check models as linear spring-dampers (pneumatic ones it cannot)."""
    isolators = tuple(iso for iso in scenario.isolators if isinstance(iso, Isolator))
    if len(isolators) != len(scenario.isolators):
        raise ScenarioError("isolators: the MuJoCo check models spring-damper isolators only, not pneumatic ones")
    return isolators


class MujocoTable:
    """The scenario as a MuJoCo model with prescribed carriage joints.

    Parameters
    ----------
    scenario : Scenario
    forces : callable, optional
        ``forces(t, piece_time) -> (n_actuators,)`` actuator forces [N] along
        each actuator's direction (world), applied at its point on the table;
        ``piece_time`` lies inside the current integration segment (for forces
        that step at profile breakpoints), or equals ``t``.
    """

    def __init__(self, scenario: Scenario, forces: Callable[[float, float], Sequence[float]] | None = None) -> None:
        try:
            import mujoco
        except ImportError as exc:
            raise IsolatorError(
                "the multibody check needs MuJoCo: pip install 'isolator[check]'"
            ) from exc
        self.mj = mujoco
        self.scenario = scenario
        self.isolators = _spring_dampers(scenario)
        self.forces = forces
        self.model = mujoco.MjModel.from_xml_string(self._xml())
        self.data = mujoco.MjData(self.model)
        self.n_c = len(scenario.carriages)
        self.site_ids = [
            mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_SITE, f"iso{k}")
            for k in range(len(scenario.isolators))
        ]
        self.table_id = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, "table")
        self.joint_dofs = [
            int(self.model.jnt_dofadr[mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_JOINT, f"c{i}")])
            for i in range(self.n_c)
        ]
        self.joint_qpos = [
            int(self.model.jnt_qposadr[mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_JOINT, f"c{i}")])
            for i in range(self.n_c)
        ]
        self.preload = scenario.isolator_preloads()
        self._full_m = np.zeros((self.model.nv, self.model.nv))

    def _xml(self) -> str:
        sc = self.scenario
        children: dict[str, list[int]] = {}
        for i, c in enumerate(sc.carriages):
            children.setdefault(c.parent, []).append(i)

        def body(i: int) -> str:
            c = sc.carriages[i]
            inner = "".join(body(j) for j in children.get(c.name, []))
            return (
                f'<body name="c{i}" pos="{_vec(c.origin)}">'
                f'<joint name="c{i}" type="slide" axis="{_vec(c.axis)}" limited="false"/>'
                f'<inertial pos="0 0 0" mass="{c.mass!r}" diaginertia="1e-10 1e-10 1e-10"/>'
                f"{inner}</body>"
            )

        sites = "".join(
            f'<site name="iso{k}" pos="{_vec(iso.position)}"/>' for k, iso in enumerate(self.isolators)
        )
        carriages = "".join(body(i) for i in children.get("table", []))
        return (
            '<mujoco model="isolation-table">'
            f'<option gravity="0 0 {-sc.gravity!r}" timestep="0.001"/>'
            "<worldbody>"
            '<body name="table" pos="0 0 0"><freejoint name="table"/>'
            f'<inertial pos="0 0 0" mass="{sc.table.mass!r}" diaginertia="{_vec(sc.table.inertia)}"/>'
            f"{sites}{carriages}</body>"
            "</worldbody></mujoco>"
        )

    # -- dynamics ---------------------------------------------------------------
    def _carriages(self, t: float, piece_time: float | None = None) -> np.ndarray:
        out = np.zeros((3, self.n_c))
        for i, c in enumerate(self.scenario.carriages):
            q, v, a = c.profile.evaluate(np.array([t]), None if piece_time is None else np.array([piece_time]))
            out[:, i] = (q[0], v[0], a[0])
        return out

    def accelerations(
        self,
        y: np.ndarray,
        carriages: np.ndarray,
        t: float = 0.0,
        ground: np.ndarray | None = None,
        piece_time: float | None = None,
    ) -> np.ndarray:
        """Table accelerations (linear world, angular table frame) for state ``y``.

        Parameters
        ----------
        y : ndarray (13,)
            Position, quaternion (w, x, y, z), world velocity, table-frame angular velocity.
        carriages : ndarray (3, n)
            Carriage coordinates, velocities, accelerations.
        t : float
            Time [s] (for the actuator forces).
        ground : ndarray (12,), optional
            Floor translation [m], rotation about the world origin [rad] and their
            rates: the isolators' ground anchors move with it.
        piece_time : float, optional
            A time inside the current integration segment (for the forces).
        """
        mj, m, d = self.mj, self.model, self.data
        d.qpos[0:7] = y[0:7] / np.r_[1.0, 1.0, 1.0, np.full(4, np.linalg.norm(y[3:7]))]
        d.qvel[0:6] = y[7:13]
        for i in range(self.n_c):
            d.qpos[self.joint_qpos[i]] = carriages[0, i]
            d.qvel[self.joint_dofs[i]] = carriages[1, i]
        mj.mj_fwdPosition(m, d)
        mj.mj_fwdVelocity(m, d)
        d.qfrc_applied[:] = 0.0
        vel6 = np.zeros(6)
        for k, iso in enumerate(self.isolators):
            sid = self.site_ids[k]
            point = d.site_xpos[sid].copy()
            mj.mj_objectVelocity(m, d, mj.mjtObj.mjOBJ_SITE, sid, vel6, 0)
            anchor = np.asarray(iso.position, dtype=float)
            disp, rate = point - anchor, vel6[3:6].copy()
            if ground is not None:
                disp -= ground[0:3] + np.cross(ground[3:6], anchor)
                rate -= ground[6:9] + np.cross(ground[9:12], anchor)
            f = -np.asarray(iso.stiffness) * disp - np.asarray(iso.damping) * rate
            f[2] += self.preload[k]
            mj.mj_applyFT(m, d, f, np.zeros(3), point, self.table_id, d.qfrc_applied)
        if self.forces is not None and self.scenario.actuators:
            rot = d.xmat[self.table_id].reshape(3, 3)
            values = self.forces(t, t if piece_time is None else piece_time)
            for act, value in zip(self.scenario.actuators, values, strict=False):
                point = d.xpos[self.table_id] + rot @ np.asarray(act.position)
                f = value * np.asarray(act.direction)
                mj.mj_applyFT(m, d, f, np.zeros(3), point, self.table_id, d.qfrc_applied)
        self._fill_mass_matrix()
        rhs = d.qfrc_applied - d.qfrc_bias
        free = slice(0, 6)
        a_c = np.zeros(m.nv)
        for i in range(self.n_c):
            a_c[self.joint_dofs[i]] = carriages[2, i]
        return np.linalg.solve(self._full_m[free, free], rhs[free] - self._full_m[free, :] @ a_c)

    def _fill_mass_matrix(self) -> None:
        """Dense joint-space mass matrix (MuJoCo 3 and 4 spell the call differently)."""
        mj, m, d = self.mj, self.model, self.data
        if hasattr(d, "qM"):
            mj.mj_fullM(m, self._full_m, d.qM)
        else:
            mj.mj_fullM(m, d, self._full_m)

    def _derivative(self, t: float, y: np.ndarray, piece_time: float) -> np.ndarray:
        acc = self.accelerations(y, self._carriages(t, piece_time), t, piece_time=piece_time)
        qw, qx, qy, qz = y[3:7]
        p, q, r = y[10:13]
        qdot = 0.5 * np.array(
            [-qx * p - qy * q - qz * r, qw * p + qy * r - qz * q, qw * q + qz * p - qx * r, qw * r + qx * q - qy * p]
        )
        return np.concatenate([y[7:10], qdot, acc])

    # -- statics and runs --------------------------------------------------------
    def equilibrium(self, positions: np.ndarray) -> np.ndarray:
        """The table's rest state (13,) with carriages parked at ``positions`` [m]."""
        rest = np.zeros((3, self.n_c))
        rest[0] = positions

        def state(z: np.ndarray) -> np.ndarray:
            angle = np.linalg.norm(z[3:])
            axis = z[3:] / angle if angle > 0 else np.zeros(3)
            quat = np.r_[math.cos(angle / 2), math.sin(angle / 2) * axis]
            return np.r_[z[:3], quat, np.zeros(6)]

        scale = np.r_[np.full(3, self.scenario.total_mass), np.asarray(self.scenario.table.inertia)]
        sol = root(lambda z: self.accelerations(state(z), rest) * scale, np.zeros(6), method="hybr",
                   options={"xtol": 1e-15})
        if not sol.success and np.max(np.abs(sol.fun)) > 1e-6:
            raise IsolatorError(f"MuJoCo check: no static equilibrium ({sol.message})")
        return state(sol.x)

    def simulate(self, rtol: float = 1e-11, atol: float = 1e-14) -> MultibodyRun:
        """Run the scenario from its initial equilibrium at the scenario's samples."""
        sc = self.scenario
        t_eval = sc.simulation.sample_times()
        y0 = self.equilibrium(sc.initial_positions())
        states = solve_piecewise(self._derivative, y0, t_eval, sc.breakpoints, rtol=rtol, atol=atol)
        return MultibodyRun(t_eval, table_signals(states, y0), states)


def solve_piecewise(
    rhs: Callable[[float, np.ndarray, float], np.ndarray],
    y0: np.ndarray,
    t_eval: np.ndarray,
    breakpoints: Sequence[float],
    rtol: float,
    atol: float,
) -> np.ndarray:
    """Integrate with DOP853, restarting at every breakpoint, states at ``t_eval``.

    Parameters
    ----------
    rhs : callable
        ``rhs(t, y, piece_time)``; ``piece_time`` is the middle of the current
        segment, for one-sided profile evaluation.
    y0 : ndarray
        State at ``t_eval[0]``.
    t_eval : ndarray
        Increasing output times [s].
    breakpoints : sequence of float
        Times [s] where the right-hand side may jump.

    Returns
    -------
    ndarray (len(t_eval), len(y0))
    """
    cuts = [float(t_eval[0]), *[b for b in breakpoints if t_eval[0] < b < t_eval[-1]], float(t_eval[-1])]
    states = np.empty((t_eval.size, np.size(y0)))
    filled = np.zeros(t_eval.size, bool)
    y = np.asarray(y0, dtype=float)
    for a, b in itertools.pairwise(cuts):
        if b - a <= 0:
            continue
        mask = (t_eval >= a) & (t_eval <= b) & ~filled
        times = np.union1d(t_eval[mask], [b])
        sol = solve_ivp(rhs, (a, b), y, method="DOP853", t_eval=times, rtol=rtol, atol=atol, args=(0.5 * (a + b),))
        if not sol.success:
            raise IsolatorError(f"integration failed between {a:g} s and {b:g} s ({sol.message})")
        states[mask] = sol.y.T[np.isin(times, t_eval[mask])]
        filled |= mask
        y = sol.y[:, -1]
    return states
