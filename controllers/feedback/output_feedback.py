"""A discrete controller from the scenario's sensors to its actuators, designed and optionally gain-scheduled.

:func:`design_controller` is what ``isolator controller`` runs: it checks the request, linearises the
scenario at the design positions, designs there (:func:`~controllers.feedback.output_designs.skyhook_design`,
:func:`~controllers.feedback.output_designs.lqg_design`, :func:`~controllers.feedback.hinf_output.hinf_design`)
and returns a :class:`~isolator.simulation.discrete_controller.DiscreteController` ready for
``controller.json`` and the C export. On a bending top the design is made on the top's rigid-body model
(:func:`~controllers.feedback.rolloff.rigid_top`: a root locus or a Riccati equation on the full plant answers
to the elastic modes' light damping, and skyhook's would choose almost no gain), judged on the full plant (the
top's elastic modes included) at the design positions and the start, and rolled off above the isolation band
where it would be unstable or short of its disk margin there (:func:`~controllers.feedback.rolloff.roll_off`,
recorded in ``settings["rolloff"]``); the search's moves are simulated on the full plant.

Design positions: without a schedule, every carriage at the middle of its travel (the configuration
that is closest to all others; the robustness check then covers the travel's ends). With ``schedule=N``
(``N >= 2``), ``N`` evenly spaced positions over the travel of the scheduling carriage (by default the one
whose travel moves the most carried mass the farthest: mass it carries times its stroke), the others at
their middle; the controller interpolates between the points at the scheduling carriage's position.
"""

from __future__ import annotations

import inspect
import numbers
from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from isolator.analysis.linear import linearise
from isolator.analysis.modes import modes
from isolator.analysis.sampling import check_sample_rate
from isolator.errors import ParameterError, ScenarioError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.simulation.closed_loop import controller_factor
from isolator.simulation.discrete_controller import DiscreteController, ScheduleEntry

from .hinf_output import hinf_design
from .output_designs import DiscreteDesign, lqg_design, skyhook_design
from .output_tuning import TUNED, travel, tune
from .rolloff import rigid_top, roll_off
from .sensor_plant import SensorPlant, sensor_plant

__all__ = ["METHODS", "checked_sample_rate", "design_controller", "design_positions", "travel"]

#: the output-feedback designs, by name
METHODS: dict[str, Callable[..., DiscreteDesign]] = {"skyhook": skyhook_design, "lqg": lqg_design,
                                                     "hinf": hinf_design}


def _carried_mass(scenario: Scenario, index: int) -> float:
    """The mass a carriage moves: its own and that of every carriage riding on it [kg]."""
    names = {scenario.carriages[index].name}
    total = 0.0
    for carriage in scenario.carriages[index:]:
        if carriage.name in names or carriage.parent in names:
            names.add(carriage.name)
            total += carriage.mass
    return total


def design_positions(scenario: Scenario, schedule: int = 1, carriage: str | None = None
                     ) -> tuple[np.ndarray, int]:
    """The carriages' positions at the design points (points, carriages) [m] and the scheduling carriage.

    Parameters
    ----------
    schedule : int
        Design points (1: one design, every carriage at the middle of its travel).
    carriage : str, optional
        The carriage that schedules (default: the largest carried mass times stroke).
    scenario : Scenario
        The scenario (or a bundled scenario's name, or a TOML file's path).

    Returns
    -------
    positions : ndarray
        (points, carriages): the carriages' positions at each design point [m].
    carriage : int
        The index of the scheduling carriage.
    """
    if isinstance(schedule, bool) or not isinstance(schedule, numbers.Integral) or schedule < 1:
        raise ParameterError(f"schedule: must be a whole number of design points >= 1, got {schedule!r}")
    ranges = travel(scenario)
    middle = ranges.mean(axis=1) if ranges.size else np.zeros(0)
    names = [c.name for c in scenario.carriages]
    if carriage is not None and carriage not in names:
        raise ParameterError(f"schedule_carriage: no carriage named '{carriage}' (the scenario has "
                             f"{', '.join(names) or 'none'})")
    if schedule == 1:
        if carriage is not None:
            raise ParameterError("schedule_carriage (--schedule-carriage): names the carriage of a schedule; "
                                 "give --schedule N with N >= 2 design points, or leave it out")
        return middle[None, :], 0
    strokes = ranges[:, 1] - ranges[:, 0]
    if not names or float(np.max(strokes)) <= 0:
        raise ParameterError(f"schedule: {schedule} design points need a carriage that travels; none does")
    index = names.index(carriage) if carriage else int(np.argmax(
        [_carried_mass(scenario, i) * strokes[i] for i in range(len(names))]))
    if strokes[index] <= 0:
        raise ParameterError(f"schedule_carriage: '{names[index]}' does not travel (its profile stays at "
                             f"{ranges[index, 0]:.6g} m)")
    points = np.repeat(middle[None, :], schedule, axis=0)
    points[:, index] = np.linspace(ranges[index, 0], ranges[index, 1], schedule)
    return points, index


def _check_rate(plant: SensorPlant, sample_rate: float, where: str) -> None:
    highest = float(np.max(modes(plant.lin).frequencies_hz))
    if sample_rate < 2 * highest:
        raise ParameterError(f"sample_rate (--sample-rate): {sample_rate:.6g} Hz is below twice the table's highest "
                             f"mode ({highest:.4g} Hz {where}); sample at {2 * highest:.4g} Hz or more (ten times "
                             "that is usual)")


def checked_sample_rate(sample_rate: float) -> float:
    """A controller's rate [Hz] as a float, or a one-line :class:`ParameterError` naming ``--sample-rate``
    unless it follows the one rule of
    :func:`~isolator.analysis.sampling.check_sample_rate`."""
    return check_sample_rate(sample_rate, "sample_rate (--sample-rate)")


def design_controller(scenario: Scenario, method: str, sample_rate: float, delay: bool = False,
                      schedule: int = 1, schedule_carriage: str | None = None,
                      options: Mapping[str, Any] | None = None,
                      parameters: np.ndarray | None = None, search: bool = True) -> DiscreteController:
    """Design a discrete output-feedback controller from the scenario's sensors to its actuators.

    Parameters
    ----------
    scenario : Scenario
        With ``[[sensors]]`` and ``[[actuators]]``.
    method : {"skyhook", "lqg", "hinf"}
    sample_rate : float
        The controller's rate [Hz]; at least twice the table's highest mode.
    delay : bool
        Design for one sample of computation delay (``u_k`` acting from ``t_{k+1}``).
    schedule : int
        Design points along the scheduling carriage's travel (1: no scheduling). ``hinf`` designs only one.
    schedule_carriage : str, optional
        The carriage that schedules (see the module's description for the default).
    options : mapping, optional
        Keyword settings of the method's design function (e.g. ``{"gain": 2e4}`` for skyhook [N s/m],
        ``{"max_velocity": 5e-3}`` for lqg and hinf [m/s]).
    parameters : ndarray, optional
        The model's parameter vector to design with (e.g. a calibrated one); default the scenario's.
    search : bool
        ``lqg`` and ``skyhook`` without their weights in ``options`` (``max_velocity``/``max_rate``,
        ``gain``): choose them by a small search judged by the simulated move's settling, the actuators' force
        limits and the margins (:mod:`controllers.feedback.output_tuning`; its outcome under
        ``settings["search"]``); False: the design function's own defaults.

    Returns
    -------
    DiscreteController
        The controller from the scenario's sensors to its actuators (gain-scheduled with ``schedule`` > 1),
        as :func:`write_c` writes it.

    Raises
    ------
    ScenarioError
        No sensors or no actuators.
    ParameterError
        An unknown method or option, a sample rate below twice the highest mode, a schedule ``hinf``
        cannot interpolate.
    OptimisationError
        The design has no solution.
    """
    if method not in METHODS:
        raise ParameterError(f"method: must be one of {', '.join(METHODS)}, got {method!r}")
    sample_rate = checked_sample_rate(sample_rate)
    if not scenario.sensors:
        raise ScenarioError(f"sensors: the {method} design feeds back the scenario's [[sensors]], and it has none "
                            "(add [[sensors]] entries: geophones or accelerometers on the table)")
    if not any(s.on == "table" for s in scenario.sensors):
        raise ScenarioError(f"sensors: every one of the scenario's [[sensors]] is on the floor; the {method} design "
                            "feeds back the table's motion and needs at least one sensor with on = \"table\"")
    if not scenario.actuators:
        raise ScenarioError(f"actuators: the {method} design commands the scenario's [[actuators]], and it has none")
    try:  # the simulation must be able to run it: a stepping grid that is a multiple of both rates
        controller_factor(scenario.simulation, sample_rate)
    except ParameterError as exc:
        raise ParameterError(f"sample_rate (--sample-rate): {sample_rate:.6g} Hz cannot be simulated with this "
                             f"scenario ({str(exc).split(': ', 1)[1]}); choose a rate that divides a multiple of "
                             "the scenario's simulation.sample_rate") from None
    settings = dict(options or {})
    known = set(list(inspect.signature(METHODS[method]).parameters)[3:])
    if unknown := sorted(set(settings) - known):
        raise ParameterError(f"options: {method} has no setting '{unknown[0]}' (it takes {', '.join(sorted(known))})")
    points, index = design_positions(scenario, schedule, schedule_carriage)
    if search and method in TUNED and not set(TUNED[method]) & set(settings):
        def design(weights: dict[str, Any]) -> DiscreteController:
            return design_controller(scenario, method, sample_rate, delay, schedule, schedule_carriage,
                                     {**settings, **weights}, parameters, search=False)

        outcome = tune(scenario, method, design, parameters)
        chosen = design(outcome.settings)
        return _with_settings(chosen, {**chosen.settings, "search": outcome.to_dict()})
    if method == "hinf" and len(points) > 1:
        raise ParameterError("schedule (--schedule): an H-infinity design's states are the synthesis's own, so two "
                             "designs have no common coordinates to interpolate; use --method lqg or skyhook to "
                             "schedule, or one hinf design")
    names = [c.name for c in scenario.carriages]
    designs, lins = [], []
    reduced = rigid_top(scenario)  # a bending top's design is made on its rigid-body model, judged on the full one
    for q in points:
        where = ", ".join(f"{n} at {v:.4g} m" for n, v in zip(names, q, strict=True)) or "at rest"
        plant = sensor_plant(linearise(scenario, positions=q, parameters=parameters))
        _check_rate(plant, sample_rate, f"with {where}")
        lins.append(plant.lin)
        if reduced is not scenario:
            plant = sensor_plant(linearise(reduced, positions=q, parameters=parameters))
        designs.append(METHODS[method](plant, sample_rate, delay, **settings))
    record: dict[str, Any] = {**settings, "design_positions": points.tolist(),
                              "points": [d.settings for d in designs]}
    common: dict[str, Any] = {"sample_rate": sample_rate, "sensors": [s.name for s in scenario.sensors],
              "actuators": [a.name for a in scenario.actuators], "carriages": names, "method": method,
              "settings": record, "delay": bool(delay)}
    if len(designs) == 1:
        made = DiscreteController(**common, A=designs[0].A, B=designs[0].B, C=designs[0].C, D=designs[0].D)
    else:
        entries = [ScheduleEntry(tuple(q), *d.matrices) for q, d in zip(points, designs, strict=True)]
        made = DiscreteController(**common, schedule=entries, schedule_carriage=index)
    if getattr(scenario.table, "flexible", None) is not None:  # judged on the full plant, at the start too
        lins.append(linearise(scenario, parameters=parameters))
    return roll_off(made, lins)


def _with_settings(controller: DiscreteController, settings: dict[str, Any]) -> DiscreteController:
    """The controller with other design settings (the same matrices)."""
    return replace(controller, settings=settings)


check_public(globals())
