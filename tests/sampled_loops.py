"""The geophone table, controllers and settling helper shared by the tests of the compiled closed loop
(``tests/simulation/test_sampled_loop*.py``)."""

from __future__ import annotations

import tomllib
from pathlib import Path

import control
import numpy as np

from controllers.feedback import from_statespace
from isolator import Simulator
from isolator.scenario.definitions import SIGNALS
from isolator.scenario.reader import bundled_scenarios
from isolator.simulation.actuation import ForceHistory
from isolator.simulation.discrete_controller import DiscreteController
from isolator.simulation.settling import settling_metrics
from isolator.simulation.stepping import hold_time

RATE = 2000.0
PULSE = (0.6, 0.8)  # s: a feedforward force pulse after the (parked) carriages' stop time, 0.5 s


def geophone_data(parked: bool = True, duration: float = 4.0, max_force: float = 80.0,
                  quantity: str = "velocity") -> dict:
    data = tomllib.loads(Path(bundled_scenarios()["paper-table-3-2-geophones"]).read_text())
    for sensor in data["sensors"]:
        sensor["quantity"] = quantity
    data["simulation"]["duration"] = duration
    for act in data["actuators"]:
        act["max_force"] = max_force
    if parked:
        for c in data["carriages"]:
            start = c["profile"]["start"]
            c["profile"] = {"type": "samples", "t": [0.0, 0.5], "q": [start, start]}
    return data


def names(s) -> tuple[list[str], list[str], list[str]]:
    return [x.name for x in s.sensors], [a.name for a in s.actuators], [c.name for c in s.carriages]


def dynamic(s, delay: bool = False) -> DiscreteController:
    """12 states: per sensor/actuator pair, skyhook damping -2000 N s/m through a 40 Hz low-pass (geophones),
    or of the acceleration integrated with a 1 Hz leak (accelerometers)."""
    w = 2 * np.pi * 40.0
    if s.sensors[0].quantity == "acceleration":
        channel = control.ss(control.tf([-2000.0], [1.0, 2 * np.pi]))
    else:
        channel = control.ss(control.tf([-2000.0 * w], [1.0, w]))
    system = channel
    for _ in range(11):
        system = control.append(system, channel)
    return from_statespace(system, RATE, *names(s), delay=delay)


def pulse(s, value: float = 100.0) -> ForceHistory:
    t = np.array([0.0, PULSE[0], PULSE[0], PULSE[1], PULSE[1], 4.0])
    f = np.zeros((12, t.size))
    f[0, 2:4], f[5, 2:4], f[8, 2:4] = value, -0.6 * value, 0.8 * value  # x1, z2, z3
    return ForceHistory(t, f, tuple(a.name for a in s.actuators))


def settling(s, response, t: np.ndarray, signals: np.ndarray) -> np.ndarray:
    sim = Simulator(s)
    hold = hold_time(sim.equilibria(sim.parameters)[1])
    metrics = settling_metrics(t, signals, np.zeros(6), response.stop_time, response.band, hold, interpolate=True)
    return np.array([metrics[k].time for k in SIGNALS])
