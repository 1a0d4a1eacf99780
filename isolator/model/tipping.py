"""Will the table stand? One criterion for ``isolator stability`` and for every simulation.

The table stands when its condensed rocking stiffness (:class:`~isolator.model.equilibrium.RockingStiffness`)
is positive at rest with the carriages anywhere in their travel: at the start, at the end, and at
every combination of each carriage's stroke limits and mid-point over the run (and over the
configurations of a ``[sequence]``). The exact model's
static pose is used where one exists, else the upright pose. :func:`tipping_verdict` gives the one
line both the stability report and a refused simulation print.
"""

from __future__ import annotations

import itertools

import numpy as np

from isolator.errors import UnstableTableError
from isolator.model.equilibrium import RockingStiffness, rocking_stiffness, static_equilibria, static_equilibrium
from isolator.model.variants import Model
from isolator.scenario.definitions import Scenario

__all__ = ["rocking_over", "tipping_verdict", "travel_configurations"]


def travel_configurations(scenario: Scenario) -> np.ndarray:
    """Carriage coordinates [m] to check, (configurations, carriages): the start, the end (when the
    carriages stop), and every combination of each carriage's extremes and mid-point over the run."""
    # a [sequence] moves the carriages between its configurations (the S-curves stay between them)
    levels = [sorted({lo, 0.5 * (lo + hi), hi}) for lo, hi in scenario.travel().tolist()]
    configs = [scenario.initial_positions()]
    finals = scenario.final_positions()
    if finals is not None:
        configs.append(finals)
    configs += [np.array(combo, dtype=float) for combo in itertools.product(*levels)] if levels else []
    return np.array(configs, dtype=float).reshape(len(configs), -1)


def rocking_over(model: Model, p: np.ndarray, configs: np.ndarray) -> tuple[RockingStiffness, ...]:
    """The rocking stiffness at rest in each configuration (rows of ``configs``) of the exact ``model`` (the rests
    solved side by side, each row's Newton iterations its own; one by one when one of them has none)."""
    try:
        poses = [rest.pose for rest in static_equilibria(model, np.asarray(p, dtype=float)[None], configs,
                                                         check=False)]
    except UnstableTableError:
        poses = []
        for q in configs:
            try:
                poses.append(static_equilibrium(model, p, q, check=False).pose)
            except UnstableTableError:  # no equilibrium near upright: judge the upright pose
                poses.append(np.zeros(6))
    return tuple(rocking_stiffness(model, p, q, pose) for q, pose in zip(configs, poses, strict=True))


def tipping_verdict(configs: np.ndarray, rocking: tuple[RockingStiffness, ...]) -> tuple[bool, int, str]:
    """Whether the table stands (every margin > 0), the configuration with the smallest margin, and
    the one line that says so."""
    worst = int(np.argmin([r.margin for r in rocking]))
    r = rocking[worst]
    # nothing acts on the rotations (no gravity, no stiffness: a free-floating table) is neutral, not tipping
    idle = all(np.all(np.abs(x.values) <= 1e-12) and np.all(np.abs(x.elastic) <= 1e-12) for x in rocking)
    stable = r.margin > 0.0 or idle
    where = ", ".join(f"{q:.4g}" for q in configs[worst]) or "no carriages"
    verdict = ("neutral (nothing resists or drives a rotation)" if idle else "stable") if stable else (
        "UNSTABLE: the table would tip")
    return stable, worst, f"{verdict}; smallest {r.describe()}, with the carriages at [{where}] m"
