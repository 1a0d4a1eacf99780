"""``simulate``: one run of a scenario's carriage transients, the shortest way to a settling time (the
:class:`~isolator.simulation.simulator.Simulator` does the work)."""

from __future__ import annotations

from collections.abc import Mapping

from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.simulation.response import Response
from isolator.simulation.simulator import Simulator

__all__ = ["simulate"]


def simulate(scenario: Scenario, model: str = "exact", changes: Mapping[str, float] | None = None) -> Response:
    """Simulate a scenario's carriage transients from the initial static equilibrium.

    The table starts at rest on its isolators with the carriages at their start; the run lasts the
    scenario's ``[simulation] duration`` and is measured in its ``[settling]`` band. For runs with actuator
    forces, a feedback law or an exported controller, and for many runs of one scenario, use
    :class:`Simulator`.

    Parameters
    ----------
    scenario : Scenario or str or Path
        The scenario, a bundled scenario's name or a TOML file's path.
    model : {"exact", "paper"}
        The exact rigid-body model (finite rotations, the carriages' full accelerations) or the paper's
        small-angle time-varying one.
    changes : mapping of str to float, optional
        Parameter values by name (:attr:`ParameterLayout.names`, e.g. ``{"isolators[0].stiffness.z": 6e5}``;
        ``isolators[*].damping`` sets every isolator's), in SI units; checked by the scenario's rules.

    Returns
    -------
    Response
        The table's six signals (x, y, z [m] and rx, ry, rz [rad] from the initial equilibrium), their peaks,
        final values and 5 % settling times [s after the last carriage stops].

    Raises
    ------
    ScenarioError
        A bad scenario file (naming the key).
    ParameterError
        A bad ``model`` or a change with an unknown name or a value its rule refuses.
    UnstableTableError
        The table would tip (no stable equilibrium over the carriages' travel).
    SimulationError
        The run diverged.

    Examples
    --------
    >>> from isolator import load_scenario, simulate
    >>> response = simulate(load_scenario("paper-table-3-2"))
    >>> {name: round(time, 2) for name, time in response.settling_time.items()}
    {'x': 0.64, 'y': 0.82, 'z': 2.31, 'rx': 0.02, 'ry': 0.0, 'rz': 0.83}
    >>> damped = simulate("paper-table-3-2", changes={"isolators[*].damping": 2.0e4})
    >>> damped.settling_time_max < response.settling_time_max
    True
    """
    return Simulator(scenario, model).run(changes)


check_public(globals())
