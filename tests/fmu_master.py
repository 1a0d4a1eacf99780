"""A small Co-Simulation master for the FMU tests: FMPy's FMU2Slave stepped at a fixed communication step, inputs
set (with their first derivatives) before each step, outputs read after it; a controller FMU in the loop in the
contract's master order."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

#: t -> (input values, their time derivatives: one value (the first) or a sequence of orders 1, 2, ...)
Inputs = Callable[[float], tuple[dict[str, float], dict[str, Any]]]


class Slave:
    """One Co-Simulation FMU instance, initialised, its variables by name."""

    def __init__(self, path, tmp, start_values: dict[str, float] | None = None, name: str = "instance"):
        self.md = read_model_description(str(path))
        unzip = extract(str(path), unzipdir=str(tmp / f"unzip-{name}"))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=unzip,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0)
        for key, value in (start_values or {}).items():
            self.fmu.setReal([self.vr[key]], [value])
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()

    def set(self, values: dict[str, float], derivatives: dict[str, Any] | None = None) -> None:
        if values:
            self.fmu.setReal([self.vr[k] for k in values], list(values.values()))
        for name, rates in (derivatives or {}).items():
            orders = list(np.atleast_1d(rates))
            self.fmu.setRealInputDerivatives([self.vr[name]] * len(orders), list(range(1, len(orders) + 1)),
                                             [float(r) for r in orders])

    def get(self, names: Sequence[str]) -> np.ndarray:
        return np.array(self.fmu.getReal([self.vr[k] for k in names]))

    def close(self) -> None:
        self.fmu.terminate()
        self.fmu.freeInstance()


def run(path, tmp, names: Sequence[str], stop: float, step: float = 1e-3, inputs: Inputs | None = None,
        start_values: dict[str, float] | None = None, extra: Sequence[float] = ()) -> tuple[np.ndarray, np.ndarray]:
    """Step the FMU from 0 to ``stop`` every ``step`` s (and at the times ``extra``: a host that ends its steps
    on the inputs' breakpoints); the communication times and the outputs ``names`` there (points, names)."""
    slave = Slave(path, tmp, start_values)
    grid = np.arange(round(stop / step) + 1) * step
    times = np.union1d(grid, [e for e in extra if 0.0 < e < stop])
    out = np.empty((times.size, len(names)))
    for k, t in enumerate(times):
        if inputs is not None:
            slave.set(*inputs(float(t)))
        out[k] = slave.get(names)
        if k + 1 < times.size:
            slave.fmu.doStep(currentCommunicationPoint=float(t), communicationStepSize=float(times[k + 1] - t))
    slave.close()
    return times, out


def relative_error(got: np.ndarray, reference: np.ndarray) -> float:
    """max |got - reference| / max |reference| (the contract's measure)."""
    return float(np.max(np.abs(got - reference)) / np.max(np.abs(reference)))


def master_loop(plant: Slave, controller: Slave, ctrl: Any, steps: int, h: float, read: Sequence[str],
                wired: Sequence[str] = ()) -> np.ndarray:
    """A plant FMU and a controller FMU in the contract's master order at each of ``steps + 1`` samples ``h`` [s]
    apart: read the plant's outputs ``read`` (the sensors' ``s:<name>`` among them), give the controller its
    readings ``y:<name>`` and the outputs named in ``wired`` as its inputs of the same name, step it, give its
    commands ``u:<name>`` to the plant's ``f:<name>``, step the plant. The outputs read, (steps + 1, len(read));
    both instances closed."""
    read = list(read)
    sensors = [read.index(f"s:{s}") for s in ctrl.sensors]
    out = np.empty((steps + 1, len(read)))
    for k in range(steps + 1):
        t = k * h
        out[k] = plant.get(read)
        controller.set({**{f"y:{s}": out[k, i] for s, i in zip(ctrl.sensors, sensors, strict=True)},
                        **{name: out[k, read.index(name)] for name in wired}})
        if k == steps:
            break
        controller.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        u = controller.get([f"u:{a}" for a in ctrl.actuators])
        plant.set({f"f:{a}": u[i] for i, a in enumerate(ctrl.actuators)})
        plant.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
    plant.close()
    controller.close()
    return out
