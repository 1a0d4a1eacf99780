"""A bending top against the rest of its scenario: the rigid modes against ``[table]``, and everything fixed to
the top (isolators, actuators, table sensors, points, disturbances, the carriages on the table along their
travel) standing on a face of its nodes, each at its feet.

Run by the file reader and :func:`isolator.scenario.validation.validate_scenario`; each failure one
:class:`ScenarioError` naming the thing.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np

from isolator.errors import ScenarioError
from isolator.scenario.definitions import Scenario
from isolator.scenario.flexible import ModalData, check_top
from isolator.scenario.flexible.faces import is_single_layer

__all__ = ["check_flexible", "standing"]


def standing(scenario: Scenario) -> Iterator[tuple[str, np.ndarray, np.ndarray]]:
    """Everything that stands on the top: ``(what, position in the table frame [m], feet (k, 2) [m])``; a carriage
    on the table once at each end of its travel."""
    one = np.zeros((1, 2))
    fixed: tuple[tuple[str, tuple[Any, ...]], ...] = (
        ("isolators", scenario.isolators), ("actuators", scenario.actuators), ("disturbances", scenario.disturbances))
    for section, things in fixed:
        for i, thing in enumerate(things):
            yield f"{section}[{i}]{_named(thing)}.position", np.asarray(thing.position, dtype=float), one
    for i, sensor in enumerate(scenario.sensors):
        if sensor.on == "table":
            yield f"sensors[{i}] ({sensor.name}).position", np.asarray(sensor.position, dtype=float), one
    for i, point in enumerate(scenario.points):
        yield from _feet(f"points[{i}] ({point.name})", "", np.asarray(point.position, dtype=float), point.feet)
    travel = scenario.travel()  # (carriages, 2): the profiles' range over the run, or the sequence's
    positions = scenario.carriage_positions(travel) if scenario.carriages else np.zeros((0, 3, 2))
    for i, carriage in enumerate(scenario.carriages):
        if carriage.parent != "table":
            continue
        for end in range(2):
            at = f" (at q = {travel[i, end]:.4g} m)" if travel[i, 0] != travel[i, 1] else ""
            yield from _feet(f"carriages[{i}] ({carriage.name})", at, positions[i, :, end], carriage.feet)


def _named(thing: object) -> str:
    name = getattr(thing, "name", "")
    return f" ({name})" if name else ""


def _feet(what: str, at: str, position: np.ndarray, feet: tuple[tuple[float, float], ...] | None
          ) -> Iterator[tuple[str, np.ndarray, np.ndarray]]:
    if feet is None:
        yield f"{what}.position{at}", position, np.zeros((1, 2))
    else:
        for j, foot in enumerate(feet):
            yield f"{what}.feet[{j}]{at}", position, np.asarray(foot, dtype=float).reshape(1, 2)


def check_flexible(scenario: Scenario) -> None:
    """A scenario's bending top (``[table.flexible]``) against the rest of it; nothing without one.

    Raises
    ------
    ScenarioError
        Empty ``feet``; the rigid modes' mass or mass centre against ``[table]``; a single layer's thickness
        other than ``table.size`` z; ``feet`` on a carriage that rides another carriage; a thing, a foot or a carriage's
        foot anywhere along its travel farther than 1 mm outside its face of the top's nodes, naming it.
    """
    things: list[tuple[str, Any]] = [(f"points[{i}]", x) for i, x in enumerate(scenario.points)]
    things += [(f"carriages[{i}]", x) for i, x in enumerate(scenario.carriages)]
    for key, thing in things:
        if thing.feet is not None and len(thing.feet) == 0:
            raise ScenarioError(f"{key}.feet: must be a non-empty list of [x, y] offsets (m), or none (one foot at "
                                "the position)")
    for i, carriage in enumerate(scenario.carriages):
        if carriage.feet is not None and carriage.parent != "table":
            raise ScenarioError(f"carriages[{i}].feet: carriage '{carriage.name}' rides its parent "
                                f"'{carriage.parent}' (and so its parent's feet); only a carriage on the table has "
                                "feet of its own")
    flexible = scenario.table.flexible
    if flexible is None:
        return
    size = scenario.table.size
    check_top(flexible, scenario.table.mass, size)
    data: ModalData = flexible.data
    if size is not None and is_single_layer(data.nodes) and abs(data.thickness - size[2]) > 1e-9 * size[2]:
        raise ScenarioError(f"table.flexible: the modal data's faces lie +-{data.thickness / 2:.4g} m from its "
                            f"single layer of nodes, but table.size z is {size[2]:.4g} m (load it with that "
                            "thickness)")
    for what, position, feet in standing(scenario):
        xy, face = position[:2] + feet, data.face_for(float(position[2]))
        if not data.inside(xy, face).all():
            data.translation(xy, face, what)  # refuses, naming the thing and the point
