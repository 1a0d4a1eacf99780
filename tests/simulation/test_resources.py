"""A run whose output grid the machine cannot hold is refused up front, through the Python API too."""

from __future__ import annotations

from dataclasses import replace

import pytest

from isolator import ParameterError, Simulator, load_scenario


def test_a_grid_too_large_for_memory_is_one_clear_error():
    s = load_scenario()
    huge = replace(s, simulation=replace(s.simulation, duration=1e9))
    with pytest.raises(ParameterError, match=r"^simulation\.duration x simulation\.sample_rate: .* GB of memory"):
        Simulator(huge)
