"""A bending top whose elastic modes lie far above the table's motion, taken quasi-statically.

The modes of a granite or honeycomb top (100 Hz to kilohertz) are stiff next to the table on its isolators
(a few hertz): an explicit step that resolves them takes thousands of steps a second. Far above the band of
the table's motion a mode follows its load: its inertia and damping terms (``eta''``, ``2 zeta w eta'``, and
the moving feet's ``2 Psi' eta'`` and the carriages' ``Psi eta''``) are of relative size ``(f / f_i)^2`` and
``2 zeta f / f_i`` for motion at ``f``, and are dropped. The table's acceleration ``a`` and the modal
coordinates ``eta`` then solve, at each instant, the full model's rows (:mod:`isolator.model.flexible_equations`)
without those terms, a linear system

    ``M a + A_re eta = b_r``,   ``A_er a + D eta = b_e``,

``b`` the residual's loads at ``a = 0, eta = 0`` (exact, at the state), ``M`` and ``A_er`` the table's and
the carriages' inertia (time-only), ``A_re`` and ``D = W^2 + ...`` the deflection's forces on the table and on
the modes. ``A_re`` and ``D`` change with the table's pose only to second order in the small motions (the
bending model drops such terms): they are taken at the run's initial rest, and ``D`` without the moving loads'
``m Psi^T Psi''`` (below ``1e-8`` of ``W^2`` for any stage speed), so that ``a`` is the Schur complement's
``S^-1 (b_r - G b_e)`` with ``G = A_re D^-1`` and ``S = M - G A_er`` computed per stage time in numpy
(:func:`stage_values`). The state is the rigid table's 13; the expansion gives the full model's state back
(``eta`` and its rate) for the outputs that read it.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from isolator.model.flexible.coupling import carriage_terms
from isolator.model.flexible.structure import ElasticStructure
from isolator.model.flexible_equations import elastic_state
from isolator.model.parameters import ParameterLayout
from isolator.model.residual import carriage_paths, newton_euler_residual
from isolator.model.rotations import quaternion_rate, quaternion_to_matrix
from isolator.model.variants import EXACT, ModelVariant
from isolator.numerics.native import MappedFunction

__all__ = ["QuasiStaticTop", "quasi_static_top", "rest_blocks", "stage_values"]

Shapes = dict[int, tuple[ca.SX, ca.SX, ca.SX]]


@dataclass(frozen=True)
class QuasiStaticTop:
    """The rigid table's 13 states with the top's modes quasi-static, stepped as a model is
    (:class:`~isolator.numerics.systems.SteppedSystem`; see the module).

    Attributes
    ----------
    layout : ParameterLayout
    staged_rhs : casadi.Function
        ``(x, v, p) -> dx/dt``, ``v`` the stage values of :func:`stage_values`.
    expansion : casadi.Function
        ``(x, v, p) -> x_full``: the full bending model's state, the modal coordinates and their rates (along
        the motion, the carriages' jerk and the other inputs' rates left out) after the table's 13.
    matrices : MappedFunction
        ``(c, shapes, p) -> (M, A_re of the carriages, A_er)`` per stage (compiled).
    rest : casadi.Function
        ``(x_ref, c, shapes, p) -> (A_re of the rest, D)``: the isolators' and actuators' part of ``A_re`` (the
        carriages' taken out) and ``D``, with the table at ``x_ref``.
    expanded : MappedFunction
        ``expansion`` compiled for many states at once.
    """

    layout: ParameterLayout
    staged_rhs: ca.Function
    expansion: ca.Function
    matrices: MappedFunction
    rest: ca.Function
    expanded: MappedFunction

    n_states = 13
    kind = "quasi_static"
    variant: ModelVariant = EXACT

    @property
    def tag(self) -> str:
        """The structure in a name, for the compiled steppers."""
        flexible = self.layout.flexible
        assert flexible is not None  # built for a bending top only
        lay = self.layout
        return (f"quasi_static_c{lay.n_carriages}_i{lay.n_isolators}_a{lay.n_actuators}_g{int(lay.ground)}"
                f"_fl{flexible.n_modes}_{flexible.digest}")

    @property
    def rhs(self) -> ca.Function:
        """The staged right-hand side (the top has no other)."""
        return self.staged_rhs


@dataclass(frozen=True)
class _Rows:
    """The residual's rows, affine in the table's acceleration ``acc`` and the modal coordinates ``eta``."""

    x: ca.SX
    acc: ca.SX
    eta: ca.SX
    residual: ca.SX

    def loads(self, eta: ca.SX) -> ca.SX:
        """Minus the residual at ``acc = 0`` and the modal coordinates ``eta``, (6 + modes,)."""
        return -ca.substitute(self.residual, ca.vertcat(self.acc, self.eta), ca.vertcat(ca.SX.zeros(6, 1), eta))

    def matrices(self) -> list[ca.SX]:
        """``M``, ``A_re``, ``A_er``, ``D`` (the rows' Jacobians; the rows are affine)."""
        zero = ca.SX.zeros(6 + self.eta.shape[0], 1)
        blocks = [ca.jacobian(self.residual[:6], self.acc), ca.jacobian(self.residual[:6], self.eta),
                  ca.jacobian(self.residual[6:], self.acc), ca.jacobian(self.residual[6:], self.eta)]
        return [ca.substitute(b, ca.vertcat(self.acc, self.eta), zero) for b in blocks]


def _rows(structure: ElasticStructure, parents: tuple[int, ...], x: ca.SX, c: ca.SX, prm: dict[str, ca.SX],
          extra: dict[str, ca.SX | None], shapes: Shapes) -> _Rows:
    n, nm = len(parents), structure.n_modes
    rot = quaternion_to_matrix(x[3:7])
    acc, eta, zero = ca.SX.sym("a", 6), ca.SX.sym("eta", nm), ca.SX.zeros(nm, 1)
    elastic = elastic_state(structure, parents, c, prm, eta, zero, zero, acc[:3], acc[3:], x[10:13], rot, shapes)
    res = newton_euler_residual(x[0:3], rot, x[7:10], x[10:13], acc[:3], acc[3:], c[: 3 * n], prm, parents,
                                ground=extra["ground"], actuator_forces=extra["actuator_forces"], elastic=elastic)
    return _Rows(x, acc, eta, res)


def _rate(x: ca.SX, accel: ca.SX) -> ca.SX:
    qt, vel, w = x[3:7], x[7:10], x[10:13]
    return ca.vertcat(vel, quaternion_rate(qt, w), quaternion_to_matrix(qt) @ accel[:3], accel[3:])


def _blocks(structure: ElasticStructure, n_inputs: int) -> list[tuple[str, int]]:
    """The stage values' blocks in order, (name, size): the stepping part, then the expansion's."""
    nm = structure.n_modes
    shapes = [(f"{name}{r}", 3 * nm) for r in structure.roots for name in ("psi", "dpsi", "ddpsi")]
    return [("c", n_inputs), *shapes, ("rest", nm), ("schur", 36), ("gain", 6 * nm), ("flexibility", nm * nm),
            ("inertia", 6 * nm)]


@lru_cache(maxsize=8)
def quasi_static_top(layout: ParameterLayout) -> QuasiStaticTop:
    """The quasi-static top of a bending layout (built once per structure)."""
    structure = layout.flexible
    if structure is None:
        raise ValueError("quasi_static_top: the layout's top is rigid")
    n, nm = layout.n_carriages, structure.n_modes
    p = ca.SX.sym("p", layout.size)
    prm = layout.unpack(p)
    x = ca.SX.sym("x", 13)
    blocks = _blocks(structure, layout.input_size)
    v = ca.SX.sym("v", sum(m for _, m in blocks))
    part, k = {}, 0
    for name, m in blocks:
        part[name] = v[k: k + m]
        k += m
    shapes: Shapes = {r: (ca.reshape(part[f"psi{r}"], 3, nm), ca.reshape(part[f"dpsi{r}"], 3, nm),
                          ca.reshape(part[f"ddpsi{r}"], 3, nm)) for r in structure.roots}
    u = part["c"]
    extra = {"ground": u[layout.ground_slice] if layout.ground else None,
             "actuator_forces": u[layout.actuator_slice] if layout.n_actuators else None}
    rows = _rows(structure, layout.parents, x, u, prm, extra, shapes)
    loads = rows.loads(part["rest"])
    accel = ca.reshape(part["schur"], 6, 6) @ (loads[:6] - ca.reshape(part["gain"], 6, nm) @ loads[6:])
    xdot = _rate(x, accel)
    stepping = sum(m for name, m in blocks if name not in ("flexibility", "inertia"))
    staged_rhs = ca.Function("staged_rhs", [x, v[:stepping], p], [ca.substitute(xdot, v[stepping:], ca.SX.zeros(
        v.shape[0] - stepping, 1))], ["x", "v", "p"], ["xdot"])

    eta = part["rest"] + ca.reshape(part["flexibility"], nm, nm) @ (loads[6:] - ca.reshape(part["inertia"], nm, 6)
                                                                     @ accel)
    rate_of = {"c": ca.vertcat(u[n: 3 * n], ca.SX.zeros(u.shape[0] - 2 * n, 1))}
    for r in structure.roots:
        rate_of[f"psi{r}"], rate_of[f"dpsi{r}"] = part[f"dpsi{r}"], part[f"ddpsi{r}"]
    v_rate = ca.vertcat(*[rate_of.get(name, ca.SX.zeros(m, 1)) for name, m in blocks])
    eta_rate = ca.jtimes(eta, x, xdot) + ca.jtimes(eta, v, v_rate)
    expansion = ca.Function("expansion", [x, v, p], [ca.vertcat(x, eta, eta_rate)], ["x", "v", "p"], ["x_full"])

    reference = ca.SX.sym("x_ref", 13)
    shape_values = ca.vertcat(*[part[name] for name, _ in blocks if name[:3] in ("psi", "dps", "ddp")])
    args = [u, shape_values, p]
    mass, _, inertia, _ = rows.matrices()  # time-only
    carriage_part = _carriage_rows(structure, layout.parents, u, prm, shapes)
    matrices = ca.Function("quasi_static_matrices", args, [mass, carriage_part, inertia])
    at_rest = _rows(structure, layout.parents, reference, u, prm, extra, shapes).matrices()
    rest = ca.Function("quasi_static_rest", [reference, *args], [at_rest[1] - carriage_part, at_rest[3]])
    tag = f"qs_{n}_{layout.n_isolators}_{layout.n_actuators}_{int(layout.ground)}_{nm}_{structure.digest}"
    return QuasiStaticTop(layout, staged_rhs, expansion,
                          MappedFunction(matrices, f"isolator_{tag}", block=64, optimisation="-O1"), rest,
                          MappedFunction(expansion, f"isolator_{tag}_expansion", block=64, optimisation="-O1"))


def _carriage_rows(structure: ElasticStructure, parents: tuple[int, ...], c: ca.SX, prm: dict[str, ca.SX],
                   shapes: Shapes) -> ca.SX:
    """The carriages' part of ``A_re`` (6, modes): the table's rows' terms in ``eta`` from the carriages riding
    the deflection (:func:`~isolator.model.flexible.coupling.carriage_terms`; independent of the table's motion)."""
    nm, zero3, zero_m = structure.n_modes, ca.SX.zeros(3, 1), ca.SX.zeros(structure.n_modes, 1)
    eta = ca.SX.sym("eta", nm)
    g_world = ca.vertcat(0, 0, -prm["gravity"])
    terms = carriage_terms(structure, carriage_paths(c[: 3 * len(parents)], prm, parents), prm["masses"], shapes,
                           eta, zero_m, zero_m, zero3, zero3, zero3, zero3, g_world)
    return ca.jacobian(ca.vertcat(terms[0], terms[1]), eta)


def _shape_values(structure: ElasticStructure, n: int, inputs: np.ndarray) -> np.ndarray:
    """The carriages' ``Psi``, ``dPsi/dt``, ``d2Psi/dt2`` at the inputs (N, 9 modes per root), casadi's order."""
    nm, parts = structure.n_modes, []
    for r in structure.roots:
        shape = next(s for s in structure.carriages if s.root == r)
        for values in shape.along(inputs[:, r], inputs[:, n + r], inputs[:, 2 * n + r], nm):
            parts.append(values.transpose(0, 2, 1).reshape(inputs.shape[0], -1))  # column-major, as casadi
    return np.hstack(parts) if parts else np.zeros((inputs.shape[0], 0))


def rest_blocks(top: QuasiStaticTop, inputs: np.ndarray, p: np.ndarray, reference: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What the stage values take at the run's initial rest: the isolators' and actuators' part of ``A_re``
    (6, modes), ``D^-1`` (modes, modes) and the modal coordinates at rest (modes,), with the full model's state
    ``reference`` (13 + 2 modes,) and the carriages where the inputs (inputs,) put them, at rest (``D`` without the
    moving loads' terms)."""
    structure = top.layout.flexible
    assert structure is not None  # a quasi-static top bends
    n, nm = top.layout.n_carriages, structure.n_modes
    reference = np.asarray(reference, dtype=float)
    resting = np.array(inputs, dtype=float).reshape(1, -1)
    resting[:, n: 3 * n] = 0.0
    fixed, stiffness = (np.asarray(m, dtype=float) for m in top.rest(
        reference[:13], resting[0], _shape_values(structure, n, resting)[0], p))
    return fixed, np.linalg.inv(stiffness), reference[13: 13 + nm]


def stage_values(top: QuasiStaticTop, inputs: np.ndarray, p: np.ndarray,
                 rest: tuple[np.ndarray, np.ndarray, np.ndarray], expansion: bool = False) -> np.ndarray:
    """The quasi-static top's stage values ``v`` (N, size) at the model's inputs (N, inputs).

    Parameters
    ----------
    top : QuasiStaticTop
    inputs : ndarray (N, inputs)
        The model's inputs at the stage times.
    p : ndarray
        The parameters.
    rest : tuple of ndarray
        :func:`rest_blocks` of the run.
    expansion : bool
        Append what the expansion needs (``D^-1`` and ``A_er``); else only what the steps need.
    """
    structure = top.layout.flexible
    assert structure is not None  # a quasi-static top bends
    inputs = np.ascontiguousarray(np.atleast_2d(np.asarray(inputs, dtype=float)))
    n, nm, count = top.layout.n_carriages, structure.n_modes, inputs.shape[0]
    shapes = _shape_values(structure, n, inputs)
    mass, carried, inertia = top.matrices(inputs, shapes, p)
    fixed, flexibility, eta = rest
    gain = (fixed + carried) @ flexibility  # (N, 6, modes)
    schur = np.linalg.inv(mass - gain @ inertia)
    parts = [inputs, shapes, np.broadcast_to(eta, (count, nm)), schur.transpose(0, 2, 1).reshape(count, -1),
             gain.transpose(0, 2, 1).reshape(count, -1)]
    if expansion:
        parts += [np.broadcast_to(flexibility.T.reshape(1, -1), (count, nm * nm)),
                  inertia.transpose(0, 2, 1).reshape(count, -1)]
    return np.ascontiguousarray(np.hstack(parts))
