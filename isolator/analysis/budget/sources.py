"""The random sources of an error budget and where each enters the linear model
(``docs/scenario-format.md``, "Error budget: random disturbances and noise at the points").

Every source is one scalar random signal, uncorrelated with every other, entering the table through a fixed
vector of the linear model's inputs (``ground:*``, ``force:* / torque:*``, ``actuator:*``) or, for a sensor's
noise, added to that sensor's reading at the controller's input.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from isolator.analysis.elastic_outputs import point_force_weights
from isolator.analysis.linear import LinearModel
from isolator.scenario.definitions import Scenario
from isolator.scenario.random_sources import SpectralDensity

__all__ = ["BUDGET_POINT", "Source", "budget_point_names", "budget_sources", "has_random_sources"]

#: the budget's point of a scenario without ``[[points]]``: its mass centre
BUDGET_POINT = "table"


def has_random_sources(scenario: Scenario, closed_loop: bool = False) -> bool:
    """Whether the table has a random source for an error budget: a ``[ground.spectrum]`` (or ``vc``), a
    ``[[disturbances]]`` entry, an actuator's ``noise_psd`` or, in a closed loop (``closed_loop``), a sensor's
    noise."""
    spectrum = scenario.ground.spectrum if scenario.ground is not None else None
    return spectrum is not None or bool(scenario.disturbances) or any(
        a.noise_psd is not None for a in scenario.actuators) or (closed_loop and any(
            s.noise > 0 or s.noise_psd is not None for s in scenario.sensors))


def budget_point_names(scenario: Scenario) -> tuple[str, ...]:
    """The points a budget of ``scenario`` knows: its ``[[points]]``, or :data:`BUDGET_POINT` when it has none."""
    return tuple(p.name for p in scenario.points) or (BUDGET_POINT,)


@dataclass(frozen=True)
class Source:
    """One random source.

    Attributes
    ----------
    name : str
        ``floor:x``, ``force:<disturbance>``, ``actuator:<name>`` or ``sensor:<name>``.
    density : callable
        Its one-sided PSD at frequencies [Hz], in the units of what it drives: floor translation [m^2/Hz],
        force [N^2/Hz], sensor reading [SI^2/Hz].
    corners : ndarray
        Frequencies [Hz] where the density may jump or bend (grid points of the integration).
    inputs : ndarray or None
        The linear model's inputs it drives, one weight per input (None for a sensor's noise).
    sensor : int or None
        The sensor whose reading it adds to (a sensor's noise), else None.
    key : str
        The scenario's key that gives its density (``ground.spectrum``, ``disturbances[0].psd``, ...), for
        messages.
    """

    name: str
    density: Callable[[np.ndarray], np.ndarray]
    corners: np.ndarray
    inputs: np.ndarray | None = None
    sensor: int | None = None
    key: str = ""


def _floor(lin: LinearModel, axis: int, name: str) -> Source:
    spectrum = lin.scenario.ground.spectrum  # type: ignore[union-attr]
    letter = "xyz"[axis]

    def density(f: np.ndarray) -> np.ndarray:  # velocity PSD over (2 pi f)^2: the floor's translation
        f = np.asarray(f, dtype=float)
        velocity = np.asarray(spectrum.velocity_psd(letter, f))  # type: ignore[union-attr]
        with np.errstate(over="ignore", divide="ignore"):  # 0 where the floor is still, even at f -> 0
            return np.divide(velocity, (2 * np.pi * f) ** 2, out=np.zeros_like(velocity), where=velocity > 0)

    weights = np.zeros(len(lin.input_names))
    weights[lin.input_names.index(f"ground:{letter}")] = 1.0
    return Source(name, density, spectrum.edges, weights, key="ground.spectrum")  # type: ignore[union-attr]


def _input(name: str, psd: SpectralDensity, weights: np.ndarray, key: str) -> Source:
    return Source(name, psd, psd.corners, weights, key=key)


def budget_sources(lin: LinearModel, sample_rate: float | None = None) -> tuple[Source, ...]:
    """The scenario's random sources: the floor on each axis its ``[ground.spectrum]`` gives, every
    ``[[disturbances]]`` entry, every actuator with a ``noise_psd`` and, with a controller sampling at
    ``sample_rate`` [Hz], every sensor with noise (``noise`` or ``noise_psd``).

    Parameters
    ----------
    lin : LinearModel
        The parked table.
    sample_rate : float, optional
        The controller's rate [Hz]; None: passive (no sensor sources).

    Returns
    -------
    tuple of Source
        In that order.
    """
    scenario = lin.scenario
    names = lin.input_names
    out: list[Source] = []
    spectrum = scenario.ground.spectrum if scenario.ground is not None else None
    if spectrum is not None:
        out += [_floor(lin, k, f"floor:{a}") for k, a in enumerate("xyz") if a in spectrum.values]
    for i, d in enumerate(scenario.disturbances):
        weights = point_force_weights(lin, d.position, d.direction, None, f"disturbances ({d.name})")
        out.append(_input(f"force:{d.name}", d.psd, weights, f"disturbances[{i}].psd"))
    for i, act in enumerate(scenario.actuators):
        if act.noise_psd is not None:
            weights = np.zeros(len(names))
            weights[names.index(f"actuator:{act.name}")] = 1.0
            out.append(_input(f"actuator:{act.name}", act.noise_psd, weights, f"actuators[{i}].noise_psd"))
    if sample_rate is not None:
        for i, sensor in enumerate(scenario.sensors):
            psd = sensor.noise_density(sample_rate)
            if psd is not None:
                key = f"sensors[{i}].{'noise_psd' if sensor.noise_psd is not None else 'noise'}"
                out.append(Source(f"sensor:{sensor.name}", psd, psd.corners, None, i, key))
    return tuple(out)
