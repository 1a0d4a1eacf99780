"""Trust round 4 (issue 42), item 12: a calibration misfit named where it is. A few bad samples (a spike, a step)
are named by time and size in sigma, not blamed on units or directions; a record in other units is judged by
its magnitude on the nominal model (a fit it forced is no reference), so it is not taken for a flipped sensor; a
record whose time is in milliseconds is refused before any work. Small and fast: the goodness test on made-up
residuals, the time check on the bundled example's records."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from isolator import ScenarioError, load_scenario
from isolator.calibration.calibrate import read_records
from isolator.calibration.definition import bundled_calibrations, load_calibration
from isolator.calibration.experiments import FloorExperiment, MoveExperiment, check_time_columns
from isolator.calibration.goodness import goodness_of_fit
from isolator.calibration.records import Record

SENSORS = load_scenario("paper-table-3-2-geophones").sensors[:4]
FLOOR = load_scenario("paper-table-3-2-geophones").sensors[4:5]  # any sensor stands for a floor one here
N = 2000
T = np.arange(N) / 500.0


def _move(y: np.ndarray) -> MoveExperiment:
    experiment = object.__new__(MoveExperiment)
    experiment.name, experiment.table, experiment.t, experiment.y = "move", SENSORS, T, y
    return experiment


def _model(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    phases = rng.uniform(0, 2 * np.pi, size=(len(SENSORS), 1))
    return np.sin(2 * np.pi * 3.1 * T[None, :] + phases) * np.exp(-T[None, :] / 2)  # a decaying mode, sigma units


@given(seed=st.integers(0, 2**16), channel=st.integers(0, len(SENSORS) - 1), at=st.integers(10, N - 10),
       size=st.floats(25.0, 1e6), step=st.booleans())
@settings(max_examples=40, deadline=None)
def test_a_bad_sample_is_named_by_its_time_and_size(seed, channel, at, size, step):
    rng = np.random.default_rng(seed)
    model = 40.0 * _model(seed)
    y = model + rng.normal(size=model.shape)
    if step:
        y[channel, at:] += size
    else:
        y[channel, at] += size
    g = goodness_of_fit(_move(y), "move.csv", (model - y).ravel(), 6.0, model, model)
    assert g.jump is not None
    name, when, sigma = g.jump
    assert name == SENSORS[channel].name
    assert when in (T[at], T[at + 1])
    assert sigma == pytest.approx(size, rel=0.1, abs=10)
    assert g.diagnosis.startswith(f"the misfit sits at t = {when:.6g} s in {name}: a jump of ")
    assert "flipped" not in g.diagnosis
    assert "times the model's" not in g.diagnosis


@given(seed=st.integers(0, 2**16))
@settings(max_examples=20, deadline=None)
def test_noise_and_a_smooth_misfit_have_no_bad_sample(seed):
    rng = np.random.default_rng(seed)
    model = 40.0 * _model(seed)
    y = 1.3 * model + rng.normal(size=model.shape)  # a model 30 % off: a misfit, spread over every sample
    g = goodness_of_fit(_move(y), "move.csv", (model - y).ravel(), 6.0, model, model)
    assert g.jump is None
    assert "misfit sits" not in g.diagnosis


@given(power=st.sampled_from([3, 6]), seed=st.integers(0, 2**16))
@settings(max_examples=10, deadline=None)
def test_a_floor_record_in_other_units_is_not_taken_for_a_flipped_sensor(power, seed):
    rng = np.random.default_rng(seed)
    h = rng.normal(size=(len(SENSORS), 3, 50)) + 1j * rng.normal(size=(len(SENSORS), 3, 50))
    experiment = _floor(10.0**power * h, rng.normal(size=(len(SENSORS) + 1, N)))
    forced = -h  # a fit dragged to the wrong shape by the record: its sign is no clue
    g = goodness_of_fit(experiment, "floor.csv", np.ones(2 * h.size) * 30.0, 6.0, forced, h)
    assert "flipped" not in g.diagnosis
    assert f"about {10.0**power:g} times the model's" in g.diagnosis


def _floor(h1: np.ndarray, samples: np.ndarray) -> FloorExperiment:
    experiment = object.__new__(FloorExperiment)
    experiment.name, experiment.table, experiment.floor, experiment.H1 = "floor", SENSORS, FLOOR, h1
    experiment.t, experiment.samples = T, samples
    return experiment


@given(seed=st.integers(0, 2**16), channel=st.integers(0, len(SENSORS)), at=st.integers(10, N - 10),
       size=st.floats(25.0, 1e6))
@settings(max_examples=20, deadline=None)
def test_a_bad_sample_in_a_floor_record_is_named(seed, channel, at, size):
    rng = np.random.default_rng(seed)
    h = rng.normal(size=(len(SENSORS), 1, 50)) + 0j
    samples = rng.normal(size=(len(SENSORS) + 1, N))  # the table's channels, then the floor's, in sigma
    samples[channel, at] += size
    g = goodness_of_fit(_floor(1.1 * h, samples), "floor.csv", np.ones(2 * h.size) * 30.0, 6.0, h, h)
    assert g.jump is not None
    assert g.jump[0] == (*SENSORS, *FLOOR)[channel].name
    assert g.jump[1] in (T[at], T[at + 1])
    assert g.diagnosis.startswith("the misfit sits at t = ")


def test_a_flipped_sensor_is_still_named():
    model = 40.0 * _model(1)
    y = model.copy()
    y[2] *= -1
    g = goodness_of_fit(_move(y), "move.csv", (model - y).ravel(), 6.0, model, model)
    assert f"{SENSORS[2].name} reads about -1 times the model's" in g.diagnosis
    assert g.jump is None


@pytest.fixture(scope="module")
def example():
    calibration = load_calibration(bundled_calibrations()["table-3-2"])
    return calibration, read_records(calibration)


@given(factor=st.sampled_from([1e3, 60.0, 1e7]), which=st.sampled_from(["floor-random", "move"]))
@settings(max_examples=6, deadline=None)
def test_a_record_too_slow_for_its_experiment_is_refused_before_any_work(example, factor, which):
    calibration, records = example
    slow = dict(records)
    record = records[which]
    slow[which] = Record(record.path, record.t * factor, record.channels)
    with pytest.raises(ScenarioError) as error:
        check_time_columns(calibration, slow)
    message = str(error.value)
    assert message.startswith(f"experiments['{which}']: the record {record.path.name} is sampled at ")
    assert ("is its t column in milliseconds?" in message) == (factor < 1e7)  # 1e7: no unit makes it fast enough


def test_the_bundled_records_pass_the_time_check(example):
    check_time_columns(*example)
