"""An exported controller as an FMI 2.0 Co-Simulation FMU (``isolator controller ... --fmu``).

The contract is ``docs/scenario-format.md``, section "The table as an FMU" (its last paragraph): inputs
``y:<sensor>`` (the readings minus their equilibrium values) and ``q:<carriage>``, outputs ``u:<actuator>``;
a ``doStep`` from a sample time ``t_k`` steps the controller once with the inputs set before it, and its
outputs are then ``u_k`` (``u_{k-1}`` for a design with one sample of delay, which the simulation applies
from ``t_{k+1}``). The FMU's C is the exported ``controller.h``/``controller.c``
(:func:`~controllers.feedback.export.c_sources`) and the wrapper ``isolator/fmu/templates/controller_fmu.c.j2``,
packed by :func:`isolator.fmu.package.build_fmu` as the plant's FMU is.
"""

from __future__ import annotations

from pathlib import Path

from controllers.feedback.export import c_sources
from isolator.errors import ParameterError
from isolator.fmu.package import FmuVariable, build_fmu
from isolator.fmu.units import sensor_unit
from isolator.numerics.rendering import render
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.simulation.discrete_controller import DiscreteController

__all__ = ["write_controller_fmu"]


def write_controller_fmu(controller: DiscreteController, out: str | Path, key: str = "out",
                         scenario: Scenario | None = None) -> Path:
    """Write ``controller`` as the Co-Simulation FMU ``out`` (its model identifier ``controller``), every
    variable with its SI unit.

    Parameters
    ----------
    controller : DiscreteController
        The exported controller (its ``controller.c`` is the FMU's).
    out : str or Path
        The ``.fmu`` file.
    key : str
        How errors name ``out``.
    scenario : Scenario, optional
        The scenario the controller was designed for: the units of the readings ``y:`` are its sensors'
        (without it, theirs are not stated).

    Returns
    -------
    Path
        The ``.fmu`` file written.

    Raises
    ------
    ParameterError
        Not a controller; no C compiler; ``out`` not writable.
    """
    if not isinstance(controller, DiscreteController):
        raise ParameterError(f"controller: must be a DiscreteController, got {type(controller).__name__}")
    m, p = len(controller.actuators), len(controller.sensors)
    units = {s.name: sensor_unit(s) for s in scenario.sensors} if scenario is not None else {}
    variables = [FmuVariable(f"u:{a}", k, "output", "discrete", "actuator command [N]", "exact", 0.0, unit="N")
                 for k, a in enumerate(controller.actuators)]
    variables += [FmuVariable(f"y:{s}", m + k, "input", "continuous", "sensor reading minus its equilibrium value "
                              f"[{units.get(s, 'SI')}]", start=0.0, unit=units.get(s))
                  for k, s in enumerate(controller.sensors)]
    variables += [FmuVariable(f"q:{c}", m + p + k, "input", "continuous", "carriage position along its axis [m]",
                              start=0.0, unit="m") for k, c in enumerate(controller.carriages)]
    variables.append(FmuVariable("time", len(variables), "independent", unit="s"))
    sources = {**c_sources(controller),
               "controller_fmu.c": render("isolator.fmu", "templates/controller_fmu.c.j2", guid="@GUID@",
                                          delay=controller.delay)}
    rate = float(controller.sample_rate)
    return build_fmu(Path(out), "controller", "controller", f"{controller.method} controller (isolator)", variables,
                     sources, me=False, cs=True, step=1.0 / rate, key=key)


check_public(globals())
