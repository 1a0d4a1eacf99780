"""What a run will need, checked before it starts: memory for the output grid."""

from __future__ import annotations

from isolator.scenario.definitions import Scenario
from isolator.scenario.files import available_memory, check_memory

__all__ = ["available_memory", "check_memory", "check_run_memory"]


def check_run_memory(scenario: Scenario) -> None:
    """Refuse a run whose output grid (``simulation.duration`` x ``simulation.sample_rate``) needs more
    memory than the machine has: the states, the signals and the integrator's dense output per sample."""
    sim = scenario.simulation
    samples = sim.duration * sim.sample_rate + 1
    states = 12 + 2 * len(scenario.carriages) + 4 * len(scenario.isolators) + len(scenario.actuators)
    check_memory(samples * 8 * (6 * states + 24),
                 f"simulation.duration x simulation.sample_rate: {sim.duration:g} s at {sim.sample_rate:g} Hz, "
                 f"{samples:.3g} output samples,", "shorten the run or lower the sample rate")
