"""The exact model linearised about a rest configuration, as a python-control system.

:func:`linearise` parks the carriages (at their start, at their positions at a
given time of their profiles, or at positions given by name), solves the static
equilibrium, and expands the one symbolic model
(:func:`isolator.model.linearisation.build_linearisation`) to first order there:

``M d'' + C d' + K d = -(G0 g + G1 g' + Bw w + Ba f)``

(pneumatic tables add the chamber pressures' deviations ``e`` as states, with
``+ Kp e`` on the left and ``e' = Pd d + Pv d' + Pp e + Pg g + Pgd g'``, valves
closed)

with ``d`` the table's displacement and small rotation (world axes, from the
equilibrium), ``g`` the floor's translations and rotations (about the world
origin), ``w`` a force and moment at the table's mass centre and ``f`` the
actuator forces. The state-space form absorbs the floor-velocity term ``G1 g'``
into the velocity states (see :class:`LinearModel`), so the floor's displacement
is an ordinary input.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from isolator.analysis.elastic_outputs import point_rows, sensor_shapes
from isolator.analysis.frequency_response import state_space_response
from isolator.analysis.realisation import Realisation
from isolator.analysis.sensor_outputs import sensor_response, sensor_rows
from isolator.errors import ParameterError
from isolator.model.cache import get_model
from isolator.model.equilibrium import DOF_NAMES, Equilibrium, RockingStiffness, rocking_stiffness, static_equilibrium
from isolator.model.linearisation import build_linearisation
from isolator.model.parameters import ParameterLayout
from isolator.model.rotations import pose_rotation
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.scenario.pneumatic import PneumaticIsolator
from isolator.scenario.rules import check_value, closest

if TYPE_CHECKING:  # python-control takes most of a second to import: imported where used
    import control

__all__ = [
    "FORCE_INPUTS",
    "GROUND_INPUTS",
    "STATE_NAMES",
    "AirMatrices",
    "LinearModel",
    "is_stable",
    "linearise",
    "rest_positions",
    "state_space_response",
]

GROUND_INPUTS = tuple(f"ground:{a}" for a in DOF_NAMES)
FORCE_INPUTS = ("force:x", "force:y", "force:z", "torque:x", "torque:y", "torque:z")
STATE_NAMES = (*DOF_NAMES, "vx", "vy", "vz", "wx", "wy", "wz")


def rest_positions(
    scenario: Scenario,
    positions: Mapping[str, float] | Sequence[float] | np.ndarray | None = None,
    time: float | None = None,
) -> np.ndarray:
    """Carriage coordinates [m] of a rest configuration.

    Parameters
    ----------
    scenario : Scenario
    positions : mapping or sequence, optional
        By carriage name (the others at their start), or one value per carriage.
    time : float, optional
        Park the carriages where their profiles put them at this time [s].

    Raises
    ------
    ParameterError
        Both ``positions`` and ``time``; an unknown name; a wrong count; a
        non-finite value; a carriage whose mass would leave the table's footprint.
    """
    if positions is not None and time is not None:
        raise ParameterError("positions: give carriage positions or a time, not both")
    q = scenario.initial_positions()
    names = [c.name for c in scenario.carriages]
    if time is not None:
        t = _finite(time, "time")
        if t < 0:
            raise ParameterError(f"time: must be a finite time >= 0 s, got {time}")
        q = np.array([c.profile.position(t) for c in scenario.carriages], dtype=float)
    elif isinstance(positions, Mapping):
        for name, value in positions.items():
            if name not in names:
                near = closest(str(name), names)
                hint = f"; did you mean '{near}'?" if near else ""
                raise ParameterError(
                    f"positions.{name}: no such carriage{hint} (carriages: {', '.join(names) or 'none'})")
            q[names.index(name)] = _finite(value, f"positions.{name}")
    elif positions is not None:
        if isinstance(positions, str | bytes):
            raise ParameterError(
                f"positions: must be carriage positions by name or one per carriage, got {positions!r}")
        try:
            values = np.array(positions, dtype=float).ravel()
        except (TypeError, ValueError):
            values = np.array(positions, dtype=object).ravel()
        if values.size != len(names):
            raise ParameterError(f"positions: needs {len(names)} values (one per carriage), got {values.size}")
        q = np.array([_finite(v, f"positions[{i}]") for i, v in enumerate(values)])
    _check_footprint(scenario, q)
    return q


def _finite(value: object, key: str) -> float:
    return check_value(key, value, key, ParameterError)


def _check_footprint(scenario: Scenario, q: np.ndarray) -> None:
    excess = scenario.outside_footprint(q)
    if excess is not None:
        i, axis, _, coordinate = excess
        half = scenario.table.size[axis] / 2.0  # type: ignore[index]
        raise ParameterError(
            f"positions.{scenario.carriages[i].name}: puts the carriage's mass at {'xy'[axis]} = {coordinate:.4g} m, "
            f"beyond the table's footprint (+-{half:.4g} m, table.size)"
        )


@dataclass(frozen=True)
class LinearModel:
    """A scenario linearised about a rest configuration.

    Attributes
    ----------
    scenario : Scenario
    positions : ndarray
        Carriage coordinates of the rest configuration [m].
    equilibrium : Equilibrium
        The static equilibrium it is linearised about.
    mass, damping, stiffness : ndarray (ndof, ndof)
        ``M, C, K`` for the coordinates ``d`` (m, rad; then the top's modal
        coordinates on a bending top) and the equations' force and moment rows
        (N, N m), world axes about the mass centre (then the modes' rows).
    ground_stiffness, ground_damping : ndarray (6, 6)
        ``G0, G1``: the floor's displacement and velocity terms.
    force_input : ndarray (ndof, 6 + n_a + modes)
        ``[Bw, Ba, Bm]``: a wrench at the mass centre, the actuator forces, and on a
        bending top the generalised forces on its modes.
    realisation : Realisation
        The system's matrices and signal names as arrays and strings (what ``system`` is built from, on first
        use: python-control takes about a second to import).
    system : control.StateSpace
        States ``x, y, z, rx, ry, rz, vx, vy, vz, wx, wy, wz``; inputs
        ``ground:x .. ground:rz`` [m, rad], ``force:x .. torque:z`` [N, N m] and
        ``actuator:<name>`` [N]; outputs the six table signals ``x .. rz`` [m, rad]
        and ``<point>:x, :y, :z`` [m] per point of interest, then ``s:<sensor>`` per ``[[sensors]]`` entry
        (:mod:`isolator.analysis.sensor_outputs`). On a top that bends (``[table.flexible]``) the states
        add the modal coordinates ``eta1 ..`` after ``rz`` and their rates ``deta1 ..`` after ``wz``, the
        inputs the generalised modal forces ``modal:eta1 ..`` [N per modal unit] (a force at a point:
        :func:`isolator.analysis.elastic_outputs.point_force_weights`), and each point's outputs its elastic
        translation ``<point>:ex, :ey, :ez`` (table axes) [m]. With a moving floor
        the velocity states are the table's velocity minus ``-M^-1 G1 g``, the
        part that the floor's velocity adds at once through the isolators' dampers.
    parameters : ndarray
        The model's parameter vector it was linearised with (the scenario's own
        unless another was given; ``Simulator.layout`` names its entries).
    air : AirMatrices or None
        Pneumatic tables: how the chamber pressures (states ``p:<isolator>``,
        then ``p2:<isolator>`` for damping chambers, deviations [Pa]) enter.
    """

    scenario: Scenario
    positions: np.ndarray
    equilibrium: Equilibrium
    mass: np.ndarray
    damping: np.ndarray
    stiffness: np.ndarray
    ground_stiffness: np.ndarray
    ground_damping: np.ndarray
    force_input: np.ndarray
    realisation: Realisation
    parameters: np.ndarray
    air: AirMatrices | None = None

    @functools.cached_property
    def system(self) -> control.StateSpace:
        """The python-control system (built on first use: importing python-control takes about a second)."""
        return self.realisation.state_space()

    # -- names -------------------------------------------------------------------
    @property
    def input_names(self) -> list[str]:
        return list(self.realisation.inputs)

    @property
    def output_names(self) -> list[str]:
        return list(self.realisation.outputs)

    # -- analyses ----------------------------------------------------------------
    def frequency_response(
        self,
        frequency_hz: np.ndarray,
        inputs: Sequence[str] | None = None,
        outputs: Sequence[str] | None = None,
    ) -> np.ndarray:
        """Complex frequency response ``H(j 2 pi f)``.

        Parameters
        ----------
        frequency_hz : ndarray (nf,)
            [Hz], >= 0.
        inputs, outputs : sequence of str, optional
            Names (default: all).

        Returns
        -------
        ndarray (nf, n_outputs, n_inputs)
            In output units per input unit.
        """
        return state_space_response(self.system, frequency_hz, inputs, outputs)

    def sensor_response(self, frequency_hz: np.ndarray, inputs: Sequence[str] | None = None) -> np.ndarray:
        """Each ``[[sensors]]`` entry's exact frequency response (nf, sensors, inputs), in its quantity
        [m, m/s or m/s^2] per input unit: the displacement response times ``(j 2 pi f)^k``
        (:func:`isolator.analysis.sensor_outputs.sensor_response`; from floor inputs an acceleration output
        of :attr:`system` lacks the instantaneous floor-velocity term)."""
        return sensor_response(self.system, self.scenario.sensors, pose_rotation(self.equilibrium.pose[3:6]),
                               self.feedthrough, frequency_hz, inputs, sensor_shapes(self.scenario))

    @property
    def feedthrough(self) -> np.ndarray:
        """``B1`` (12, inputs): the true state is ``system``'s state plus ``B1 u``.

        Non-zero only in the velocity rows of the floor inputs: what the floor's
        velocity adds through the isolators' dampers at once (``-M^-1 G1``).
        """
        return _feedthrough(self.mass, self.ground_damping, len(self.input_names), self.air)

    def rocking_stiffness(self) -> RockingStiffness:
        """The static rocking stiffness and its margin at this rest configuration."""
        model = get_model(ParameterLayout.of(self.scenario), "exact")
        return rocking_stiffness(model, self.parameters, self.positions, self.equilibrium.pose)

    @property
    def eigenvalues(self) -> np.ndarray:
        """Of the system [1/s] (12 states, plus the chamber pressures of pneumatic tables)."""
        return np.linalg.eigvals(np.asarray(self.system.A))

    @property
    def stable(self) -> bool:
        """All eigenvalues in the open left half-plane (up to round-off)."""
        return is_stable(self.eigenvalues)


def is_stable(eigenvalues: np.ndarray) -> bool:
    """All continuous-time eigenvalues [1/s] in the open left half-plane (up to round-off)."""
    eig = np.asarray(eigenvalues)
    return bool(np.all(eig.real < 1e-9 * max(1.0, float(np.abs(eig).max(initial=0.0)))))


@dataclass(frozen=True)
class AirMatrices:
    """The chamber pressures' part of a pneumatic table's linear model (valves closed).

    ``M d'' + C d' + K d + Kp e + ... = 0`` and ``e' = Pd d + Pv d' + Pp e + Pg g + Pgd g'``
    for the pressure deviations ``e`` [Pa]; ``Kair`` is the stiffness the air adds when squeezed
    slowly (each group's chambers at one pressure), so ``K + Kair`` is the static stiffness.
    """

    names: tuple[str, ...]
    kp: np.ndarray
    pd: np.ndarray
    pv: np.ndarray
    pp: np.ndarray
    pg: np.ndarray
    pgd: np.ndarray
    kair: np.ndarray


def _feedthrough(mass: np.ndarray, ground_damping: np.ndarray, n_inputs: int, air: AirMatrices | None = None
                 ) -> np.ndarray:
    """``B1`` (states, n_inputs): what the floor's velocity adds at once to the states, through the dampers
    to the velocities and through the chambers' volumes to the pressures."""
    n_air = 0 if air is None else len(air.names)
    ndof = mass.shape[0]
    out = np.zeros((2 * ndof + n_air, n_inputs))
    out[ndof:2 * ndof, :6] = -np.linalg.solve(mass, ground_damping)
    if air is not None:
        out[2 * ndof:, :6] = air.pgd
    return out


def _air_names(scenario: Scenario) -> tuple[str, ...]:
    """State names of the chamber pressures: ``p:<isolator>``, then ``p2:<isolator>`` per damping chamber."""
    names = tuple(f"p:{iso.name}" for iso in scenario.isolators if isinstance(iso, PneumaticIsolator))
    return names + tuple(f"p2:{iso.name}" for iso in scenario.isolators
                         if isinstance(iso, PneumaticIsolator) and iso.has_damping_chamber)


def linearise(
    scenario: Scenario,
    positions: Mapping[str, float] | Sequence[float] | np.ndarray | None = None,
    time: float | None = None,
    check: bool = True,
    parameters: np.ndarray | None = None,
) -> LinearModel:
    """Linearise the exact model about a rest configuration.

    Parameters
    ----------
    scenario : Scenario
        The scenario (or a bundled scenario's name, or a TOML file's path).
    positions : mapping or sequence, optional
        Carriage positions [m] by name or one per carriage (default: their start).
    time : float, optional
        Park the carriages where their profiles are at this time [s] instead.
    check : bool
        Raise :class:`~isolator.UnstableTableError` when the table cannot stand
        (False: linearise anyway, about the equilibrium or the upright pose).
    parameters : ndarray, optional
        The model's parameter vector instead of the scenario's, for example
        ``Simulator(scenario).scaled_parameters(stiffness, damping)``.

    Returns
    -------
    LinearModel
        The ``control.StateSpace`` (``system``, named states, inputs and outputs) with the mass, stiffness
        and damping matrices and the equilibrium it was taken about.

    Examples
    --------
    >>> from isolator import load_scenario
    >>> from isolator.analysis.linear import linearise
    >>> lin = linearise(load_scenario(), positions={"x-stage": 0.2})
    >>> lin.system.nstates
    12
    """
    layout = ParameterLayout.of(scenario)  # checks a scenario built from the dataclasses, as the reader does
    q = rest_positions(scenario, positions, time)
    model = get_model(layout, "exact")
    p = layout.pack(scenario) if parameters is None else layout.checked(parameters, "parameters")
    eq = static_equilibrium(model, p, q, "in this rest configuration", check=check)
    c = np.concatenate([q, np.zeros(2 * q.size)])
    mats = [np.asarray(m, dtype=float) for m in build_linearisation(layout)(eq.pose, c, p)]
    mass, damping, stiffness, g0, g1, bw, ba = mats[:7]
    air = None if layout.pneumatic is None else AirMatrices(_air_names(scenario), *mats[7:])
    ndof = mass.shape[0]
    force_input = np.hstack([bw, ba.reshape(ndof, -1), -np.eye(ndof, ndof - 6, -6)])  # then generalised modal forces
    realisation = _realisation(scenario, eq, mass, damping, stiffness, g0, g1, force_input, air)
    return LinearModel(scenario, q, eq, mass, damping, stiffness, g0, g1, force_input, realisation, p, air)


def _realisation(
    scenario: Scenario,
    eq: Equilibrium,
    mass: np.ndarray,
    damping: np.ndarray,
    stiffness: np.ndarray,
    g0: np.ndarray,
    g1: np.ndarray,
    force_input: np.ndarray,
    air: AirMatrices | None = None,
) -> Realisation:
    ndof = mass.shape[0]
    inv_m = np.linalg.inv(mass)
    zero, eye = np.zeros((ndof, ndof)), np.eye(ndof)
    a = np.block([[zero, eye], [-inv_m @ stiffness, -inv_m @ damping]])
    n_in = 6 + force_input.shape[1]
    b0 = np.vstack([np.zeros((ndof, n_in)), -inv_m @ np.hstack([g0, force_input])])
    n_air = 0 if air is None else len(air.names)
    if air is not None:
        a = np.block([[a, np.vstack([np.zeros((ndof, n_air)), -inv_m @ air.kp])],
                      [air.pd, air.pv, air.pp]])
        b0 = np.vstack([b0, np.hstack([air.pg, np.zeros((n_air, n_in - 6))])])
    b1 = _feedthrough(mass, g1, n_in, air)
    # x' = A x + B0 u + B1 u'  ->  xi = x - B1 u:  xi' = A xi + (A B1 + B0) u
    rot0 = pose_rotation(eq.pose[3:6])
    rows = [np.hstack([np.eye(6, ndof), np.zeros((6, ndof))])]
    out_names = list(DOF_NAMES)
    for point in scenario.points:
        rows.append(point_rows(point, rot0, ndof, scenario.table))
        out_names += [f"{point.name}:{a}" for a in ("x", "y", "z", "ex", "ey", "ez")[:rows[-1].shape[0]]]
    c = np.hstack([np.vstack(rows), np.zeros((sum(r.shape[0] for r in rows), n_air))])
    modes = [f"eta{i + 1}" for i in range(ndof - 6)]
    inputs = [*GROUND_INPUTS, *FORCE_INPUTS, *(f"actuator:{act.name}" for act in scenario.actuators),
              *(f"modal:{m}" for m in modes)]
    states = [*DOF_NAMES, *modes, *STATE_NAMES[6:], *(f"d{m}" for m in modes), *(air.names if air is not None else ())]
    c_sensors, d_sensors = sensor_rows(scenario.sensors, rot0, a, a @ b1 + b0, b1, sensor_shapes(scenario))
    return Realisation(a, a @ b1 + b0, np.vstack([c, c_sensors]), np.vstack([c @ b1, d_sensors]), tuple(inputs),
                       (*out_names, *(f"s:{sensor.name}" for sensor in scenario.sensors)), tuple(states), scenario.name)


check_public(globals(), ("LinearModel", "linearise"))
