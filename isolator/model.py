"""Equations of motion of the table and its carriages, written once in casadi.

One function, :func:`newton_euler_residual`, states Newton's and Euler's laws
for the rigid table carrying point-mass carriages whose motion relative to the
table is prescribed. Every model is built from it:

* the exact model (:func:`build_model` with ``kind="exact"``) solves the
  residual for the table's accelerations: finite rotations (quaternion state),
  the carriages' full absolute accelerations (Coriolis and centripetal terms),
  isolator forces along the world axes at the moving attachment points, with
  the isolators' static preload;
* the paper's small-angle model (``kind="paper"``) is its first-order
  expansion in the table's pose about the unloaded reference pose, with
  unloaded isolators, ``M(t) x'' + C(t) x' + K(t) x = F(t)`` as in Shin, Sun
  and Kim, eq. (11) and appendix. Linearising about the unloaded pose drops
  the product of the static sag with the rotation, i.e. the weight carried at
  attachment points below the mass centre, which lowers the rocking
  stiffness by about (total weight) x (mass-centre height above them).

Design parameters (masses, inertia, geometry, stiffness, damping, gravity) are
symbolic inputs ``p``, and the carriages' coordinates, velocities and
accelerations are inputs ``c``, so that sweeps and optimisers change numbers,
not models. Frames and signals follow ``docs/scenario-format.md``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import casadi as ca
import numpy as np

from .scenario import Scenario

__all__ = [
    "MODEL_KINDS",
    "Model",
    "ParameterLayout",
    "build_linearisation",
    "build_model",
    "carriage_kinematics",
    "newton_euler_residual",
    "pose_rotation",
]

MODEL_KINDS = ("exact", "paper")


# -- small rotation helpers (casadi) -----------------------------------------
def skew(v: ca.SX) -> ca.SX:
    """Cross-product matrix [v]x of a 3-vector."""
    return ca.vertcat(
        ca.horzcat(0, -v[2], v[1]),
        ca.horzcat(v[2], 0, -v[0]),
        ca.horzcat(-v[1], v[0], 0),
    )


def quaternion_to_matrix(qt: ca.SX) -> ca.SX:
    """Rotation matrix of a quaternion (w, x, y, z), normalised on the fly."""
    w, x, y, z = qt[0], qt[1], qt[2], qt[3]
    s = 2.0 / (w * w + x * x + y * y + z * z)
    return ca.vertcat(
        ca.horzcat(1 - s * (y * y + z * z), s * (x * y - w * z), s * (x * z + w * y)),
        ca.horzcat(s * (x * y + w * z), 1 - s * (x * x + z * z), s * (y * z - w * x)),
        ca.horzcat(s * (x * z - w * y), s * (y * z + w * x), 1 - s * (x * x + y * y)),
    )


def quaternion_rate(qt: ca.SX, w_body: ca.SX) -> ca.SX:
    """d/dt of a quaternion (w, x, y, z) for a body-frame angular velocity [rad/s]."""
    w, x, y, z = qt[0], qt[1], qt[2], qt[3]
    p, q, r = w_body[0], w_body[1], w_body[2]
    return 0.5 * ca.vertcat(
        -x * p - y * q - z * r,
        w * p + y * r - z * q,
        w * q + z * p - x * r,
        w * r + x * q - y * p,
    )


def cardan_matrix(th: ca.SX) -> ca.SX:
    """R = Rz(th[2]) Ry(th[1]) Rx(th[0]); equal to I + [th]x to first order."""
    cx, sx = ca.cos(th[0]), ca.sin(th[0])
    cy, sy = ca.cos(th[1]), ca.sin(th[1])
    cz, sz = ca.cos(th[2]), ca.sin(th[2])
    rx = ca.vertcat(ca.horzcat(1, 0, 0), ca.horzcat(0, cx, -sx), ca.horzcat(0, sx, cx))
    ry = ca.vertcat(ca.horzcat(cy, 0, sy), ca.horzcat(0, 1, 0), ca.horzcat(-sy, 0, cy))
    rz = ca.vertcat(ca.horzcat(cz, -sz, 0), ca.horzcat(sz, cz, 0), ca.horzcat(0, 0, 1))
    return rz @ ry @ rx


def pose_rotation(angles: np.ndarray) -> np.ndarray:
    """Numeric Rz Ry Rx of Cardan angles (rx, ry, rz) [rad], e.g. of an equilibrium pose, (3, 3)."""
    return np.asarray(cardan_matrix(ca.DM(np.asarray(angles, dtype=float))), dtype=float)


# -- parameters ---------------------------------------------------------------
@dataclass(frozen=True)
class ParameterLayout:
    """Names and order of the design-parameter vector ``p`` of a model structure.

    Attributes
    ----------
    n_carriages, n_isolators : int
    parents : tuple of int
        Parent index of each carriage (-1: the table); the structure of the chain.
    n_actuators : int
        Force actuators between ground and table.
    ground : bool
        Whether the floor moves (the inputs then hold its motion).
    names : tuple of str
        One name per entry of ``p``, e.g. ``isolators[2].stiffness.z``.

    Notes
    -----
    The model's input vector ``u`` holds, in order: the carriages' coordinates,
    velocities and accelerations (3 n); with ``ground``, the floor's
    displacement ``x, y, z`` [m], rotation ``rx, ry, rz`` [rad] (about the world
    origin) and their rates (12); the actuator forces [N] (``n_actuators``).
    """

    n_carriages: int
    n_isolators: int
    parents: tuple[int, ...]
    n_actuators: int = 0
    ground: bool = False
    names: tuple[str, ...] = field(init=False)

    def __post_init__(self) -> None:
        names = ["gravity", "table.mass", "table.inertia.x", "table.inertia.y", "table.inertia.z"]
        names += [f"carriages[{i}].mass" for i in range(self.n_carriages)]
        for key in ("axis", "origin"):
            names += [f"carriages[{i}].{key}.{a}" for i in range(self.n_carriages) for a in "xyz"]
        for key in ("position", "stiffness", "damping"):
            names += [f"isolators[{i}].{key}.{a}" for i in range(self.n_isolators) for a in "xyz"]
        for key in ("position", "direction"):
            names += [f"actuators[{i}].{key}.{a}" for i in range(self.n_actuators) for a in "xyz"]
        object.__setattr__(self, "names", tuple(names))

    @property
    def size(self) -> int:
        return len(self.names)

    @property
    def input_size(self) -> int:
        """Length of the model's input vector ``u``."""
        return 3 * self.n_carriages + (12 if self.ground else 0) + self.n_actuators

    @property
    def ground_slice(self) -> slice:
        """Where the floor's motion sits in ``u`` (empty without ``ground``)."""
        start = 3 * self.n_carriages
        return slice(start, start + (12 if self.ground else 0))

    @property
    def actuator_slice(self) -> slice:
        """Where the actuator forces sit in ``u``."""
        return slice(self.input_size - self.n_actuators, self.input_size)

    def rest_inputs(self, positions: np.ndarray) -> np.ndarray:
        """Inputs ``u`` with the carriages at rest at ``positions`` [m], the floor still, no forces."""
        q = np.asarray(positions, dtype=float).ravel()
        u = np.zeros(self.input_size)
        u[: self.n_carriages] = q
        return u

    @classmethod
    def of(cls, scenario: Scenario) -> ParameterLayout:
        return cls(
            len(scenario.carriages),
            len(scenario.isolators),
            scenario.parent_indices(),
            len(scenario.actuators),
            scenario.has_ground_motion,
        )

    def pack(self, scenario: Scenario) -> np.ndarray:
        """The parameter vector of a scenario with this structure."""
        if ParameterLayout.of(scenario) != self:
            raise ValueError("scenario does not have this model's structure")
        values = [scenario.gravity, scenario.table.mass, *scenario.table.inertia]
        values += [c.mass for c in scenario.carriages]
        values += [v for c in scenario.carriages for v in c.axis]
        values += [v for c in scenario.carriages for v in c.origin]
        for key in ("position", "stiffness", "damping"):
            values += [v for iso in scenario.isolators for v in getattr(iso, key)]
        for key in ("position", "direction"):
            values += [v for act in scenario.actuators for v in getattr(act, key)]
        return np.array(values, dtype=float)

    def unpack(self, p: ca.SX) -> dict[str, ca.SX]:
        """Split a symbolic parameter vector into named blocks."""
        n, m = self.n_carriages, self.n_isolators
        out: dict[str, ca.SX] = {}
        i = 0

        def take(name: str, size: int, cols: int = 1) -> None:
            nonlocal i
            block = p[i : i + size * cols]
            out[name] = ca.reshape(block, size, cols) if cols > 1 else block
            i += size * cols

        take("gravity", 1)
        take("table_mass", 1)
        take("inertia", 3)
        take("masses", n)
        take("axes", 3, n)
        take("origins", 3, n)
        take("positions", 3, m)
        take("stiffness", 3, m)
        take("damping", 3, m)
        take("actuator_positions", 3, self.n_actuators)
        take("actuator_directions", 3, self.n_actuators)
        sizes = {"axes": n, "origins": n, "actuator_positions": self.n_actuators,
                 "actuator_directions": self.n_actuators}
        for k in ("axes", "origins", "positions", "stiffness", "damping", "actuator_positions",
                  "actuator_directions"):
            if sizes.get(k, m) <= 1:
                out[k] = ca.reshape(out[k], 3, sizes.get(k, m))
        return out


# -- the physics --------------------------------------------------------------
def carriage_kinematics(c: ca.SX, prm: dict[str, ca.SX], parents: tuple[int, ...]) -> dict[str, ca.SX]:
    """Mass moments of the carriages in the table frame.

    Parameters
    ----------
    c : SX, (3 n,)
        Carriage coordinates q [m], velocities [m/s], accelerations [m/s^2].
    prm : dict
        Unpacked parameters (masses, axes, origins).
    parents : tuple of int
        Parent index per carriage (-1: table).

    Returns
    -------
    dict
        ``m`` total carriage mass [kg]; ``S, Sd, Sdd`` first mass moment and its
        table-frame rates [kg m, kg m/s, kg m/s^2]; ``Jc`` point-mass inertia
        about the table's mass centre [kg m^2]; ``Hd`` sum m d x d'' [N m];
        ``B`` the matrix with sum m d x (2 w x d') = B w [kg m^2/s].
    """
    n = len(parents)
    zero = ca.SX.zeros(3, 1)
    out = {"m": ca.SX(0), "S": zero, "Sd": zero, "Sdd": zero, "Jc": ca.SX.zeros(3, 3),
           "Hd": zero, "B": ca.SX.zeros(3, 3)}
    d: dict[int, tuple[ca.SX, ca.SX, ca.SX]] = {}
    remaining = list(range(n))
    while remaining:
        for i in list(remaining):
            if parents[i] != -1 and parents[i] not in d:
                continue
            remaining.remove(i)
            base = d[parents[i]] if parents[i] != -1 else (zero, zero, zero)
            axis = prm["axes"][:, i]
            pos = base[0] + prm["origins"][:, i] + axis * c[i]
            vel = base[1] + axis * c[n + i]
            acc = base[2] + axis * c[2 * n + i]
            d[i] = (pos, vel, acc)
            m = prm["masses"][i]
            out["m"] += m
            out["S"] += m * pos
            out["Sd"] += m * vel
            out["Sdd"] += m * acc
            out["Jc"] += m * (ca.dot(pos, pos) * ca.SX.eye(3) - pos @ pos.T)
            out["Hd"] += m * ca.cross(pos, acc)
            out["B"] += 2 * m * (ca.dot(pos, vel) * ca.SX.eye(3) - vel @ pos.T)
    return out


def _upper(m: ca.SX) -> ca.SX:
    """The upper triangle of a symmetric matrix, row by row."""
    n = m.shape[0]
    return ca.vertcat(*[m[i, j] for i in range(n) for j in range(i, n)])


def _symmetric(values: ca.SX, n: int) -> ca.SX:
    """Inverse of :func:`_upper`."""
    out = ca.SX.zeros(n, n)
    k = 0
    for i in range(n):
        for j in range(i, n):
            out[i, j] = out[j, i] = values[k]
            k += 1
    return out


#: time-only values of the staged exact model: (name, packed size); ``Jc`` and the inverse mass matrix
#: ``Minv`` are symmetric, stored as upper triangles
TIME_ONLY = (("S", 3), ("Sd", 3), ("Sdd", 3), ("Jc", 6), ("Hd", 3), ("B", 9), ("Minv", 21))


def _pack_time_only(kin: dict[str, ca.SX], inv_mass: ca.SX) -> ca.SX:
    parts = {**kin, "Jc": _upper(kin["Jc"]), "B": ca.vec(kin["B"]), "Minv": _upper(inv_mass)}
    return ca.vertcat(*[parts[name] for name, _ in TIME_ONLY])


def _unpack_time_only(packed: ca.SX, carriage_mass: ca.SX) -> tuple[dict[str, ca.SX], ca.SX]:
    """The carriage moments (with their constant total mass) and the inverse mass matrix."""
    out, i = {"m": carriage_mass}, 0
    for name, size in TIME_ONLY:
        block = packed[i : i + size]
        out[name] = {"Jc": lambda b: _symmetric(b, 3), "B": lambda b: ca.reshape(b, 3, 3),
                     "Minv": lambda b: _symmetric(b, 6)}.get(name, lambda b: b)(block)
        i += size
    inv_mass = out.pop("Minv")
    return out, inv_mass


def isolator_preloads(prm: dict[str, ca.SX], carriage_mass: ca.SX) -> ca.SX:
    """Vertical static force of each isolator at the reference pose [N], (3, m).

    Every isolator has the same free height: its zero-force point lies
    ``delta = g m_total / sum(k_z)`` above its attachment point at the
    reference pose (table mass centre at the origin, axes level), so the
    isolators together carry the whole weight there.
    """
    kz = prm["stiffness"][2, :]
    weight = prm["gravity"] * (prm["table_mass"] + carriage_mass)
    delta = weight / ca.fmax(ca.sum2(kz), 1e-300)
    m = kz.shape[1]
    return ca.vertcat(ca.SX.zeros(2, m), kz * delta)


def newton_euler_residual(
    pos: ca.SX,
    rot: ca.SX,
    vel: ca.SX,
    w_body: ca.SX,
    acc_body: ca.SX,
    alpha_body: ca.SX,
    c: ca.SX,
    prm: dict[str, ca.SX],
    parents: tuple[int, ...],
    preload: bool = True,
    ground: ca.SX | None = None,
    actuator_forces: ca.SX | None = None,
    wrench: ca.SX | None = None,
    kin: dict[str, ca.SX] | None = None,
) -> ca.SX:
    """Newton's and Euler's laws for the table with its carriages, table frame.

    Parameters
    ----------
    pos : SX (3,)
        Table mass centre from the reference pose, world [m].
    rot : SX (3, 3)
        Table orientation (table to world).
    vel : SX (3,)
        Velocity of the mass centre, world [m/s].
    w_body, alpha_body : SX (3,)
        Angular velocity [rad/s] and acceleration [rad/s^2], table frame.
    acc_body : SX (3,)
        Acceleration of the mass centre in table-frame components, R^T a [m/s^2].
    c : SX (3 n,)
        Carriage coordinates, velocities, accelerations.
    prm : dict
        Unpacked parameters.
    parents : tuple of int
        Carriage chain structure.
    preload : bool
        Whether isolators carry their static preload (False: unloaded springs).
    ground : SX (12,), optional
        Floor displacement [m], rotation about the world origin [rad] and their
        rates; the isolators' ground anchors move with the floor (their axes and
        preload stay along the world axes).
    actuator_forces : SX (n_a,), optional
        Actuator forces [N] along their world directions at their table points.
    wrench : SX (6,), optional
        Force [N] and moment [N m] applied at the table's mass centre, world axes.
    kin : dict, optional
        The carriages' moments (:func:`carriage_kinematics`) when already
        known; ``c`` is then not used.

    Returns
    -------
    SX (6,)
        Table-frame components of [sum of m a - forces (N); moment balance
        about the table's mass centre (N m)]; zero when the motion obeys the
        laws. Linear in ``acc_body`` and ``alpha_body`` with the constant-form
        mass matrix [[m I, -[S]x], [[S]x, J + Jc]].
    """
    if kin is None:
        kin = carriage_kinematics(c, prm, parents)
    m_tot = prm["table_mass"] + kin["m"]
    g_world = ca.vertcat(0, 0, -prm["gravity"])
    J = ca.diag(prm["inertia"])
    S, w = kin["S"], w_body

    force = m_tot * g_world
    moment = ca.SX.zeros(3, 1)
    load = isolator_preloads(prm, kin["m"]) if preload else None
    w_world = rot @ w
    for k in range(prm["positions"].shape[1]):
        s = prm["positions"][:, k]
        arm = rot @ s
        stretch, rate = pos + arm - s, vel + ca.cross(w_world, arm)
        if ground is not None:
            stretch = stretch - ground[0:3] - ca.cross(ground[3:6], s)
            rate = rate - ground[6:9] - ca.cross(ground[9:12], s)
        f = -prm["stiffness"][:, k] * stretch - prm["damping"][:, k] * rate
        if load is not None:
            f = f + load[:, k]
        force += f
        moment += ca.cross(arm, f)
    if actuator_forces is not None:
        for k in range(actuator_forces.shape[0]):
            f = prm["actuator_directions"][:, k] * actuator_forces[k]
            force += f
            moment += ca.cross(rot @ prm["actuator_positions"][:, k], f)
    if wrench is not None:
        force += wrench[0:3]
        moment += wrench[3:6]
    g_body = rot.T @ g_world
    rel = kin["Sdd"] + 2 * ca.cross(w, kin["Sd"]) + ca.cross(alpha_body, S) + ca.cross(w, ca.cross(w, S))
    translation = m_tot * acc_body + rel - rot.T @ force
    rotation = (
        (J + kin["Jc"]) @ alpha_body
        + ca.cross(w, (J + kin["Jc"]) @ w)
        + ca.cross(S, acc_body)
        + kin["Hd"]
        + kin["B"] @ w
        - rot.T @ moment
        - ca.cross(S, g_body)
    )
    return ca.vertcat(translation, rotation)


# -- models -------------------------------------------------------------------
@dataclass(frozen=True)
class Model:
    """A model's casadi functions for one scenario structure.

    Attributes
    ----------
    kind : str
        "exact" or "paper".
    layout : ParameterLayout
    n_states : int
    rhs : casadi.Function
        ``(x, c, p) -> dx/dt``.
    static_residual : casadi.Function
        ``(z, c, p) -> (r, dr/dz)`` with z = (position, Cardan angles) of the
        table at rest: zero at a static equilibrium.
    pose_state : casadi.Function
        ``(z) -> x`` the state at rest in pose z.
    state_jacobian : casadi.Function
        ``(x, c, p) -> d(dx/dt)/dx``.
    linear_matrices : casadi.Function or None
        The paper model's ``(c, p) -> (M, C, K, F)``.
    staged_inputs, staged_rhs : casadi.Function or None
        The right-hand side split in two: ``staged_inputs (c, p) -> v`` holds
        what depends on time only (the carriages' mass moments and the
        inverse mass matrix, then the floor's motion and the actuator forces)
        and ``staged_rhs (x, v, p) -> dx/dt`` the rest, so that ``v`` can be
        computed once per stage time for many runs (exact model; None for
        the paper model).
    """

    kind: str
    layout: ParameterLayout
    n_states: int
    rhs: ca.Function
    static_residual: ca.Function
    pose_state: ca.Function
    state_jacobian: ca.Function
    linear_matrices: ca.Function | None = None
    staged_inputs: ca.Function | None = None
    staged_rhs: ca.Function | None = None

    @property
    def tag(self) -> str:
        """Kind and structure in a name, e.g. ``exact_c2_i4_a0_g0``, for compiled functions and their cache."""
        lay = self.layout
        return f"{self.kind}_c{lay.n_carriages}_i{lay.n_isolators}_a{lay.n_actuators}_g{int(lay.ground)}"


def build_model(layout: ParameterLayout, kind: str = "exact") -> Model:
    """Build the casadi functions of a model for a scenario structure.

    Parameters
    ----------
    layout : ParameterLayout
        Structure (numbers of carriages and isolators, carriage chain).
    kind : {"exact", "paper"}

    Returns
    -------
    Model
    """
    if kind not in MODEL_KINDS:
        raise ValueError(f"model: must be one of {', '.join(MODEL_KINDS)}, got '{kind}'")
    n = layout.n_carriages
    p = ca.SX.sym("p", layout.size)
    c = ca.SX.sym("u", layout.input_size)
    prm = layout.unpack(p)
    parents = layout.parents
    z = ca.SX.sym("z", 6)
    zero3 = ca.SX.zeros(3, 1)
    rest = ca.vertcat(c[:n], ca.SX.zeros(layout.input_size - n, 1))
    extra = {
        "ground": c[layout.ground_slice] if layout.ground else None,
        "actuator_forces": c[layout.actuator_slice] if layout.n_actuators else None,
    }
    rest_extra = {
        "ground": rest[layout.ground_slice] if layout.ground else None,
        "actuator_forces": rest[layout.actuator_slice] if layout.n_actuators else None,
    }

    if kind == "exact":
        x = ca.SX.sym("x", 13)
        pos, qt, vel, w = x[0:3], x[3:7], x[7:10], x[10:13]
        rot = quaternion_to_matrix(qt)
        acc_vars = ca.SX.sym("a", 6)
        res = newton_euler_residual(
            pos, rot, vel, w, acc_vars[:3], acc_vars[3:], c[: 3 * n], prm, parents, **extra
        )
        mass = ca.jacobian(res, acc_vars)
        bias = ca.substitute(res, acc_vars, ca.SX.zeros(6, 1))
        accel = _solve_blocks(mass, -bias)
        xdot = ca.vertcat(vel, quaternion_rate(qt, w), rot @ accel[:3], accel[3:])
        staged = _staged(layout, x, rot, acc_vars, c, p, prm, extra)
        static = newton_euler_residual(
            z[:3], cardan_matrix(z[3:]), zero3, zero3, zero3, zero3, rest[: 3 * n], prm, parents, **rest_extra
        )
        pose = ca.vertcat(z[:3], _cardan_to_quaternion(z[3:]), ca.SX.zeros(6, 1))
        linear = None
    else:
        x = ca.SX.sym("x", 12)
        gen = ca.SX.sym("g", 18)  # position/angles, rates, accelerations
        pos, th = gen[0:3], gen[3:6]
        rot = cardan_matrix(th)
        body = newton_euler_residual(
            pos, rot, gen[6:9], gen[9:12], rot.T @ gen[12:15], gen[15:18], c[: 3 * n], prm, parents,
            preload=False, **extra,
        )
        res = ca.vertcat(rot @ body[:3], rot @ body[3:])  # world frame, as the paper writes it
        at_zero = {"x": ca.SX.zeros(18, 1)}
        mass = ca.substitute(ca.jacobian(res, gen[12:18]), gen, at_zero["x"])
        damp = ca.substitute(ca.jacobian(res, gen[6:12]), gen, at_zero["x"])
        stiff = ca.substitute(ca.jacobian(res, gen[0:6]), gen, at_zero["x"])
        force = -ca.substitute(res, gen, at_zero["x"])
        accel = ca.solve(mass, force - damp @ x[6:12] - stiff @ x[0:6])
        xdot = ca.vertcat(x[6:12], accel)
        rest_stiff = ca.substitute(stiff, c, rest)
        rest_force = ca.substitute(force, c, rest)
        static = rest_stiff @ z - rest_force
        pose = ca.vertcat(z, ca.SX.zeros(6, 1))
        staged = (None, None)
        linear = ca.Function(
            "paper_matrices", [c, p], [mass, damp, stiff, force], ["c", "p"], ["M", "C", "K", "F"]
        )

    rhs = ca.Function("rhs", [x, c, p], [xdot], ["x", "c", "p"], ["xdot"])
    static_fn = ca.Function(
        "static", [z, c, p], [static, ca.jacobian(static, z)], ["z", "c", "p"], ["r", "drdz"]
    )
    pose_fn = ca.Function("pose_state", [z], [pose], ["z"], ["x"])
    jac = ca.Function("state_jacobian", [x, c, p], [ca.jacobian(xdot, x)], ["x", "c", "p"], ["A"])
    return Model(kind, layout, int(x.shape[0]), rhs, static_fn, pose_fn, jac, linear, *staged)


def _staged(
    layout: ParameterLayout,
    x: ca.SX,
    rot: ca.SX,
    acc_vars: ca.SX,
    c: ca.SX,
    p: ca.SX,
    prm: dict[str, ca.SX],
    extra: dict[str, ca.SX | None],
) -> tuple[ca.Function, ca.Function]:
    """The exact model's right-hand side with its time-only part (moments, inverse mass matrix) as inputs."""
    n = layout.n_carriages
    size = sum(k for _, k in TIME_ONLY)
    rest = c[3 * n :]
    v = ca.SX.sym("v", size + rest.shape[0])
    kin, inv_mass = _unpack_time_only(v[:size], ca.sum1(prm["masses"]))
    moved = {k: None if e is None else ca.substitute(e, rest, v[size:]) for k, e in extra.items()}
    pos, qt, vel, w = x[0:3], x[3:7], x[7:10], x[10:13]
    res = newton_euler_residual(
        pos, rot, vel, w, acc_vars[:3], acc_vars[3:], None, prm, layout.parents, kin=kin, **moved
    )
    bias = ca.substitute(res, acc_vars, ca.SX.zeros(6, 1))
    accel = -inv_mass @ bias
    xdot = ca.vertcat(vel, quaternion_rate(qt, w), rot @ accel[:3], accel[3:])
    moments = carriage_kinematics(c[: 3 * n], prm, layout.parents)
    mass = ca.jacobian(newton_euler_residual(
        pos, rot, vel, w, acc_vars[:3], acc_vars[3:], None, prm, layout.parents, kin=moments, **extra
    ), acc_vars)
    inputs = ca.vertcat(_pack_time_only(moments, _solve_blocks(mass, ca.SX.eye(6))), rest)
    return (
        ca.Function("staged_inputs", [c, p], [inputs], ["c", "p"], ["v"]),
        ca.Function("staged_rhs", [x, v, p], [xdot], ["x", "v", "p"], ["xdot"]),
    )


@lru_cache(maxsize=32)
def build_linearisation(layout: ParameterLayout) -> ca.Function:
    """The exact model's first-order expansion about a rest pose, as a casadi function.

    Coordinates: ``d`` = (mass-centre displacement [m], small rotation vector
    [rad] with ``R = (I + [phi]x) R0``), both world axes. The Jacobians of the one
    :func:`newton_euler_residual` (world components) give

    ``M d'' + C d' + K d + G0 g + G1 g' + Bw w + Ba f = 0``

    for floor motion ``g`` (6: translations, rotations about the world origin),
    a wrench ``w`` at the mass centre (force, moment; world axes) and actuator
    forces ``f``.

    Returns
    -------
    casadi.Function
        ``(z0, c, p) -> (M, C, K, G0, G1, Bw, Ba)`` with ``z0`` the rest pose
        (position [m], Cardan angles [rad]) and ``c`` the carriages' inputs
        (q, q', q'').
    """
    n = layout.n_carriages
    p = ca.SX.sym("p", layout.size)
    c = ca.SX.sym("c", 3 * n)
    z0 = ca.SX.sym("z0", 6)
    d, v, a = ca.SX.sym("d", 6), ca.SX.sym("v", 6), ca.SX.sym("a", 6)
    g = ca.SX.sym("g", 12)
    w = ca.SX.sym("w", 6)
    f = ca.SX.sym("f", layout.n_actuators)
    prm = layout.unpack(p)
    rot = cardan_matrix(d[3:]) @ cardan_matrix(z0[3:])
    body = newton_euler_residual(
        z0[:3] + d[:3], rot, v[:3], rot.T @ v[3:], rot.T @ a[:3], rot.T @ a[3:], c, prm, layout.parents,
        ground=g, actuator_forces=f if layout.n_actuators else None, wrench=w,
    )
    res = ca.vertcat(rot @ body[:3], rot @ body[3:])
    deviations = ca.vertcat(d, v, a, g, w, f)  # all zero at the rest pose

    def jac(var: ca.SX) -> ca.SX:
        return ca.substitute(ca.jacobian(res, var), deviations, ca.SX.zeros(deviations.shape))

    gj = jac(g)
    outs = [jac(a), jac(v), jac(d), gj[:, :6], gj[:, 6:], jac(w), jac(f)]
    return ca.Function(
        "linearise", [z0, c, p], outs, ["z0", "c", "p"], ["M", "C", "K", "G0", "G1", "Bw", "Ba"]
    )


def _solve_blocks(mass: ca.SX, rhs: ca.SX) -> ca.SX:
    """Solve the 6x6 (translation, rotation) system by its 3x3 Schur complement."""
    a_tt, a_tr = mass[:3, :3], mass[:3, 3:]
    a_rt, a_rr = mass[3:, :3], mass[3:, 3:]
    inv_tt = ca.inv(a_tt)
    schur = a_rr - a_rt @ inv_tt @ a_tr
    alpha = ca.solve(schur, rhs[3:, :] - a_rt @ inv_tt @ rhs[:3, :])
    acc = inv_tt @ (rhs[:3, :] - a_tr @ alpha)
    return ca.vertcat(acc, alpha)


def _cardan_to_quaternion(th: ca.SX) -> ca.SX:
    """Quaternion (w, x, y, z) of Rz(th2) Ry(th1) Rx(th0)."""
    cr, sr = ca.cos(th[0] / 2), ca.sin(th[0] / 2)
    cp, sp = ca.cos(th[1] / 2), ca.sin(th[1] / 2)
    cy, sy = ca.cos(th[2] / 2), ca.sin(th[2] / 2)
    return ca.vertcat(
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    )
