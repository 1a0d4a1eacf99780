"""The scenario's ``[[sensors]]`` as outputs of the linear model.

For the linear states ``x = (d, v)`` (displacement and small rotation vector, their rates; world axes about
the rest pose) a table sensor at the lever arm ``r = R0 r_table`` along ``n`` reads

- displacement: ``n . (d_t + phi x r) = n^T [I, -[r]x] d``;
- velocity: the same row on ``v``;
- acceleration: the velocity row on ``x'`` = ``A x + B0 u + B1 u'``.

The state-space system carries the floor-velocity term through its shifted states (``xi = x - B1 u``, see
:class:`isolator.analysis.linear.LinearModel`), so that displacement and velocity outputs are exact for every
input. An acceleration output is exact for forces and actuators; from a floor displacement input it is
improper (an isolator's damper passes the floor's velocity to the table's acceleration at once), and its
state-space form leaves out the instantaneous ``n^T [I, -[r]x] B1 u'`` term: use :func:`sensor_response`,
which multiplies the displacement response by ``(j w)^k`` exactly. A floor sensor's output is the floor's
translation along ``n`` [m] (a feedthrough of the ``ground:x .. z`` inputs), whatever its quantity;
:func:`sensor_response` gives it in the sensor's quantity.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from isolator.analysis.frequency_response import state_space_response
from isolator.analysis.signal_names import signals
from isolator.scenario.sensors import Sensor

if TYPE_CHECKING:  # python-control takes most of a second to import: imported where used
    import control

__all__ = ["displacement_rows", "sensor_response", "sensor_rows", "skew_matrix"]


def skew_matrix(r: np.ndarray) -> np.ndarray:
    """``[r]x`` (3, 3): ``[r]x v = r x v``."""
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def displacement_rows(sensors: Sequence[Sensor], rot0: np.ndarray, n_states: int, n_inputs: int,
                      shapes: Sequence[np.ndarray | None] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``C, D`` (sensors, states), (sensors, inputs) of each sensor's displacement along its direction [m]:
    table sensors on the displacement states (``rot0`` the rest pose's rotation), floor sensors on the
    ``ground:x .. z`` inputs (the first three). ``shapes``: on a bending top, each table sensor's elastic
    translation per modal coordinate (3, modes), whose coordinates follow the six rigid ones."""
    c = np.zeros((len(sensors), n_states))
    d = np.zeros((len(sensors), n_inputs))
    for i, s in enumerate(sensors):
        n = np.asarray(s.direction, dtype=float)
        if s.on == "floor":
            d[i, 0:3] = n
        else:
            arm = rot0 @ np.asarray(s.position, dtype=float)
            c[i, 0:3], c[i, 3:6] = n, -n @ skew_matrix(arm)
            shape = None if shapes is None else shapes[i]
            if shape is not None:
                c[i, 6:6 + shape.shape[1]] = n @ rot0 @ shape
    return c, d


def sensor_rows(sensors: Sequence[Sensor], rot0: np.ndarray, a: np.ndarray, b_shifted: np.ndarray, b1: np.ndarray,
                shapes: Sequence[np.ndarray | None] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``C, D`` of the sensors as outputs of the system ``xi' = A xi + B u`` (``xi = x - B1 u``; ``b_shifted``
    = ``A B1 + B0``): each sensor in its quantity (see the module's description for acceleration outputs).
    ``shapes`` as :func:`displacement_rows` takes them; the displacements then have ``6 + modes``
    coordinates, their rates as many."""
    n_states, n_inputs = a.shape[0], b_shifted.shape[1]
    c_disp, d_floor = displacement_rows(sensors, rot0, n_states, n_inputs, shapes)
    ndof = 6 + max((s.shape[1] for s in (shapes or ()) if s is not None), default=0)
    c = np.zeros_like(c_disp)
    d = np.zeros_like(d_floor)
    b0 = b_shifted - a @ b1
    for i, s in enumerate(sensors):
        if s.on == "floor":
            d[i] = d_floor[i]
            continue
        row = c_disp[i]
        velocity = np.zeros(n_states)
        velocity[ndof:2 * ndof] = row[0:ndof]
        if s.order == 0:
            c[i], d[i] = row, row @ b1
        elif s.order == 1:
            c[i], d[i] = velocity, velocity @ b1
        else:
            c[i], d[i] = velocity @ a, velocity @ (a @ b1 + b0)
    return c, d


def sensor_response(system: control.StateSpace, sensors: Sequence[Sensor], rot0: np.ndarray, b1: np.ndarray,
                    frequency_hz: np.ndarray, inputs: Sequence[str] | None = None,
                    shapes: Sequence[np.ndarray | None] | None = None) -> np.ndarray:
    """Each sensor's exact frequency response (nf, sensors, inputs) in its quantity per input unit: its
    displacement response times ``(j 2 pi f)^k`` (k = 0, 1, 2 for displacement, velocity, acceleration);
    ``shapes`` as :func:`displacement_rows` takes them (a top that bends)."""
    import control  # python-control takes most of a second to import: only when needed
    a, b = np.asarray(system.A), np.asarray(system.B)
    c, d = displacement_rows(sensors, rot0, a.shape[0], b.shape[1], shapes)
    shifted = control.ss(a, b, c, c @ b1 + d, inputs=list(system.input_labels),
                         outputs=signals(f"s:{s.name}" for s in sensors))
    h = state_space_response(shifted, frequency_hz, inputs)
    jw = 2j * np.pi * np.asarray(frequency_hz, dtype=float).ravel()
    orders = np.array([s.order for s in sensors])
    return h * jw[:, None, None] ** orders[None, :, None]
