"""Numbers a user can trust (issue 15): no silent wrong answer from the simulation's metrics.

Each test here failed on the code before the fix it guards.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import active_dict, asymmetric_3d_dict, base_dict, make, tipping_dict
from isolator import Simulator
from isolator.errors import ScenarioError
from isolator.simulation.actuation import ForceHistory
from isolator.simulation.settling import settling_metrics


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


# -- metrics that do not depend on the output sample rate --------------------------------
def _at_rate(data: dict, rate: float) -> dict:
    out = {**data, "simulation": {**data["simulation"], "sample_rate": rate}}
    return out


def _metrics(response) -> tuple[np.ndarray, np.ndarray]:
    times = np.array([np.nan if v is None else v for v in response.settling_time.values()])
    return np.array(list(response.peak.values())), times


@pytest.mark.parametrize("case", ["base", "asymmetric"])
def test_peaks_and_settling_are_the_same_at_5_50_and_1000_hz_output(case):
    data = base_dict() if case == "base" else asymmetric_3d_dict(duration=6.0)
    runs = [_metrics(Simulator(make(_at_rate(data, rate))).run()) for rate in (5.0, 50.0, 1000.0)]
    for peaks, times in runs[:2]:
        np.testing.assert_allclose(peaks, runs[2][0], rtol=1e-9, atol=1e-15)  # rounding: 1e-16 m
        np.testing.assert_allclose(times, runs[2][1], rtol=0, atol=1e-9)
    assert np.isfinite(runs[2][1]).sum() >= 3  # the test compares numbers, not only NaNs


def test_dense_metrics_match_a_very_fine_output_grid():
    """The peaks and settling instants from the dense output agree with those of 20 kHz samples
    (which are right to their 50 us spacing)."""
    data = base_dict()
    coarse = Simulator(make(_at_rate(data, 5.0))).run()
    fine = Simulator(make(_at_rate(data, 20000.0))).run()
    sampled = settling_metrics(fine.t, fine.signals, fine.final, fine.stop_time, make(data).settling)
    for name, result in coarse.settling.items():
        assert result.peak == pytest.approx(sampled[name].peak, rel=1e-7)
        if result.time is not None and result.time > 0:
            assert result.time == pytest.approx(sampled[name].time, abs=1e-4)
            # and the instant is the band's edge: the signal is on it to the interpolation's accuracy
            t_cross = fine.stop_time + result.time
            i = int(np.argmin(np.abs(fine.t - t_cross)))
            k = list(coarse.settling).index(name)
            assert abs(abs(fine.signals[k, i] - fine.final[k]) - result.band) < 0.05 * result.band


def test_actuator_runs_step_on_an_internal_grid_whatever_the_output_rate():
    data = active_dict()
    runs = []
    for rate in (5.0, 50.0, 1000.0):
        scenario = make(_at_rate(data, rate))
        names = tuple(a.name for a in scenario.actuators)
        t = np.array([0.0, 0.3, 0.3, 0.6, 0.6, 3.0])
        force = np.zeros((len(names), t.size))
        force[2] = [0.0, 0.0, 200.0, 200.0, 0.0, 0.0]  # a 0.3 s push on z0
        runs.append(_metrics(Simulator(scenario).run(forces=ForceHistory(t, force, names))))
    for peaks, times in runs[:2]:
        np.testing.assert_allclose(peaks, runs[2][0], rtol=1e-9, atol=1e-15)  # rounding: 1e-16 m
        np.testing.assert_allclose(times, runs[2][1], rtol=0, atol=1e-9)


def test_a_batch_gives_the_single_runs_metrics_at_a_coarse_output_rate():
    data = _at_rate(base_dict(), 5.0)
    sim = Simulator(make(data))
    batch = sim.run_batch([0.7, 1.0, 1.6], [2.0, 1.0, 0.7])
    for i, (k, c) in enumerate(((0.7, 2.0), (1.0, 1.0), (1.6, 0.7))):
        peaks, times = _metrics(sim.run(p=sim.scaled_parameters(k, c)))
        np.testing.assert_allclose(batch.peak[i], peaks, rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose(batch.settling_time[i], times, rtol=0, atol=1e-9, equal_nan=True)


# -- stability and simulation agree near the tipping limit ---------------------------------
@pytest.mark.parametrize("factor", [1 - 1e-3, 1 - 1e-6, 1 + 1e-9, 1 + 1e-6, 1 + 1e-3])
def test_simulate_refuses_exactly_what_stability_calls_unstable_in_its_words(factor):
    from isolator.analysis.stability import stability
    from isolator.errors import UnstableTableError

    reference = make(tipping_dict(0.2))
    weight = reference.gravity * reference.total_mass
    critical = sum(iso.stiffness[2] * iso.position[1] ** 2 for iso in reference.isolators) / weight  # W h = sum kz y^2
    scenario = make(tipping_dict(factor * critical))
    report = stability(scenario)
    assert report.stable == (factor < 1)
    if report.stable:
        assert Simulator(scenario).run().t.size > 1  # it simulates
    else:
        with pytest.raises(UnstableTableError) as refused:
            Simulator(scenario).run()
        assert str(refused.value) == report.describe()


# -- impulsive moves ----------------------------------------------------------------------
def _impulsive(acceleration: float, active: bool = False) -> dict:
    data = active_dict() if active else base_dict()
    data["carriages"][0]["profile"] = {"type": "trapezoid", "start": -0.4, "stroke": 0.8, "velocity": 0.4,
                                       "acceleration": acceleration, "t0": 0.2}
    data["simulation"]["duration"] = 3.0
    return data


@pytest.mark.parametrize("active", [False, True])
def test_an_impulsive_move_keeps_its_pulse(active):
    """A phase of 4e-11 s (1e10 m/s^2) delivers the same momentum as one of 4e-7 s: the same response
    (it used to be merged with the breakpoint next to it and lost)."""
    responses = []
    for acceleration in (1e6, 1e10):
        scenario = make(_impulsive(acceleration, active))
        names = tuple(a.name for a in scenario.actuators)
        forces = ForceHistory(np.array([0.0, 3.0]), np.zeros((len(names), 2)), names) if active else None
        responses.append(Simulator(scenario).run(forces=forces))
    slow, fast = (np.array(list(r.peak.values())) for r in responses)
    np.testing.assert_allclose(fast, slow, rtol=1e-5, atol=1e-15)


def test_a_phase_too_short_to_resolve_is_refused_naming_the_profile():
    expected = r"carriages\[0\]\.profile: a phase of 4e-14 s at t = 0\.2 s .*at least 1e-12 s"
    with pytest.raises(ScenarioError, match=expected):
        Simulator(make(_impulsive(1e13))).run()
