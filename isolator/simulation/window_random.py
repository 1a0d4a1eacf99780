"""Windows that leave room for the random motion (``[[windows]] random = K``, ``docs/scenario-format.md``,
"Error budget"): each listed axis of such a window narrowed by ``K`` times the point's budgeted displacement
RMS (the default band, the carriages at their start, passive or with the run's controller)."""

from __future__ import annotations

import dataclasses

import numpy as np

from isolator.analysis.budget import error_budget
from isolator.analysis.budget.loop import SampledController
from isolator.analysis.linear import linearise
from isolator.errors import ScenarioError
from isolator.scenario.definitions import Scenario
from isolator.scenario.readable import length_text

__all__ = ["with_random_margins"]

#: the last scenarios resolved: (scenario, parameters, controller) -> the scenario with its margins
_RESOLVED: list[tuple[Scenario, bytes, object, Scenario]] = []
_KEEP = 4


def with_random_margins(scenario: Scenario, parameters: np.ndarray | None = None,
                        controller: SampledController | None = None) -> Scenario:
    """The scenario with each ``random`` window's margin set (``Window.margin``: ``K sigma`` per listed axis);
    the scenario itself when no window has ``random``.

    Parameters
    ----------
    scenario : Scenario
    parameters : ndarray, optional
        The model's parameter vector of the run (a sweep's design); default the scenario's.
    controller : DiscreteController, optional
        The exported controller of the run (the budget is then the closed loop's).

    Raises
    ------
    ScenarioError
        A window the random motion alone fills (naming the window, the axis and both widths), or a scenario
        without any random source.
    """
    if not any(w.random is not None for w in scenario.windows):
        return scenario
    key = b"" if parameters is None else np.asarray(parameters, dtype=float).tobytes()
    for done, p, ctrl, result in _RESOLVED:
        if done is scenario and p == key and ctrl is controller:
            return result
    lin = linearise(scenario, parameters=parameters)
    points = sorted({w.point for w in scenario.windows if w.random is not None})
    index = next(i for i, w in enumerate(scenario.windows) if w.random is not None)
    try:
        budget = error_budget(lin, controller, points=points)
    except ScenarioError as exc:
        raise ScenarioError(f"windows[{index}].random: {exc}") from None
    windows = []
    for i, w in enumerate(scenario.windows):
        if w.random is None:
            windows.append(w)
            continue
        margin = tuple(w.random * budget.value(w.point, a) for a in w.axes)
        for a, m in zip(w.axes, margin, strict=True):
            if m >= w.translation:
                raise ScenarioError(
                    f"windows[{i}]: the random motion alone fills it on {a}: {w.random:g} sigma = {length_text(m)} "
                    f"against the half-width {length_text(w.translation)} (isolator budget: "
                    f"{length_text(m / w.random)} RMS at {w.point}); widen the window, lower random, or quieten the "
                    "table")
        windows.append(dataclasses.replace(w, margin=margin))
    result = dataclasses.replace(scenario, windows=tuple(windows))
    _RESOLVED.append((scenario, key, controller, result))
    del _RESOLVED[:-_KEEP]
    return result
