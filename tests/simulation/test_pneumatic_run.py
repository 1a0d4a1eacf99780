"""What a pneumatic run reports: pressure and height columns, leveling times, supply trouble, dynamic settling."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest
from pneumatic_cases import pneumatic_dict

from isolator import scenario_from_dict, simulate
from isolator.scenario.validation import rest_gauge_pressures
from isolator.simulation.leveling import LEVEL_BAND


@pytest.fixture(scope="module")
def leveled():
    """One carriage moving 0.8 m off centre, valves on, long enough to level."""
    s = scenario_from_dict(pneumatic_dict(valves=True, stroke=0.8, duration=16.0))
    return s, simulate(s)


def test_columns_and_json(leveled, tmp_path):
    s, r = leveled
    path = r.to_csv(tmp_path / "run.csv")
    with open(path) as handle:
        rows = list(csv.reader(handle))
    header = rows[0]
    names = [iso.name for iso in s.isolators]
    assert header[-7:] == [*(f"p:{n}" for n in names), "h:front", "h:rear-left", "h:rear-right"]
    first = np.array(rows[1][-7:-3], dtype=float)
    group_of = [next(j for j, g in enumerate(s.leveling) if k in g.isolators) for k in range(4)]
    np.testing.assert_allclose(first, rest_gauge_pressures(s)[group_of], rtol=1e-9)
    data = json.loads(json.dumps(r.to_dict()))
    assert set(data["leveling_time"]) == {"front", "rear-left", "rear-right"}
    assert all(v is not None and v > 0 for v in data["leveling_time"].values())
    assert data["dynamic_settling_time_max"] is not None
    assert data["supply_exhausted"] == {}


def test_leveling_time_is_when_the_sensor_stays_in_the_band(leveled):
    """Recomputed from the h: columns: the last sample outside 1.1 dead bands after the stop, plus one sample."""
    s, r = leveled
    result = r.pneumatic
    assert result is not None
    after = r.t >= s.stop_time
    for j, name in enumerate(result.group_names):
        band = LEVEL_BAND * s.leveling[j].valve.deadband  # type: ignore[union-attr]
        h = result.heights[j][after]
        last = np.flatnonzero(np.abs(h) > band)[-1]
        assert result.leveling_time[name] == pytest.approx(r.t[after][last + 1] - s.stop_time, abs=1e-9)
        assert np.all(np.abs(h[last + 1 :]) <= band)


def test_a_run_too_short_to_level_says_so():
    s = scenario_from_dict(pneumatic_dict(valves=True, stroke=0.8, duration=3.5))
    r = simulate(s)
    assert set(r.to_dict()["leveling_time"].values()) == {None}
    assert "not level by the end of the run" in r.summary()


def test_exhausted_supply_is_reported_not_a_silent_plateau():
    """The front group needs more than its supply after the carriage moves forward: reported with the time."""
    data = pneumatic_dict(valves=True, stroke=0.9, duration=12.0)
    s0 = scenario_from_dict(data)
    start, end = rest_gauge_pressures(s0), rest_gauge_pressures(s0, s0.final_positions())
    assert end[0] > start[0]
    data["leveling"][0]["supply"] = 0.5 * (start[0] + end[0])  # enough at rest, not after the move
    s = scenario_from_dict(data)
    r = simulate(s)
    result = r.pneumatic
    assert result is not None
    assert "front" in result.supply_exhausted
    assert 0.2 < result.supply_exhausted["front"] < r.t[-1]  # after the move starts (t0 = 0.2 s)
    assert result.leveling_time["front"] is None
    # the valve stops filling, so the front sags below its dead band and stays there
    deadband = data["leveling"][0]["valve"]["deadband"]
    assert np.all(result.heights[0][r.t > r.t[-1] - 2.0] < -10 * deadband)
    assert "air supply exhausted" in r.summary()
    assert "front" in r.to_dict()["supply_exhausted"]


def test_without_valves_the_dynamic_settling_is_the_ordinary_one():
    """Isothermal and closed: the air never changes, so the quasi-static pose is the final rest itself."""
    s = scenario_from_dict(pneumatic_dict(valves=False, polytropic=1.0, stroke=0.8, duration=8.0))
    r = simulate(s)
    result = r.pneumatic
    assert result is not None
    assert result.leveling_time == {}
    after = r.t >= s.stop_time
    assert r.final is not None
    np.testing.assert_allclose(result.quasi_static[:, after], np.broadcast_to(r.final[:, None], (6, after.sum())),
                               atol=1e-9 * np.max(np.abs(r.signals)))
    for k, v in r.settling_time.items():
        assert result.dynamic[k].time == pytest.approx(v, abs=1.5e-3)


def test_with_valves_the_dynamic_settling_leaves_out_the_leveling(leveled):
    s, r = leveled
    result = r.pneumatic
    assert result is not None
    dyn, full = result.dynamic_settling_time_max, r.settling_time_max
    assert dyn is not None
    assert full is not None
    assert dyn < 0.5 * full  # the slow re-leveling dominates the ordinary 5 % settling time
    # at the end the table is level, and the quasi-static pose (the air it has, at rest) is where it is
    end = r.signals[:, -1]
    assert np.max(np.abs(result.quasi_static[:, -1] - end)) < 1e-3 * np.max(np.abs(r.signals))
    assert math.isfinite(result.quasi_static[0, -1])
    assert np.all(np.isnan(result.quasi_static[:, r.t < s.stop_time - 1e-9]))


def test_leveling_figures_do_not_depend_on_the_output_rate():
    """Leveling times and the settling about the leveling table are read on a >= 1 kHz grid of the dense
    output, whatever the output sample rate."""
    results = []
    for rate in (5.0, 50.0, 1000.0):
        data = pneumatic_dict(valves=True, stroke=0.8, duration=16.0)
        data["simulation"]["sample_rate"] = rate
        r = simulate(scenario_from_dict(data))
        assert r.pneumatic is not None
        results.append((r.pneumatic.leveling_time, r.pneumatic.dynamic_settling_time_max))
    for levels, dynamic in results[:2]:
        assert dynamic == pytest.approx(results[-1][1], abs=2e-3)
        for name, value in levels.items():
            assert value == pytest.approx(results[-1][0][name], abs=2e-3)
