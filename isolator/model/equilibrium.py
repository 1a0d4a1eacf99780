"""Static equilibrium of the parked table, its stability and its rocking-stiffness margin."""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca
import numpy as np

from isolator.errors import UnstableTableError
from isolator.model.linearisation import build_linearisation
from isolator.model.pneumatic_statics import air_contents, closed_static_function
from isolator.model.variants import Model
from isolator.numerics.native import MappedFunction

__all__ = ["DOF_NAMES", "Equilibrium", "RockingStiffness", "air_in_groups", "closed_rest_states",
           "quasi_static_sensitivity", "rocking_stiffness", "static_equilibria", "static_equilibrium"]

DOF_NAMES = ("x", "y", "z", "rx", "ry", "rz")


@dataclass(frozen=True)
class Equilibrium:
    """The table at rest under the carriages parked at ``positions``.

    Attributes
    ----------
    pose : ndarray (6,)
        Mass-centre position from the reference pose [m] and Cardan angles
        (Rz Ry Rx) [rad]; for pneumatic tables followed by each leveling
        group's gauge pressure [Pa].
    state : ndarray
        The model's state at rest in that pose.
    positions : ndarray
        Carriage coordinates [m].
    eigenvalues : ndarray
        Of the model linearised there [1/s].
    """

    pose: np.ndarray
    state: np.ndarray
    positions: np.ndarray
    eigenvalues: np.ndarray

    @functools.cached_property
    def max_frequency(self) -> float:
        """Largest eigenvalue modulus [rad/s] (kept: a batch asks for it per run)."""
        return float(np.max(np.abs(self.eigenvalues), initial=0.0))


@dataclass(frozen=True)
class RockingStiffness:
    """The table's static stiffness against rotation, translations free to follow.

    The stiffness matrix about the rest pose is condensed onto the three
    rotations (the translations take their static values), giving a 3x3
    rocking stiffness whose eigenvalues must all be positive for the table to
    stand. The weight above the isolators' attachment points takes part of the
    isolators' own rocking stiffness away (about ``W h``).

    Attributes
    ----------
    values : ndarray (3,)
        Eigenvalues of the condensed rocking stiffness, ascending [N m/rad].
    directions : ndarray (3, 3)
        Their unit rotation axes (columns), world frame.
    elastic : ndarray (3,)
        The isolators' part along those axes, without gravity [N m/rad].
    """

    values: np.ndarray
    directions: np.ndarray
    elastic: np.ndarray

    @property
    def margin(self) -> float:
        """Smallest rocking stiffness [N m/rad]; <= 0: the table tips."""
        return float(self.values[0])

    @property
    def relative_margin(self) -> float:
        """``margin`` as a fraction of the isolators' own rocking stiffness along that axis."""
        return float(self.values[0] / self.elastic[0]) if self.elastic[0] > 0 else float("-inf")

    @property
    def weakest_axis(self) -> str:
        """``rx``, ``ry`` or ``rz``: the world axis closest to the softest rotation."""
        return DOF_NAMES[3 + int(np.argmax(np.abs(self.directions[:, 0])))]

    @property
    def stable(self) -> bool:
        return self.margin > 0.0

    def describe(self) -> str:
        """One line for reports and error messages."""
        taken = self.elastic[0] - self.values[0]
        return (
            f"rocking stiffness about {self.weakest_axis} = {self.margin:.4g} N m/rad "
            f"({100 * self.relative_margin:.3g} % of the isolators' {self.elastic[0]:.4g}; "
            f"the weight above their attachment points takes {taken:.4g} N m/rad)"
        )


def rocking_stiffness(model: Model, p: np.ndarray, positions: np.ndarray, pose: np.ndarray) -> RockingStiffness:
    """Condensed rocking stiffness of the exact model at a rest ``pose`` (position [m], Cardan angles [rad]).

    Parameters
    ----------
    model : Model
        Any model of the scenario's structure (the exact equations are used).
    p : ndarray
        Parameter vector.
    positions : ndarray
        Carriage coordinates [m].
    pose : ndarray (6,)
        Usually the static equilibrium's.
    """
    lin = build_linearisation(model.layout)
    c = np.concatenate([np.asarray(positions, float), np.zeros(2 * len(positions))])

    pneumatic = model.layout.pneumatic is not None

    def stiffness(params: np.ndarray, at: np.ndarray, air_at: np.ndarray) -> np.ndarray:
        k = np.asarray(lin(at, c, params)[2], dtype=float)
        if pneumatic:  # the air's slow stiffness at the rest pressures
            k = k + np.asarray(lin(air_at, c, params)[-1], dtype=float)
        return condensed(k)

    def condensed(k: np.ndarray) -> np.ndarray:  # onto the rotations, translations (and modes) following
        k = 0.5 * (k + k.T)
        free = [0, 1, 2, *range(6, k.shape[0])]
        return k[3:6, 3:6] - k[3:6, free] @ np.linalg.pinv(k[np.ix_(free, free)]) @ k[free, 3:6]

    pose = np.asarray(pose, dtype=float)
    values, vectors = np.linalg.eigh(stiffness(p, pose, pose))
    no_gravity = np.array(p, dtype=float)
    no_gravity[0] = 0.0
    unloaded = pose.copy()
    unloaded[6:] = 0.0  # no weight: the chambers at the atmosphere, their air springs as they are
    elastic_matrix = stiffness(no_gravity, unloaded, pose)
    elastic = np.einsum("ik,ij,jk->k", vectors, elastic_matrix, vectors)
    return RockingStiffness(values, vectors, elastic)


def static_equilibrium(
    model: Model, p: np.ndarray, positions: np.ndarray, where: str = "at rest", check: bool = True
) -> Equilibrium:
    """Solve for the table's static pose and check that it is stable.

    Parameters
    ----------
    model : Model
    p : ndarray
        Parameter vector.
    positions : ndarray
        Carriage coordinates [m].
    where : str
        Words for messages, e.g. "with the carriages at their start".
    check : bool
        Raise when the equilibrium is unstable (False: return it anyway).

    Raises
    ------
    UnstableTableError
        No equilibrium, or one with a divergent mode (the table would tip);
        the message gives the rocking-stiffness margin.
    """
    return static_equilibria(model, np.asarray(p, dtype=float)[None, :], positions, where, check)[0]


def _newton(
    residual: Callable[[np.ndarray, np.ndarray], list[np.ndarray]],
    params: np.ndarray,
    size: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Newton's method for many rows side by side: ``residual(rows, z) -> (r, dr/dz)``.

    Returns the solutions (runs, size), the rows still iterating and the rows that failed.
    """
    runs = params.shape[0]
    z = np.zeros((runs, size))
    tolerance = 1e-11 * (np.abs(params[:, 0]) * params[:, 1] + 1.0)
    active = np.ones(runs, dtype=bool)
    failed = np.zeros(runs, dtype=bool)
    for _ in range(40):
        idx = np.nonzero(active)[0]
        if idx.size == 0:
            break
        r, jac = residual(idx, z[idx])[:2]
        bad = ~np.all(np.isfinite(r), axis=1)
        done = ~bad & (np.max(np.abs(r), axis=1) <= tolerance[idx])
        failed[idx[bad]] = True
        step = idx[~bad & ~done]
        active[idx[bad | done]] = False
        if step.size == 0:
            continue
        keep = ~bad & ~done
        try:
            dz = -np.linalg.solve(jac[keep], r[keep][:, :, None])[:, :, 0]
        except np.linalg.LinAlgError:  # a free direction (no stiffness along it): least squares
            dz = -np.einsum("nij,nj->ni", np.linalg.pinv(jac[keep]), r[keep])
        z[step] += dz
        small = (np.max(np.abs(dz[:, :6]), axis=1) < 1e-15) & (np.max(np.abs(dz[:, 6:]), axis=1, initial=0.0) < 1e-6)
        tipped = np.max(np.abs(z[step, 3:6]), axis=1) > 1.0
        failed[step[tipped & ~small]] = True
        active[step[small | tipped]] = False
    return z, active, failed


def static_equilibria(
    model: Model,
    params: np.ndarray,
    positions: np.ndarray,
    where: str = "at rest",
    check: bool = True,
    air: np.ndarray | None = None,
    all_closed: bool = False,
) -> list[Equilibrium]:
    """:func:`static_equilibrium` for many parameter vectors at once (Newton's method run side by side).

    Parameters
    ----------
    model : Model
    params : ndarray (runs, parameters)
    positions : ndarray
        Carriage coordinates [m], the same for every run, or one row per run (runs, carriages).
    where : str
        Words for messages.
    check : bool
        Raise when an equilibrium is unstable.
    air : ndarray (runs, groups), optional
        Pneumatic tables: each group's air (:func:`air_in_groups`) for the
        groups without a valve, which then keep it; groups with a valve hold
        their sensor at zero. None: every sensor at zero (the initial, level
        equilibrium).
    all_closed : bool
        With ``air``: every group keeps its air, valve or not (the table at
        rest with the air it has at some instant).

    Raises
    ------
    UnstableTableError
        For the first run without a stable equilibrium; the message names the
        run when there are several.
    """
    params = np.atleast_2d(np.asarray(params, dtype=float))
    q = np.asarray(positions, float)
    if q.ndim == 2 and params.shape[0] == 1:  # one parameter vector, a configuration per run
        params = np.repeat(params, q.shape[0], axis=0)
    runs = params.shape[0]
    qs = list(q) if q.ndim == 2 else [q] * runs
    c = np.array([model.layout.rest_inputs(row) for row in qs])
    solver = _solver(model)
    if air is None:
        z, active, failed = _newton(lambda rows, z: solver.residual(z, c[rows], params[rows]), params, model.n_static)
    else:
        closed = solver.closed(all_closed)
        air = np.broadcast_to(np.atleast_2d(np.asarray(air, dtype=float)), (runs, np.shape(air)[-1]))
        z, active, failed = _newton(lambda rows, z: closed(z, c[rows], params[rows], air[rows]), params, model.n_static)
    failed |= active  # did not converge
    label = (lambda i: f"run {i}: ") if runs > 1 else (lambda i: "")
    if failed.any():
        i = int(np.argmax(failed))
        rock = rocking_stiffness(model, params[i], qs[i], np.zeros(model.n_static))
        if rock.margin > 0:  # the table would not tip: the solve failed on the inputs' magnitudes, name the lever
            names = model.layout.names
            starts = [k for k, n in enumerate(names) if n.startswith("isolators[") and n.endswith(".position.x")]
            reach = [(float(np.linalg.norm(params[i][k:k + 3])), names[k][:-2]) for k in starts]
            far, key = max(reach, default=(0.0, ""))
            cause = (f"{key} lies {far:.4g} m from the table's mass centre (positions in mm? the table frame is in m)"
                     if far > 100.0 else "masses, stiffness or damping many orders of magnitude apart")
            raise UnstableTableError(f"{label(i)}no static equilibrium {where}: the solve does not converge although "
                                     f"the table would not tip ({rock.describe()}); {cause}")
        raise UnstableTableError(
            f"{label(i)}no static equilibrium {where}: the isolators cannot hold the table upright; "
            f"{rock.describe()} (the mass centre is too high for the isolator spacing, or they are too soft)"
        )
    states, jacobians = solver.linear(z, c, params)
    eigenvalues = np.linalg.eigvals(jacobians)
    scale = np.max(np.abs(eigenvalues), axis=1, initial=0.0)
    growth = np.max(eigenvalues.real, axis=1)
    unstable = growth > 1e-9 * scale + 1e-9
    if check and unstable.any():
        i = int(np.argmax(unstable))
        eig, vec = np.linalg.eig(jacobians[i])
        worst = int(np.argmax(eig.real))
        dof = _dominant_dof(model, vec[:, worst])
        rock = rocking_stiffness(model, params[i], qs[i], z[i])
        raise UnstableTableError(
            f"{label(i)}unstable table {where}: a mode mostly in {dof} grows at {eig.real[worst]:.3g} 1/s; "
            f"{rock.describe()}; the mass centre is too high for the isolator spacing "
            "(or an isolator is too soft) and the table would tip"
        )
    return [Equilibrium(z[i], states[i], qs[i], eigenvalues[i]) for i in range(runs)]


def closed_rest_states(
    model: Model, params: np.ndarray, positions: np.ndarray, air: np.ndarray, all_closed: bool = True
) -> np.ndarray:
    """States (runs, n_states) of a pneumatic table at rest with each group's ``air`` kept (groups with a
    valve level instead unless ``all_closed``), the carriages at ``positions`` (one configuration, or one
    row per run); no stability check.

    Raises
    ------
    UnstableTableError
        When a run has no such rest.
    """
    params = np.atleast_2d(np.asarray(params, dtype=float))
    z = _closed_pose(model, params, positions, np.atleast_2d(np.asarray(air, dtype=float)), all_closed)
    return np.asarray(_solver(model).pose(z, params)[0])


def quasi_static_sensitivity(
    model: Model, p: np.ndarray, positions: np.ndarray, air: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """A pneumatic table at rest with every group's ``air`` kept, and how its pose moves with the air.

    Returns
    -------
    state : ndarray (n_states,)
        The rest state.
    sensitivity : ndarray (6, groups)
        ``d(pose)/d(air)``: position [m] and Cardan angles [rad] per unit of each group's
        ``sum p^(1/n) V`` (:func:`air_in_groups`).
    """
    params = np.asarray(p, dtype=float)[None, :]
    air = np.atleast_2d(np.asarray(air, dtype=float))
    z = _closed_pose(model, params, positions, air, True)
    _, jz, ja = _solver(model).closed(True)(z, model.layout.rest_inputs(positions), params, air)
    state = np.asarray(_solver(model).pose(z, params)[0])[0]
    return state, -np.linalg.solve(jz[0], ja[0])[:6]


def _closed_pose(
    model: Model, params: np.ndarray, positions: np.ndarray, air: np.ndarray, all_closed: bool
) -> np.ndarray:
    """The static unknowns (pose, group gauge pressures) with the groups' air kept, one row per run;
    ``positions`` one configuration for all runs, or one row per run."""
    closed = _solver(model).closed(all_closed)
    q = np.asarray(positions, dtype=float)
    c = np.array([model.layout.rest_inputs(row) for row in (q if q.ndim == 2 else [q] * params.shape[0])])
    z, active, failed = _newton(lambda rows, z: closed(z, c[rows], params[rows], air[rows]), params, model.n_static)
    if (failed | active).any():
        raise UnstableTableError(f"no rest with the groups' air kept (row {int(np.argmax(failed | active))})")
    return z


def air_in_groups(model: Model, states: np.ndarray, params: np.ndarray) -> np.ndarray:
    """Each leveling group's air ``sum p^(1/n) V`` of exact-model states (N, n_states) [Pa^(1/n) m^3]."""
    return np.asarray(_solver(model).air(np.atleast_2d(states), params)[0])


class _Solver:
    """A model's static residual and rest linearisation, compiled for blocks of runs."""

    def __init__(self, model: Model) -> None:
        self.model = model
        self.residual = MappedFunction(model.static_residual, f"isolator_static_{model.tag}")
        self._closed: dict[bool, MappedFunction] = {}
        z, c = ca.SX.sym("z", model.n_static), ca.SX.sym("c", model.layout.input_size)
        p = ca.SX.sym("p", model.layout.size)
        x = model.pose_state(z, p)
        rest = ca.Function("rest_linear", [z, c, p], [x, model.state_jacobian(x, c, p)])
        self.pose = MappedFunction(ca.Function("rest_state", [z, p], [x]), f"isolator_pose_{model.tag}")
        self.linear = MappedFunction(rest, f"isolator_rest_{model.tag}", optimisation="-O1")
        structure = model.layout.pneumatic
        if structure is not None:
            x, p = ca.SX.sym("x", model.n_states), ca.SX.sym("p", model.layout.size)
            self.air = MappedFunction(
                ca.Function("air", [x, p], [air_contents(structure, model.layout.unpack(p), x)]),
                f"isolator_air_{model.tag}",
            )

    def closed(self, all_closed: bool) -> MappedFunction:
        """The final (or, ``all_closed``, the quasi-static) pneumatic residual ``(z, c, p, air)``."""
        if all_closed not in self._closed:
            self._closed[all_closed] = MappedFunction(
                closed_static_function(self.model.layout, all_closed),
                f"isolator_closed{int(all_closed)}_{self.model.tag}",
            )
        return self._closed[all_closed]


_SOLVERS: dict[tuple, _Solver] = {}


def _solver(model: Model) -> _Solver:
    key = (model.layout, model.kind)
    if key not in _SOLVERS:
        _SOLVERS[key] = _Solver(model)
    return _SOLVERS[key]


def _dominant_dof(model: Model, vector: np.ndarray) -> str:
    motion = model.variant.motion(vector)
    return DOF_NAMES[int(np.argmax(motion))]
