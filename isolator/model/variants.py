"""Model variants: the exact rigid-body model and the paper's small-angle model, as objects.

Both are built from the one residual (:func:`isolator.model.residual.newton_euler_residual`):

* :data:`EXACT` solves the residual for the table's accelerations: finite
  rotations (quaternion state), the carriages' full absolute accelerations
  (Coriolis and centripetal terms), isolator forces along the world axes at
  the moving attachment points, with the isolators' static preload;
* :data:`PAPER` is its first-order expansion in the table's pose about the
  unloaded reference pose, with unloaded isolators,
  ``M(t) x'' + C(t) x' + K(t) x = F(t)`` as in Shin, Sun and Kim, eq. (11) and
  appendix. Linearising about the unloaded pose drops the product of the
  static sag with the rotation, i.e. the weight carried at attachment points
  below the mass centre, which lowers the rocking stiffness by about (total
  weight) x (mass-centre height above them).

Design parameters (masses, inertia, geometry, stiffness, damping, gravity) are
symbolic inputs ``p``, and the carriages' coordinates, velocities and
accelerations are inputs ``c``, so that sweeps and optimisers change numbers,
not models. A variant is chosen by object or, at the API's edge, by name
(:func:`model_variant`).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import casadi as ca
import numpy as np

from isolator.errors import ParameterError
from isolator.model.flexible_equations import flexible_equations
from isolator.model.parameters import ParameterLayout
from isolator.model.pneumatic_statics import (
    element_of,
    element_rates,
    level_residual,
    pneumatic_tag,
    rest_element_states,
)
from isolator.model.residual import newton_euler_residual, solve_blocks
from isolator.model.rotations import cardan_matrix, cardan_to_quaternion, quaternion_rate, quaternion_to_matrix
from isolator.model.signals import exact_sensed_motion, table_signals
from isolator.model.staging import staged_functions
from isolator.scenario.arguments import check_public

__all__ = [
    "EXACT",
    "MODEL_KINDS",
    "MODEL_VARIANTS",
    "PAPER",
    "ExactModel",
    "Model",
    "ModelVariant",
    "PaperModel",
    "build_model",
    "model_variant",
]


@dataclass(frozen=True)
class Model:
    """A model's casadi functions for one scenario structure.

    Attributes
    ----------
    variant : ModelVariant
        Which equations (:data:`EXACT` or :data:`PAPER`).
    layout : ParameterLayout
    n_states : int
    rhs : casadi.Function
        ``(x, c, p) -> dx/dt``.
    static_residual : casadi.Function
        ``(z, c, p) -> (r, dr/dz)`` with z = (position, Cardan angles) of the
        table at rest, then for pneumatic tables each leveling group's gauge
        pressure [Pa]: zero at a static equilibrium (pneumatic: with every
        height sensor at zero, the level rest pose).
    pose_state : casadi.Function
        ``(z, p) -> x`` the state at rest in pose z.
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

    variant: ModelVariant
    layout: ParameterLayout
    n_states: int
    rhs: ca.Function
    static_residual: ca.Function
    pose_state: ca.Function
    state_jacobian: ca.Function
    linear_matrices: ca.Function | None = None
    staged_inputs: ca.Function | None = None
    staged_rhs: ca.Function | None = None

    def __hash__(self) -> int:
        return self._hash

    @cached_property
    def _hash(self) -> int:
        """The hash of the fields that tell models apart (caches keyed by a model hash it on every call; the
        dataclass's own hash went through seven casadi functions each time)."""
        return hash((self.variant.name, self.layout, self.n_states))

    @cached_property
    def n_static(self) -> int:
        """Unknowns of the static residual: 6 (pose), plus 3 group pressures for pneumatic tables."""
        return int(self.static_residual.size1_in(0))

    @property
    def kind(self) -> str:
        """The variant's name, ``"exact"`` or ``"paper"``."""
        return self.variant.name

    @property
    def tag(self) -> str:
        """Kind and structure in a name, e.g. ``exact_c2_i4_a0_g0``, for compiled functions and their cache."""
        lay = self.layout
        tag = f"{self.kind}_c{lay.n_carriages}_i{lay.n_isolators}_a{lay.n_actuators}_g{int(lay.ground)}"
        if lay.pneumatic is not None:
            tag += "_pn" + pneumatic_tag(lay.pneumatic)
        if lay.flexible is not None:
            tag += f"_fl{lay.flexible.n_modes}_{lay.flexible.digest}"
        return tag



class ModelVariant(ABC):
    """The equations a model is built from, and how its states map to the table's signals.

    Add a variant by subclassing this and registering an instance in :data:`MODEL_VARIANTS`.
    """

    #: the variant's name (``--model`` on the command line)
    name: str

    @abstractmethod
    def equations(self, layout: ParameterLayout, sym: _Symbols) -> _Equations:
        """The state, its rate, the static residual in the rest pose ``sym.z``, the rest state of a pose,
        the staged right-hand side (or None) and the linear matrices (or None)."""

    @abstractmethod
    def sensed_motion(self, x: Any, reference: Any) -> Any:
        """The table's motion as ideal inertial sensors report it, (12,), casadi (SX or MX): displacement
        [m] and rotation vector [rad] from the state ``reference``, velocity [m/s], angular velocity [rad/s]."""

    @abstractmethod
    def signals(self, states: np.ndarray, reference: np.ndarray) -> np.ndarray:
        """The six table signals (6, N) of states (N, n_states) relative to ``reference`` (one state or
        one per row), numpy."""

    @abstractmethod
    def motion(self, vector: np.ndarray) -> np.ndarray:
        """Six magnitudes (x .. rz) of a state-space vector's displacement part, comparable across axes."""

    def build(self, layout: ParameterLayout) -> Model:
        """Build the casadi functions of this variant for a scenario structure."""
        sym = _Symbols.of(layout)
        eq = self.equations(layout, sym)
        x, c, p, z = eq.x, sym.c, sym.p, sym.z
        rhs = ca.Function("rhs", [x, c, p], [eq.xdot], ["x", "c", "p"], ["xdot"])
        static_fn = ca.Function(
            "static", [z, c, p], [eq.static, ca.jacobian(eq.static, z)], ["z", "c", "p"], ["r", "drdz"]
        )
        pose_fn = ca.Function("pose_state", [z, p], [eq.pose], ["z", "p"], ["x"])
        jac = ca.Function("state_jacobian", [x, c, p], [ca.jacobian(eq.xdot, x)], ["x", "c", "p"], ["A"])
        return Model(self, layout, int(x.shape[0]), rhs, static_fn, pose_fn, jac, eq.linear, *eq.staged)


@dataclass(frozen=True)
class _Symbols:
    """The symbols every variant's equations are written in."""

    p: ca.SX
    c: ca.SX
    z: ca.SX
    prm: dict[str, ca.SX]
    rest: ca.SX
    extra: dict[str, ca.SX | None]
    rest_extra: dict[str, ca.SX | None]

    @classmethod
    def of(cls, layout: ParameterLayout) -> _Symbols:
        n = layout.n_carriages
        p = ca.SX.sym("p", layout.size)
        c = ca.SX.sym("u", layout.input_size)
        rest = ca.vertcat(c[:n], ca.SX.zeros(layout.input_size - n, 1))

        def extra(u: ca.SX) -> dict[str, ca.SX | None]:
            return {
                "ground": u[layout.ground_slice] if layout.ground else None,
                "actuator_forces": u[layout.actuator_slice] if layout.n_actuators else None,
            }

        n_static = 6 + (len(layout.pneumatic.groups) if layout.pneumatic is not None else 0)
        n_static += layout.flexible.n_modes if layout.flexible is not None else 0
        return cls(p, c, ca.SX.sym("z", n_static), layout.unpack(p), rest, extra(c), extra(rest))


@dataclass(frozen=True)
class _Equations:
    x: ca.SX
    xdot: ca.SX
    static: ca.SX
    pose: ca.SX
    staged: tuple[ca.Function | None, ca.Function | None] = (None, None)
    linear: ca.Function | None = None


@dataclass(frozen=True)
class ExactModel(ModelVariant):
    """Finite rotations (quaternion state, 13 states), preloaded isolators, full carriage accelerations."""

    name: str = "exact"

    def equations(self, layout: ParameterLayout, sym: _Symbols) -> _Equations:
        n, c, p, prm, z, rest = layout.n_carriages, sym.c, sym.p, sym.prm, sym.z, sym.rest
        parents, extra, rest_extra = layout.parents, sym.extra, sym.rest_extra
        if layout.flexible is not None:
            flex = flexible_equations(layout.flexible, parents, c, p, prm, z, rest, extra, rest_extra)
            return _Equations(flex.x, flex.xdot, flex.static, flex.pose)  # no staged form (see its module)
        zero3 = ca.SX.zeros(3, 1)
        element = element_of(layout)
        x = ca.SX.sym("x", 13 + element.n_states(layout.pneumatic))
        pos, qt, vel, w, inner = x[0:3], x[3:7], x[7:10], x[10:13], x[13:]
        states = inner if inner.shape[0] else None
        rot = quaternion_to_matrix(qt)
        acc_vars = ca.SX.sym("a", 6)
        res = newton_euler_residual(
            pos, rot, vel, w, acc_vars[:3], acc_vars[3:], c[: 3 * n], prm, parents,
            ground=extra["ground"], actuator_forces=extra["actuator_forces"],
            element=element, element_states=states,
        )
        mass = ca.jacobian(res, acc_vars)
        bias = ca.substitute(res, acc_vars, ca.SX.zeros(6, 1))
        accel = solve_blocks(mass, -bias)
        inner_rates = element_rates(layout, prm, pos, rot, vel, w, inner, extra["ground"])
        xdot = ca.vertcat(vel, quaternion_rate(qt, w), rot @ accel[:3], accel[3:], inner_rates)
        staged = staged_functions(layout, x, rot, acc_vars, c, p, prm, extra)
        pose_z = z[:6]
        rest_states = rest_element_states(layout, prm, z[6:]) if states is not None else None
        static = newton_euler_residual(
            pose_z[:3], cardan_matrix(pose_z[3:]), zero3, zero3, zero3, zero3, rest[: 3 * n], prm, parents,
            ground=rest_extra["ground"], actuator_forces=rest_extra["actuator_forces"],
            element=element, element_states=rest_states,
        )
        if layout.pneumatic is not None:
            static = ca.vertcat(static, level_residual(layout, prm, pose_z))
        pose = ca.vertcat(pose_z[:3], cardan_to_quaternion(pose_z[3:]), ca.SX.zeros(6, 1))
        if rest_states is not None:
            pose = ca.vertcat(pose, rest_states)
        return _Equations(x, xdot, static, pose, staged)

    def sensed_motion(self, x: Any, reference: Any) -> Any:
        return exact_sensed_motion(x, reference)

    def signals(self, states: np.ndarray, reference: np.ndarray) -> np.ndarray:
        return table_signals(states, reference)

    def motion(self, vector: np.ndarray) -> np.ndarray:
        v = np.abs(vector)
        return np.concatenate([v[0:3], 2 * v[4:7]])


@dataclass(frozen=True)
class PaperModel(ModelVariant):
    """The paper's small-angle model (12 states: position, Cardan angles, rates), unloaded isolators."""

    name: str = "paper"

    def equations(self, layout: ParameterLayout, sym: _Symbols) -> _Equations:
        n, c, p, prm, z, rest = layout.n_carriages, sym.c, sym.p, sym.prm, sym.z, sym.rest
        parents, extra = layout.parents, sym.extra
        if layout.pneumatic is not None:
            raise ParameterError(
                "model: the paper's model is for spring-damper isolators; use model='exact' for pneumatic ones"
            )
        if layout.flexible is not None:
            raise ParameterError("model: the paper's model has a rigid top; use model='exact' for a top that "
                                 "bends ([table.flexible])")
        x = ca.SX.sym("x", 12)
        gen = ca.SX.sym("g", 18)  # position/angles, rates, accelerations
        pos, th = gen[0:3], gen[3:6]
        rot = cardan_matrix(th)
        body = newton_euler_residual(
            pos, rot, gen[6:9], gen[9:12], rot.T @ gen[12:15], gen[15:18], c[: 3 * n], prm, parents,
            preload=False, ground=extra["ground"], actuator_forces=extra["actuator_forces"],
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
        linear = ca.Function(
            "paper_matrices", [c, p], [mass, damp, stiff, force], ["c", "p"], ["M", "C", "K", "F"]
        )

        return _Equations(x, xdot, static, pose, linear=linear)

    def sensed_motion(self, x: Any, reference: Any) -> Any:
        return ca.vertcat(x[:6] - reference[:6], x[6:12])

    def signals(self, states: np.ndarray, reference: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray((states[:, 0:6] - np.asarray(reference, dtype=float)[..., 0:6]).T)

    def motion(self, vector: np.ndarray) -> np.ndarray:
        return np.abs(vector[0:6])


#: the exact rigid-body model
EXACT = ExactModel()
#: the paper's small-angle time-varying model
PAPER = PaperModel()
#: the variants by name
MODEL_VARIANTS: dict[str, ModelVariant] = {v.name: v for v in (EXACT, PAPER)}
MODEL_KINDS = tuple(MODEL_VARIANTS)


def model_variant(spec: str | ModelVariant, key: str = "model") -> ModelVariant:
    """The variant named ``spec`` (or ``spec`` itself); a bad name is a :class:`ParameterError` naming ``key``."""
    if isinstance(spec, ModelVariant):
        return spec
    if spec not in MODEL_VARIANTS:
        raise ParameterError(f"{key}: must be one of {', '.join(MODEL_KINDS)}, got {spec!r}")
    return MODEL_VARIANTS[spec]


def build_model(layout: ParameterLayout, variant: str | ModelVariant = EXACT) -> Model:
    """Build the casadi functions of a model for a scenario structure.

    Parameters
    ----------
    layout : ParameterLayout
        Structure (numbers of carriages and isolators, carriage chain).
    variant : ModelVariant or {"exact", "paper"}

    Returns
    -------
    Model
        The casadi functions of the structure's equations of motion (right-hand side, static residual,
        Jacobians, linear matrices).
    """
    return model_variant(variant).build(layout)


check_public(globals(), ("Model", "build_model"))
