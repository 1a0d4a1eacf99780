"""Step-and-settle sequences: the event rule on hand-made signals, one step equal to the single move, the
sequence equal to a fixed-time run of the same moves, stop = start for a step that does not move,
measure = 0, the step that does not settle, designed moves, the output sample rate, CSV/JSON/figure."""

from __future__ import annotations

import copy
import csv
import json
from typing import Any

import numpy as np
import pytest

from conftest import base_dict
from isolator import (
    MotionLimits,
    ParameterError,
    ScenarioError,
    Simulator,
    load_scenario,
    run_sequence,
    scenario_from_dict,
    scurve,
    simulate,
    trapezoid,
)
from isolator.simulation.sequence import chain_scenario
from isolator.simulation.sequence_result import STEP_COLUMNS
from isolator.simulation.sequence_rule import held_from, normalised

PROBE = {"name": "probe", "position": [0.3, 0.0, 0.45]}
LIMITS = {"velocity": 0.2, "acceleration": 0.5, "jerk": 5.0}
#: +-200 nm: the probe of base_dict's table settles into it about 2.7 s after a 0.3 m move
WINDOW = 2e-7


def sequence_dict(sequence: dict[str, Any], duration: float = 30.0, rate: float = 1000.0) -> dict[str, Any]:
    data = base_dict(points=[PROBE], windows=[{"point": "probe", "translation": WINDOW}])
    carriage = data["carriages"][0]
    del carriage["profile"]
    carriage["limits"] = dict(LIMITS)
    data["sequence"] = sequence
    data["simulation"] = {"duration": duration, "sample_rate": rate}
    return data


THREE_STEPS = {"measure": 0.2, "start": 0.3, "initial": {"x-stage": -0.2},
               "steps": [{"x-stage": 0.1}, {"x-stage": 0.0}, {"x-stage": {"target": 0.2, "velocity": 0.1,
                                                                          "delay": 0.05}}]}


@pytest.fixture(scope="module")
def three():
    sc = scenario_from_dict(sequence_dict(THREE_STEPS))
    return sc, run_sequence(sc)


def _same_signals(mine: np.ndarray, theirs: np.ndarray) -> None:
    """The translations equal to 1e-8 of their largest peak, the rotations of theirs (solver tolerance)."""
    for rows in (slice(0, 3), slice(3, 6)):
        assert np.max(np.abs(mine[rows] - theirs[rows])) < 1e-8 * np.max(np.abs(theirs[rows]))


# -- the rule on hand-made signals -------------------------------------------------------------------------


def test_rule_waits_again_when_the_window_is_left_during_the_measurement():
    """Piecewise linear, window +-1: in from 1.5, out 2.5 .. 3.25 (1 s inside: too short for 1.5 s), in for good
    from 3.25; with measure 0.5 the first interval (1.5 .. 2.5) is enough."""
    t = np.linspace(1.0, 10.0, 901)
    d = np.interp(t, [0.0, 1.0, 2.0, 3.0, 3.5, 10.0], [3.0, 2.0, 0.0, 2.0, 0.0, 0.0])[None, :]
    assert held_from(t, d, 1.5) == pytest.approx(3.25, abs=1e-12)
    assert held_from(t, d, 0.5) == pytest.approx(1.5, abs=1e-12)
    assert held_from(t, d, 1.0) == pytest.approx(1.5, abs=1e-12)  # exactly the measure: enough
    assert held_from(t, d, 0.0) == pytest.approx(1.5, abs=1e-12)
    # the measurement must end within the data: 3.25 + 7 > 10
    assert held_from(t, d, 7.0) is None
    assert held_from(t, d, 6.75) == pytest.approx(3.25, abs=1e-12)


def test_rule_on_several_axes_and_windows():
    t = np.linspace(0.0, 4.0, 401)
    a = np.interp(t, [0.0, 1.0, 4.0], [2.0, 0.0, 0.0])      # in from 0.5
    b = np.interp(t, [0.0, 2.0, 2.2, 2.4, 4.0], [0.0, 0.0, -3.0, 0.0, 0.0])  # out 2.1333 .. 2.2667 (window 2)
    rows = normalised([a[None, :], b[None, :]], [1.0, 2.0])
    assert rows.shape == (2, t.size)
    inside = 2.0 + 0.2 * 2 / 3 - 0.5  # both windows hold from 0.5 until b leaves its own
    assert held_from(t, rows, 1.0) == pytest.approx(0.5, abs=1e-12)
    assert held_from(t, rows, inside - 1e-9) == pytest.approx(0.5, abs=1e-12)
    assert held_from(t, rows, inside + 1e-9) == pytest.approx(2.2 + 0.2 / 3, abs=1e-12)
    assert held_from(t, rows, 1.7) == pytest.approx(2.2 + 0.2 / 3, abs=1e-12)
    # a on its own (window 1): no wait
    assert held_from(t, normalised([a[None, :]], [1.0]), 3.5) == pytest.approx(0.5, abs=1e-12)


def test_rule_inside_at_the_stop_and_never_inside():
    t = np.linspace(0.0, 1.0, 101)
    assert held_from(t, np.full((1, t.size), 0.5), 0.3) == 0.0
    assert held_from(t, np.full((1, t.size), 1.5), 0.0) is None
    assert held_from(t, np.full((2, t.size), 0.5), 1.0) == 0.0
    assert held_from(t, np.full((1, t.size), 0.5), 1.5) is None


# -- sequences ---------------------------------------------------------------------------------------------


def test_one_step_equals_the_single_move():
    """The same S-curve as a plain scenario: the same response to solver tolerance, and the sequence's settled
    time equals the single move's window settling (measure longer than any gap between re-entries)."""
    data = sequence_dict({"measure": 1.0, "start": 0.3, "initial": {"x-stage": -0.2}, "steps": [{"x-stage": 0.1}]},
                         duration=6.0)
    result = run_sequence(scenario_from_dict(data))
    single = copy.deepcopy(data)
    del single["sequence"]
    single["carriages"][0]["profile"] = {"type": "scurve", "start": -0.2, "stroke": 0.3, "t0": 0.3, **LIMITS}
    response = simulate(scenario_from_dict(single))
    (step,) = result.steps
    assert step.start == 0.3
    assert step.stop == pytest.approx(response.stop_time, abs=1e-12)
    assert step.settle == pytest.approx(response.window_settling_time[0], abs=1e-6)
    assert 1.0 < step.settle < 4.0
    n = result.t.size
    assert n <= response.t.size
    np.testing.assert_allclose(result.t, response.t[:n], rtol=0, atol=1e-12)
    _same_signals(result.signals, response.signals[:, :n])
    np.testing.assert_allclose(result.point("probe"), response.point("probe")[:, :n], rtol=0, atol=1e-12)
    np.testing.assert_allclose(result.q[0], response.q[0, :n], rtol=0, atol=1e-12)


def test_sequence_equals_a_fixed_time_run_of_the_same_moves(three):
    """Each carriage's moves chained at the steps' start times, run as an ordinary scenario: the same response,
    and the rule read on its samples (1 kHz) gives the same settled times."""
    sc, result = three
    fixed = chain_scenario(sc, result, after=0.5)
    assert fixed.sequence is None
    response = Simulator(fixed).run()
    n = result.t.size
    _same_signals(result.signals, response.signals[:, :n])
    np.testing.assert_allclose(result.point_signals, response.point_signals[..., :n], rtol=0, atol=1e-12)
    np.testing.assert_allclose(result.q, response.q[:, :n], rtol=0, atol=1e-12)
    for step, settled in zip(result.steps, result.settled_points[:, 0], strict=True):
        after = (response.t > step.stop) & (response.t <= step.end + 0.5)
        t = np.concatenate([[step.stop], response.t[after]])
        moved = response.point("probe")[:, after] - settled[:, None]
        first = np.array([np.interp(step.stop, response.t, row) for row in response.point("probe")]) - settled
        rows = np.hstack([first[:, None], moved]) / WINDOW
        assert held_from(t, rows, 0.2) == pytest.approx(step.settled, abs=1e-6)
        # a margin from the window's edge where the wait ended: the settled time is no graze
        k = int(np.searchsorted(t, step.settled)) - 1
        assert np.max(np.abs(rows[:, k])) > 1.0 + 1e-6


def test_step_times_and_per_step_limits(three):
    _sc, result = three
    assert [s.index for s in result.steps] == [0, 1, 2]
    assert result.unsettled is None
    s0, s1, s2 = result.steps
    assert s0.start == 0.3
    assert s0.move == pytest.approx(scurve(-0.2, 0.3, **LIMITS).stop_time, abs=1e-12)
    assert s1.start == s0.end
    assert s2.start == s1.end
    assert s1.move == pytest.approx(scurve(0.1, -0.1, **LIMITS).stop_time, abs=1e-12)
    # the per-step velocity and the delay
    assert s2.move == pytest.approx(0.05 + scurve(0.0, 0.2, 0.1, 0.5, 5.0).stop_time, abs=1e-12)
    for s in result.steps:
        assert s.end == pytest.approx(s.settled + 0.2, abs=1e-12)
        assert s.settle == pytest.approx(s.settled - s.stop)
        assert 0.5 < s.settle < 5.0
    assert result.total_time == pytest.approx(s2.end - 0.3)
    assert result.throughput == pytest.approx(3 * 3600 / result.total_time)
    assert dict(s2.targets) == {"x-stage": 0.2}
    # the carriages follow the moves: at rest at each target once the step stops
    for s in result.steps:
        k = np.searchsorted(result.t, s.stop + 0.01)
        assert result.q[0, k] == pytest.approx(dict(s.targets)["x-stage"], abs=1e-12)
    # settled positions: the static equilibrium at each target (the probe moves with the carriage's weight)
    assert np.all(np.abs(np.diff(result.settled_points[:, 0, 0])) > 1e-7)


def test_a_step_that_does_not_move_has_stop_equal_start():
    data = sequence_dict({"measure": 0.1, "steps": [{"x-stage": 0.1}, {"x-stage": 0.1}, {"x-stage": 0.0}]})
    result = run_sequence(scenario_from_dict(data))
    s0, s1, s2 = result.steps
    assert s1.stop == s1.start == s0.end
    assert s1.move == 0.0
    # the table already held the window for the previous measurement: settled at once
    assert s1.settled == s1.stop
    assert s1.end == pytest.approx(s1.start + 0.1)
    assert s2.move > 0.5


def test_measure_zero_settles_at_the_first_entry():
    data = sequence_dict({"measure": 0.0, "steps": [{"x-stage": 0.1}, {"x-stage": -0.1}]})
    result = run_sequence(scenario_from_dict(data))
    for s in result.steps:
        assert s.end == s.settled
        # the first entry: the probe is outside just before it (by linear interpolation, on the window's edge)
        before = (result.t > s.stop) & (result.t < s.settled)
        dev = result.deviation("probe")[:, before]
        assert np.max(np.abs(dev)) > WINDOW
    later = scenario_from_dict(sequence_dict({"measure": 0.5, "steps": [{"x-stage": 0.1}, {"x-stage": -0.1}]}))
    assert run_sequence(later).steps[0].settled >= result.steps[0].settled


def test_unsettled_step_is_reported():
    data = sequence_dict({"measure": 0.1, "steps": [{"x-stage": 0.1}, {"x-stage": -0.1}, {"x-stage": 0.0}]},
                         duration=5.0)
    result = run_sequence(scenario_from_dict(data))
    assert result.unsettled == 1
    assert len(result.steps) == 2
    assert result.steps[0].end is not None
    last = result.steps[1]
    assert last.settled is None
    assert last.end is None
    assert last.settle is None
    assert result.total_time is None
    assert result.throughput is None
    assert result.t[-1] == pytest.approx(5.0)
    summary = result.to_dict()
    assert summary["unsettled"] == 1
    assert summary["steps"][1]["settled"] is None
    assert "step 1 did not settle within the run's 5 s" in result.summary()


def test_output_rate_does_not_change_the_settled_times(three):
    _sc, result = three
    coarse = run_sequence(scenario_from_dict(sequence_dict(THREE_STEPS, rate=50.0)))
    for a, b in zip(result.steps, coarse.steps, strict=True):
        assert b.settled == pytest.approx(a.settled, abs=1e-9)
    assert coarse.t[1] == pytest.approx(0.02)


def test_designed_moves_replace_the_s_curve(three):
    sc, _result = three
    calls = []

    def move(k: int, name: str, q0: float, q1: float, limits: MotionLimits):
        calls.append((k, name, q0, q1, limits))
        return trapezoid(q0, q1 - q0, limits.velocity, limits.acceleration)

    designed = run_sequence(sc, move=move)
    assert [c[:4] for c in calls] == [(0, "x-stage", -0.2, 0.1), (1, "x-stage", 0.1, 0.0), (2, "x-stage", 0.0, 0.2)]
    assert calls[2][4] == MotionLimits(0.1, 0.5, 5.0)
    assert designed.steps[0].move == pytest.approx(trapezoid(-0.2, 0.3, 0.2, 0.5).stop_time)
    assert designed.steps[2].move == pytest.approx(trapezoid(0.0, 0.2, 0.1, 0.5).stop_time)  # no delay added
    with pytest.raises(ParameterError, match=r"move: step 0, carriage 'x-stage': the profile goes from"):
        run_sequence(sc, move=lambda k, n, q0, q1, lim: trapezoid(q0, 0.5 * (q1 - q0), 0.2, 0.5))
    with pytest.raises(ParameterError, match="must return a Profile"):
        run_sequence(sc, move=lambda *args: None)  # type: ignore[arg-type,return-value]


def test_scenario_without_sequence_or_windows_is_refused():
    with pytest.raises(ScenarioError, match=r"^sequence: the scenario has no \[sequence\]"):
        run_sequence(load_scenario("paper-table-3-2"))
    data = sequence_dict({"measure": 0.1, "steps": [{"x-stage": 0.1}]})
    del data["windows"]
    with pytest.raises(ScenarioError, match=r"^windows: a \[sequence\] needs at least one"):
        run_sequence(scenario_from_dict(data))


def test_outputs(three, tmp_path):
    _sc, result = three
    steps = result.write_steps(tmp_path / "steps.csv")
    with open(steps) as handle:
        rows = list(csv.reader(handle))
    assert tuple(rows[0]) == STEP_COLUMNS == ("step", "start", "stop", "settled", "end", "move", "settle")
    assert len(rows) == 4
    assert float(rows[2][4]) == pytest.approx(result.steps[1].end)
    response = result.write_response(tmp_path / "response.csv")
    with open(response) as handle:
        rows = list(csv.reader(handle))
    assert rows[0] == ["t", "x", "y", "z", "rx", "ry", "rz", "q:x-stage", "probe:x", "probe:y", "probe:z", "step"]
    assert len(rows) == result.t.size + 1
    data = json.loads(json.dumps(result.to_dict()))
    assert {"steps", "total_time", "throughput_per_hour", "unsettled", "measure"} <= set(data)
    assert set(data["steps"][0]) >= {"start", "stop", "settled", "end", "move", "settle"}
    assert data["throughput_per_hour"] == pytest.approx(result.throughput)


def test_plot(three):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    _, result = three
    fig = result.plot()
    ax = fig.axes[0]
    assert "[nm]" in ax.get_ylabel()
    assert "[s]" in fig.axes[1].get_xlabel()
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert {"move", "settle", "measure"} <= set(labels)
    assert any("window ±200 nm" in label for label in labels)
    plt.close(fig)


def test_bundled_sequence_runs_fast_and_reasonably():
    result = run_sequence(load_scenario("paper-table-3-2-sequence"))
    assert result.unsettled is None
    assert len(result.steps) == 20
    assert 60.0 < result.total_time < 150.0
    assert all(1.0 < s.settle < 6.0 for s in result.steps)
    assert 400 < result.throughput < 1500


def test_pneumatic_sequence_carries_the_chambers_over():
    """The chamber pressures (and the valves acting on them) continue from step to step: the sequence equals a
    fixed-time run of the same moves. The window is microns: the valves' dead band leaves the table off its
    level rest by some (tens of nanometres are out of reach of this table)."""
    import tomllib

    from isolator import bundled_scenarios

    data = tomllib.loads(bundled_scenarios()["paper-table-3-2-pneumatic"].read_text())
    for c in data["carriages"]:
        del c["profile"]
        c["limits"] = dict(LIMITS)
    data["points"] = [{"name": "probe", "position": [0.0, 0.0, 0.5]}]
    data["windows"] = [{"point": "probe", "translation": 3e-5}]
    data["sequence"] = {"measure": 0.1, "start": 0.5, "initial": {"x-stage": -0.2},
                        "steps": [{"x-stage": -0.1}, {"x-stage": 0.1, "y-stage": 0.1}, {"x-stage": 0.0}]}
    data["simulation"]["duration"] = 30.0
    sc = scenario_from_dict(data)
    result = run_sequence(sc)
    assert result.unsettled is None
    assert all(0.5 < s.settle < 5.0 for s in result.steps)
    response = Simulator(chain_scenario(sc, result, after=0.5)).run()
    n = result.t.size
    np.testing.assert_allclose(result.point_signals, response.point_signals[..., :n], rtol=0, atol=1e-11)
    pressures = result.states[:, 13:]
    assert np.max(np.abs(pressures - response.states[:n, 13:])) < 1e-9 * np.max(np.abs(pressures))


def test_moving_floor_keeps_the_sequence_time():
    """The floor's motion is read at the sequence's time (not the step's): equal to the fixed-time run."""
    data = sequence_dict({"measure": 0.1, "start": 0.4, "steps": [{"x-stage": 0.1}, {"x-stage": -0.1}]})
    data["ground"] = {"z": {"type": "trapezoid", "start": 0.0, "stroke": 1e-8, "velocity": 1e-7,
                            "acceleration": 1e-5, "t0": 0.2}}
    sc = scenario_from_dict(data)
    result = run_sequence(sc)
    assert result.unsettled is None
    response = Simulator(chain_scenario(sc, result, after=0.5)).run()
    n = result.t.size
    np.testing.assert_allclose(result.point_signals, response.point_signals[..., :n], rtol=0, atol=1e-12)
