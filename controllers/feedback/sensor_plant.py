"""The plant an output-feedback controller sees: actuator commands in, the scenario's sensors out.

:func:`sensor_plant` takes the linear model at one rest configuration (with any parameter changes
already in it) and appends each lagged actuator's first-order lag, so that the plant's input is the
*command* (before the lag) as the controller issues it. Its outputs are the ``[[sensors]]`` in file
order, each in its own quantity (m, m/s or m/s^2; an accelerometer's row is its velocity row times the
state equation, so it reads the lag states and any direct actuator force). :meth:`SensorPlant.discrete`
samples it as the controller runs (commands held by a zero-order hold, readings at the samples), with
optionally one sample of computation delay.

The disturbance inputs ``ground:x .. ground:rz`` [m, rad] and ``force:x .. torque:z`` [N, N m] are kept
for the designs' noise models and the closed-loop responses. An acceleration output from a floor
input lacks the instantaneous floor-velocity term (see :mod:`isolator.analysis.sensor_outputs`); the
designs use floor inputs only as a disturbance model, where that term is immaterial.
"""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np

from isolator.analysis.closed_loop import held_air
from isolator.analysis.linear import FORCE_INPUTS, GROUND_INPUTS, LinearModel
from isolator.analysis.sampling import closed_loop_matrix, sample_held
from isolator.analysis.signal_names import labels, signals
from isolator.errors import ParameterError, ScenarioError
from isolator.scenario.arguments import check_public

from .loops import lagged_plant

__all__ = ["DISTURBANCES", "SensorPlant", "held_air", "loop_matrix", "sensor_plant"]

#: the disturbance inputs of the plant, after the actuators
DISTURBANCES = (*GROUND_INPUTS, *FORCE_INPUTS)


@dataclass(frozen=True)
class SensorPlant:
    """The table from actuator commands (and disturbances) to the sensors' readings, continuous time.

    Attributes
    ----------
    lin : LinearModel
        The rest configuration it comes from.
    system : control.StateSpace
        States: the linear model's (12 table states, then chamber pressures of pneumatic tables), then
        one lag state per actuator with a ``bandwidth`` [N]. Inputs ``actuator:<name>`` [N] in file order,
        then :data:`DISTURBANCES`; outputs ``s:<sensor>`` in file order [m, m/s or m/s^2].
    """

    lin: LinearModel
    system: control.StateSpace

    @property
    def n_actuators(self) -> int:
        """Number of actuators (the first inputs)."""
        return len(self.lin.scenario.actuators)

    @property
    def held_air(self) -> int:
        """Pneumatic tables: the open loop's poles at zero, one per leveling group with its valve closed (the
        air it holds: no actuator or sensor reaches it); 0 otherwise."""
        return held_air(self.lin)

    @property
    def n_sensors(self) -> int:
        """Number of sensors (the outputs)."""
        return int(self.system.noutputs)

    def matrices(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(A, B, C, D)`` of :attr:`system` as float arrays."""
        s = self.system
        return tuple(np.asarray(m, dtype=float) for m in (s.A, s.B, s.C, s.D))  # type: ignore[return-value]

    def discrete(self, sample_rate: float, delay: bool = False) -> control.StateSpace:
        """The plant sampled at ``sample_rate`` [Hz] as the controller runs it.

        Every input is held over each sample (zero-order hold, exact for the held commands; the
        disturbance columns are held too, a model only). With ``delay``, ``m`` extra states hold the
        command of the previous sample: the input ``u_k`` computed at ``t_k`` acts from ``t_{k+1}``. The
        readings at ``t_k`` are the left limit, as the simulation and a real sampler take them: a command
        that reaches a reading at once (an accelerometer with an actuator without lag) is seen there as
        the command applied just before ``t_k``, held in ``m`` more states.

        Returns
        -------
        control.StateSpace
            Discrete (``dt = 1 / sample_rate``), inputs and outputs named as :attr:`system`'s; states the
            continuous plant's, then the delayed command (with ``delay``), then the command applied before
            the sample (with a direct feedthrough).
        """
        az, bz, cz, dz = sample_held(self.matrices(), self.n_actuators, sample_rate, delay)
        inputs, outputs = list(self.system.input_labels), list(self.system.output_labels)
        return control.ss(az, bz, cz, dz, 1.0 / sample_rate, inputs=inputs, outputs=outputs)


def loop_matrix(plant: control.StateSpace, controller: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
                ) -> np.ndarray:
    """The state matrix of the sampled loop: ``plant`` (discrete, its first ``m`` inputs the commands) with
    the controller ``(A, B, C, D)`` from its outputs to those inputs (``u = C x_c + D y``, the command itself).

    Parameters
    ----------
    plant : control.StateSpace
        The sampled plant, its first ``m`` inputs the commands [N].
    controller : tuple of ndarray
        The controller's ``(A, B, C, D)``, from the plant's outputs to the commands.

    Returns
    -------
    ndarray (plant states + controller states, same)
        States ``(x, x_c)``; the loop is stable when every eigenvalue is inside the unit circle.

    Raises
    ------
    ParameterError
        The loop is algebraically singular (``I - D D_p`` not invertible: no command satisfies it).
    """
    m = np.asarray(controller[2]).shape[0]
    parts = (plant.A, np.asarray(plant.B)[:, :m], plant.C, np.asarray(plant.D)[:, :m])
    return closed_loop_matrix(tuple(np.asarray(x, dtype=float) for x in parts),
                              tuple(np.asarray(x, dtype=float) for x in controller))


def sensor_plant(lin: LinearModel) -> SensorPlant:
    """The plant from the actuators' commands to the scenario's sensors at ``lin``'s rest configuration.

    Raises
    ------
    ScenarioError
        The scenario has no ``[[actuators]]`` or no ``[[sensors]]``.
    """
    if not isinstance(lin, LinearModel):
        raise ParameterError(f"lin: must be a LinearModel, got {type(lin).__name__}")
    scenario = lin.scenario
    if not scenario.actuators:
        raise ScenarioError("actuators: the scenario has no [[actuators]] to control with")
    if not scenario.sensors:
        raise ScenarioError("sensors: the scenario has no [[sensors]] to feed back (add [[sensors]] entries)")
    plant = lagged_plant(lin)  # the table with each lagged actuator's lag state, commands in
    rows = [plant.outputs.index(f"s:{s.name}") for s in scenario.sensors]
    in_labels = labels(lin.system.input_labels)
    iu = [in_labels.index(f"actuator:{act.name}") for act in scenario.actuators]
    acts = scenario.actuators
    lagged = [k for k, act in enumerate(acts) if act.bandwidth is not None]
    direct = [k for k in range(len(acts)) if k not in lagged]
    n, m = lin.system.nstates, len(acts)
    du = np.asarray(lin.system.D, dtype=float)[np.ix_(rows, iu)]  # accelerometers: the force acts at once
    c_full = plant.cy[rows].copy()
    c_full[:, n:] = du[:, lagged]  # ... through its lag state when it has one
    d_full = np.hstack([np.zeros((len(rows), m)), plant.dyw[rows]])
    d_full[:, direct] = du[:, direct]
    a_full, b_full = plant.a, np.hstack([plant.bu, plant.bw])
    system = control.ss(a_full, b_full, c_full, d_full,
                        inputs=signals([*(f"actuator:{act.name}" for act in acts), *DISTURBANCES]),
                        outputs=signals(f"s:{s.name}" for s in scenario.sensors), name="sensor-plant")
    return SensorPlant(lin, system)


check_public(globals())
