"""What a run will need, checked before it starts: memory for the output grid."""

from __future__ import annotations

from isolator.scenario.definitions import Scenario
from isolator.scenario.files import available_memory, check_memory
from isolator.simulation.time_grid import internal_rate

__all__ = ["available_memory", "check_memory", "check_run_memory"]


def check_run_memory(scenario: Scenario, what: str | None = None) -> None:
    """Refuse a run whose output grid (``simulation.duration`` x ``simulation.sample_rate``) needs more
    memory than the machine has: the states, the signals and the integrator's dense output per sample, and
    the inputs at every node of the internal grid (at least 1 kHz however low the sample rate: a 2-sample
    record spanning 10^6 s is a grid of 10^9 nodes). ``what`` names the run in the message (default the
    two keys)."""
    sim = scenario.simulation
    samples = sim.duration * sim.sample_rate + 1
    nodes = sim.duration * internal_rate(sim)[0] + 1
    inputs = 6 + 2 * len(scenario.carriages) + len(scenario.actuators)
    states = 12 + 2 * len(scenario.carriages) + 4 * len(scenario.isolators) + len(scenario.actuators)
    check_memory(samples * 8 * (6 * states + 24) + nodes * 8 * (4 + 3 * inputs),
                 what or f"simulation.duration x simulation.sample_rate: {sim.duration:g} s at {sim.sample_rate:g} "
                 f"Hz, {samples:.3g} output samples ({nodes:.3g} steps),", "shorten the run or lower the sample rate")
