"""Newton's and Euler's laws for the table and its carriages, written once in casadi.

:func:`newton_euler_residual` states Newton's and Euler's laws for the rigid
table carrying point-mass carriages whose motion relative to the table is
prescribed; every model variant (:mod:`isolator.model.variants`) and the
linearisation (:mod:`isolator.model.linearisation`) are built from it.
Frames and signals follow ``docs/scenario-format.md``.
"""

from __future__ import annotations

import casadi as ca

from isolator.model.blocks import solve_blocks
from isolator.model.elements.base import AttachmentMotion, IsolatorElement
from isolator.model.elements.spring_damper import SPRING_DAMPER, isolator_preloads
from isolator.model.flexible.coupling import ElasticState, modal_shapes

__all__ = ["attachment_motion", "carriage_kinematics", "carriage_paths", "newton_euler_residual", "solve_blocks"]


def attachment_motion(
    pos: ca.SX, rot: ca.SX, vel: ca.SX, w_body: ca.SX, prm: dict[str, ca.SX], ground: ca.SX | None = None,
    elastic: tuple[list[ca.DM], ca.SX, ca.SX] | None = None,
) -> AttachmentMotion:
    """The isolators' attachment points relative to their floor points (world axes) [m], [m/s].

    ``ground`` (12,): floor displacement [m], rotation about the world origin
    [rad] and their rates; the floor points move with the floor. ``elastic``: a bending top's shapes at the
    attachment points (3, modes) each, its modal coordinates and their rates; the points then move with the
    top's elastic translation too.
    """
    w_world = rot @ w_body
    stretches, rates = [], []
    for k in range(prm["positions"].shape[1]):
        s = prm["positions"][:, k]
        arm = rot @ (s if elastic is None else s + elastic[0][k] @ elastic[1])
        stretch, rate = pos + arm - s, vel + ca.cross(w_world, arm)
        if elastic is not None:  # the point's elastic velocity
            rate = rate + rot @ (elastic[0][k] @ elastic[2])
        if ground is not None:
            stretch = stretch - ground[0:3] - ca.cross(ground[3:6], s)
            rate = rate - ground[6:9] - ca.cross(ground[9:12], s)
        stretches.append(stretch)
        rates.append(rate)
    return AttachmentMotion(stretches, rates, pos, rot)


def carriage_paths(c: ca.SX, prm: dict[str, ca.SX], parents: tuple[int, ...]) -> list[tuple[ca.SX, ca.SX, ca.SX]]:
    """Each carriage's position, velocity and acceleration in the table frame from the mass centre
    [m, m/s, m/s^2], from its coordinates ``c`` (q, q', q'', 3 n) and its parents' (in carriage order)."""
    n = len(parents)
    zero = ca.SX.zeros(3, 1)
    d: dict[int, tuple[ca.SX, ca.SX, ca.SX]] = {}
    for i in _carriage_order(parents):
        base = d[parents[i]] if parents[i] != -1 else (zero, zero, zero)
        axis = prm["axes"][:, i]
        d[i] = (base[0] + prm["origins"][:, i] + axis * c[i], base[1] + axis * c[n + i],
                base[2] + axis * c[2 * n + i])
    return [d[i] for i in range(n)]


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
    zero = ca.SX.zeros(3, 1)
    out = {"m": ca.SX(0), "S": zero, "Sd": zero, "Sdd": zero, "Jc": ca.SX.zeros(3, 3),
           "Hd": zero, "B": ca.SX.zeros(3, 3)}
    paths = carriage_paths(c, prm, parents)
    for i in _carriage_order(parents):
        pos, vel, acc = paths[i]
        m = prm["masses"][i]
        out["m"] += m
        out["S"] += m * pos
        out["Sd"] += m * vel
        out["Sdd"] += m * acc
        out["Jc"] += m * (ca.dot(pos, pos) * ca.SX.eye(3) - pos @ pos.T)
        out["Hd"] += m * ca.cross(pos, acc)
        out["B"] += 2 * m * (ca.dot(pos, vel) * ca.SX.eye(3) - vel @ pos.T)
    return out


def _carriage_order(parents: tuple[int, ...]) -> list[int]:
    """Carriages parents first (the order the moments were always summed in)."""
    order: list[int] = []
    remaining = list(range(len(parents)))
    while remaining:
        for i in list(remaining):
            if parents[i] != -1 and parents[i] not in order:
                continue
            remaining.remove(i)
            order.append(i)
    return order


def newton_euler_residual(
    pos: ca.SX,
    rot: ca.SX,
    vel: ca.SX,
    w_body: ca.SX,
    acc_body: ca.SX,
    alpha_body: ca.SX,
    c: ca.SX | None,
    prm: dict[str, ca.SX],
    parents: tuple[int, ...],
    preload: bool = True,
    ground: ca.SX | None = None,
    actuator_forces: ca.SX | None = None,
    wrench: ca.SX | None = None,
    kin: dict[str, ca.SX] | None = None,
    element: IsolatorElement = SPRING_DAMPER,
    element_states: ca.SX | None = None,
    elastic: ElasticState | None = None,
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
    element : IsolatorElement
        The isolators' kind (:mod:`isolator.model.elements`).
    element_states : SX, optional
        Its internal states (the pneumatic element's chamber pressures [Pa]).
    elastic : ElasticState, optional
        A bending top's modal coordinates and the carriages' elastic terms
        (:mod:`isolator.model.flexible.coupling`): the isolators and actuators act
        at their elastically displaced points and load the modes.

    Returns
    -------
    SX (6,) or (6 + modes,)
        Table-frame components of [sum of m a - forces (N); moment balance
        about the table's mass centre (N m)]; zero when the motion obeys the
        laws. Linear in ``acc_body`` and ``alpha_body`` with the constant-form
        mass matrix [[m I, -[S]x], [[S]x, J + Jc]]. With ``elastic``, the modes'
        equations follow (:meth:`ElasticState.modal_rows`).
    """
    if kin is None:
        if c is None:
            raise ValueError("newton_euler_residual: give the carriage inputs c or their moments kin")
        kin = carriage_kinematics(c, prm, parents)
    m_tot = prm["table_mass"] + kin["m"]
    g_world = ca.vertcat(0, 0, -prm["gravity"])
    J = ca.diag(prm["inertia"])
    S, w = kin["S"], w_body

    force = m_tot * g_world
    moment = ca.SX.zeros(3, 1)
    load = isolator_preloads(prm, kin["m"]) if preload and element is SPRING_DAMPER else None
    structure = elastic.structure if elastic is not None else None
    shapes = modal_shapes(structure.isolators, structure) if structure is not None else []
    motion = attachment_motion(pos, rot, vel, w, prm, ground,
                               None if elastic is None else (shapes, elastic.eta, elastic.rate))
    modal_force = ca.SX.zeros(structure.n_modes if structure is not None else 0, 1)

    def act(point: ca.SX, shape: ca.DM | None, f: ca.SX) -> None:
        """A force ``f`` (world) at a table point; on a bending top at its displaced point, loading the modes."""
        nonlocal force, moment, modal_force
        force += f
        if elastic is None or shape is None:
            moment += ca.cross(rot @ point, f)
        else:
            moment += ca.cross(rot @ (point + shape @ elastic.eta), f)
            modal_force += shape.T @ (rot.T @ f)

    for k, f in enumerate(element.forces(prm, motion, element_states, load)):
        act(prm["positions"][:, k], shapes[k] if shapes else None, f)
    if actuator_forces is not None:
        at = modal_shapes(structure.actuators, structure) if structure is not None else []
        for k in range(actuator_forces.shape[0]):
            act(prm["actuator_positions"][:, k], at[k] if at else None,
                prm["actuator_directions"][:, k] * actuator_forces[k])
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
    if elastic is None:
        return ca.vertcat(translation, rotation)
    return ca.vertcat(translation + elastic.terms[0], rotation + elastic.terms[1], elastic.modal_rows(modal_force))
