"""An independent multibody check of a scenario, built in MuJoCo.

The table is a free body, each carriage a body on a slide joint (chained as in
the scenario), and each isolator a force applied at a site on the table. The
carriages' joint motion is prescribed: at every instant MuJoCo gives the joint
space mass matrix and bias forces, and the table's accelerations follow from
the partition ``M_tt a_t = f_t - b_t - M_tc a_c`` with the carriages'
prescribed accelerations ``a_c``. The states are integrated with scipy's
DOP853 at tight tolerance, restarted at the profiles' breakpoints
(:func:`solve_piecewise`). MuJoCo also finds its own static equilibria (a
root of its accelerations), so that nothing but the scenario is shared with
the casadi model.

Pneumatic scenarios: the chamber pressures (:class:`AirChambers`, the
contract's equations in numpy) are integrated in the same right-hand side as
the table; each air spring pushes along world +z at its site, each group's
valve reads the height of a sensor site. The run starts at the reference
pose (every chamber at its rest volume) with the group pressures that MuJoCo's
own generalized forces balance there.

Needs the optional dependency ``mujoco`` (``pip install isolator[check]``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import root

from isolator.errors import IsolatorError, ScenarioError
from isolator.model.signals import table_signals
from isolator.scenario.definitions import Isolator, Scenario
from isolator.scenario.pneumatic import PneumaticIsolator
from isolator.validation.piecewise import solve_piecewise
from isolator.validation.pneumatic_chambers import AirChambers

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
    chambers : ndarray (N, chambers) or None
        Pneumatic runs: absolute chamber pressures [Pa], every spring chamber
        then every damping chamber (the layout of ``Response.states[:, 13:]``).
    pressures : ndarray (isolators, N) or None
        Pneumatic runs: spring chamber gauge pressures ``p1 - p_atm`` [Pa].
    heights : ndarray (groups, N) or None
        Pneumatic runs: each leveling group's sensor height [m].
    """

    t: np.ndarray
    signals: np.ndarray
    states: np.ndarray
    chambers: np.ndarray | None = None
    pressures: np.ndarray | None = None
    heights: np.ndarray | None = None


def _vec(v: Iterable[float]) -> str:
    return " ".join(f"{float(x):.17g}" for x in v)


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
        self.isolators: tuple[Isolator | PneumaticIsolator, ...] = tuple(scenario.isolators)
        self.air = AirChambers(scenario) if scenario.is_pneumatic else None
        self.forces = forces
        self.model = mujoco.MjModel.from_xml_string(self._xml())
        self.data = mujoco.MjData(self.model)
        self.n_c = len(scenario.carriages)
        self.site_ids = [
            mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_SITE, f"iso{k}")
            for k in range(len(scenario.isolators))
        ]
        self.sensor_ids = [
            mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_SITE, f"sensor{j}") for j in range(len(scenario.leveling))
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
        ) + "".join(f'<site name="sensor{j}" pos="{_vec(g.sensor)} 0"/>' for j, g in enumerate(sc.leveling)) + "".join(
            f'<site name="point{j}" pos="{_vec(pt.position)}"/>' for j, pt in enumerate(sc.points))
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
        y : ndarray (13,) or (13 + chambers,)
            Position, quaternion (w, x, y, z), world velocity, table-frame angular
            velocity; pneumatic tables: then the chamber pressures [Pa] (absolute).
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
        return self._dynamics(y, carriages, t, ground, piece_time)[0]

    def _dynamics(
        self,
        y: np.ndarray,
        carriages: np.ndarray,
        t: float = 0.0,
        ground: np.ndarray | None = None,
        piece_time: float | None = None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Table accelerations (6,), and each isolator's vertical stroke and its rate [m], [m/s]."""
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
        n_iso = len(self.scenario.isolators)
        stroke, stroke_rate = np.zeros(n_iso), np.zeros(n_iso)
        lift = self.air.vertical_forces(y[13:]) if self.air is not None else self.preload
        for k, iso in enumerate(self.isolators):
            sid = self.site_ids[k]
            point = d.site_xpos[sid].copy()
            mj.mj_objectVelocity(m, d, mj.mjtObj.mjOBJ_SITE, sid, vel6, 0)
            anchor = np.asarray(iso.position, dtype=float)
            disp, rate = point - anchor, vel6[3:6].copy()
            if ground is not None:
                disp -= ground[0:3] + np.cross(ground[3:6], anchor)
                rate -= ground[6:9] + np.cross(ground[9:12], anchor)
            stroke[k], stroke_rate[k] = disp[2], rate[2]
            if isinstance(iso, PneumaticIsolator):
                stiffness, damping = np.r_[iso.horizontal_stiffness, 0.0], np.r_[iso.horizontal_damping, 0.0]
            else:
                stiffness, damping = np.asarray(iso.stiffness), np.asarray(iso.damping)
            f = -stiffness * disp - damping * rate
            f[2] += lift[k]
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
        acc = np.linalg.solve(self._full_m[free, free], rhs[free] - self._full_m[free, :] @ a_c)
        return acc, stroke, stroke_rate

    def sensor_heights(self) -> np.ndarray:
        """Each group's sensor height [m]: world z of its site at MuJoCo's current positions."""
        return np.array([self.data.site_xpos[sid][2] for sid in self.sensor_ids])

    def point_positions(self, states: np.ndarray) -> np.ndarray:
        """World positions (points, 3, N) [m] of the scenario's ``[[points]]`` sites for table states (N, >= 7)
        (position, quaternion w, x, y, z), by MuJoCo's kinematics."""
        ids = [self.mj.mj_name2id(self.model, self.mj.mjtObj.mjOBJ_SITE, f"point{j}")
               for j in range(len(self.scenario.points))]
        out = np.empty((len(ids), 3, len(states)))
        for i, y in enumerate(np.asarray(states, dtype=float)):
            self.data.qpos[0:7] = np.r_[y[0:3], y[3:7] / np.linalg.norm(y[3:7])]
            self.mj.mj_kinematics(self.model, self.data)
            out[:, :, i] = [self.data.site_xpos[sid] for sid in ids]
        return out

    def _fill_mass_matrix(self) -> None:
        """Dense joint-space mass matrix (MuJoCo 3 and 4 spell the call differently)."""
        mj, m, d = self.mj, self.model, self.data
        if hasattr(d, "qM"):
            mj.mj_fullM(m, self._full_m, d.qM)
        else:
            mj.mj_fullM(m, d, self._full_m)

    def _derivative(self, t: float, y: np.ndarray, piece_time: float) -> np.ndarray:
        acc, stroke, stroke_rate = self._dynamics(y, self._carriages(t, piece_time), t, piece_time=piece_time)
        qw, qx, qy, qz = y[3:7]
        p, q, r = y[10:13]
        qdot = 0.5 * np.array(
            [-qx * p - qy * q - qz * r, qw * p + qy * r - qz * q, qw * q + qz * p - qx * r, qw * r + qx * q - qy * p]
        )
        if self.air is None:
            return np.concatenate([y[7:10], qdot, acc])
        chambers = self.air.rates(y[13:], stroke, stroke_rate, self.sensor_heights())
        return np.concatenate([y[7:10], qdot, acc, chambers])

    # -- statics and runs --------------------------------------------------------
    def equilibrium(self, positions: np.ndarray) -> np.ndarray:
        """The table's rest state (13,) with carriages parked at ``positions`` [m] (spring-damper isolators)."""
        if self.air is not None:
            raise ScenarioError("isolators: a pneumatic table rests at its reference pose (see initial_state)")
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

    def rest_pressures(self, positions: np.ndarray) -> np.ndarray:
        """Gauge pressure of each leveling group [Pa] holding the table at the reference pose.

        MuJoCo's generalized forces at the reference pose (carriages parked at
        ``positions`` [m]): the table dofs' gravity and bias against each
        group's air springs at unit gauge pressure; vertical force and the
        two tilting moments give three equations in the three pressures.
        """
        if self.air is None:
            raise ScenarioError("isolators: rest pressures need a pneumatic scenario")
        mj, m, d = self.mj, self.model, self.data
        d.qpos[:], d.qvel[:] = 0.0, 0.0
        d.qpos[3] = 1.0
        for i in range(self.n_c):
            d.qpos[self.joint_qpos[i]] = positions[i]
        mj.mj_fwdPosition(m, d)
        mj.mj_fwdVelocity(m, d)
        unit = np.zeros((6, len(self.scenario.leveling)))
        per_group = self.air.group_areas()
        for k in range(len(self.scenario.isolators)):
            d.qfrc_applied[:] = 0.0
            point = d.site_xpos[self.site_ids[k]].copy()
            mj.mj_applyFT(m, d, np.array([0.0, 0.0, 1.0]), np.zeros(3), point, self.table_id, d.qfrc_applied)
            unit += np.outer(d.qfrc_applied[0:6], per_group[k])
        rows = [2, 3, 4]  # force along z, moments about x and y (world = table frame here)
        return np.asarray(np.linalg.solve(unit[rows], d.qfrc_bias[rows]), dtype=float)

    def initial_state(self) -> np.ndarray:
        """The run's initial state: the rest state, and for pneumatic tables the chamber pressures [Pa]."""
        positions = self.scenario.initial_positions()
        if self.air is None:
            return self.equilibrium(positions)
        pose = np.r_[np.zeros(3), 1.0, np.zeros(9)]
        return np.r_[pose, self.air.initial(self.rest_pressures(positions))]

    def simulate(self, rtol: float = 1e-11, atol: float = 1e-14, max_step: float = np.inf) -> MultibodyRun:
        """Run the scenario from its initial equilibrium at the scenario's samples.

        Parameters
        ----------
        rtol, atol : float
            DOP853 tolerances; ``atol`` applies to the table's states [m, rad, m/s,
            rad/s]; the chamber pressures get ``atol`` times the atmosphere [Pa].
        max_step : float
            Longest integration step [s].
        """
        sc = self.scenario
        t_eval = sc.simulation.sample_times()
        y0 = self.initial_state()
        tolerance = np.full(y0.size, atol)
        if self.air is not None:
            tolerance[13:] = atol * self.air.p_atm
        states = solve_piecewise(self._derivative, y0, t_eval, sc.breakpoints, rtol=rtol, atol=tolerance,
                                 max_step=max_step)
        if self.air is None:
            return MultibodyRun(t_eval, table_signals(states, y0), states)
        heights = np.empty((len(sc.leveling), t_eval.size))
        for i, y in enumerate(states):
            self.data.qpos[0:7] = y[0:7] / np.r_[1.0, 1.0, 1.0, np.full(4, np.linalg.norm(y[3:7]))]
            self.mj.mj_kinematics(self.model, self.data)
            heights[:, i] = self.sensor_heights()
        table = states[:, :13]
        return MultibodyRun(t_eval, table_signals(table, y0[:13]), table, states[:, 13:],
                            self.air.gauge(states[:, 13:]), heights)
