"""What a run will need, checked before it starts: memory for the output grid."""

from __future__ import annotations

import os

from isolator.errors import ParameterError
from isolator.scenario.definitions import Scenario

__all__ = ["available_memory", "check_memory", "check_run_memory"]


def available_memory() -> int | None:
    """Bytes of memory available to a new allocation (Linux ``MemAvailable``), None if unknown."""
    try:
        with open("/proc/meminfo") as handle:
            for line in handle:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def _gb(n: float) -> str:
    return f"{n / 1e9:.3g} GB"


def check_memory(needed: float, what: str, fix: str) -> None:
    """Refuse up front what needs more memory than the machine has available, with the estimate.

    ``what`` starts with the key or option it comes from (``--points: 1e+09 frequencies``)."""
    have = available_memory()
    if have is not None and needed > have:
        raise ParameterError(f"{what} need about {_gb(needed)} of memory, more than the {_gb(have)} this machine "
                             f"has available; {fix}")


def check_run_memory(scenario: Scenario) -> None:
    """Refuse a run whose output grid (``simulation.duration`` x ``simulation.sample_rate``) needs more
    memory than the machine has: the states, the signals and the integrator's dense output per sample."""
    sim = scenario.simulation
    samples = sim.duration * sim.sample_rate + 1
    states = 12 + 2 * len(scenario.carriages) + 4 * len(scenario.isolators) + len(scenario.actuators)
    check_memory(samples * 8 * (6 * states + 24),
                 f"simulation.duration x simulation.sample_rate: {sim.duration:g} s at {sim.sample_rate:g} Hz, "
                 f"{samples:.3g} output samples,", "shorten the run or lower the sample rate")
