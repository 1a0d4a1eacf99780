"""Numbers a user can trust (issue 15): no silent wrong answer from the simulation's metrics.

Each test here failed on the code before the fix it guards.
"""

from __future__ import annotations

import pytest

from conftest import base_dict, make
from isolator import Simulator
from isolator.errors import ScenarioError


# -- a run shorter than the motion ------------------------------------------------------
def test_a_run_that_ends_before_the_carriage_starts_is_an_error_naming_duration_start_and_stop():
    data = base_dict()
    data["simulation"]["duration"] = 0.1  # the move starts at 0.2 s and stops at 2.65 s
    with pytest.raises(ScenarioError, match=r"simulation\.duration.*starts moving at 0\.2 s.*stops at 2\.65 s"):
        Simulator(make(data)).run()


def test_a_run_that_ends_before_the_stop_is_an_error_naming_duration_and_the_stop_time():
    data = base_dict()
    data["simulation"]["duration"] = 1.0
    with pytest.raises(ScenarioError, match=r"simulation\.duration: 1 s .*stops at 2\.65 s \(stop time\)"):
        Simulator(make(data)).run()


def test_a_run_that_includes_the_stop_but_ends_before_settling_reports_not_settled():
    data = base_dict()
    data["simulation"]["duration"] = 2.7  # 50 ms after the stop
    response = Simulator(make(data)).run()
    assert response.settling_time_max is None
    assert "lengthen simulation.duration" in response.settling["x"].reason


def test_the_whole_scenario_validator_names_the_duration_too():
    from isolator.scenario.validation import validate_scenario

    data = base_dict()
    scenario = make(data)
    short = scenario.with_changes(simulation=type(scenario.simulation)(duration=2.0, sample_rate=1000.0))
    with pytest.raises(ScenarioError, match=r"simulation\.duration"):
        validate_scenario(short)
