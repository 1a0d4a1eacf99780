"""Hostile controllers (issue 35, item 9): ``controller.json`` checked against its schema before use, an
unstable controller warned about, and one that blows up in a run an error naming it and the sample, not
NaN commands clipped to the force limits and a run that "succeeds"."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from isolator import ParameterError, SimulationError, Simulator, load_scenario
from isolator.simulation.discrete_controller import DiscreteController


@pytest.fixture(scope="module")
def scenario():
    return load_scenario("paper-table-3-2-geophones")


def _good(scenario, a: float = 0.5) -> dict:
    p, m = len(scenario.sensors), len(scenario.actuators)
    return DiscreteController(1000.0, [s.name for s in scenario.sensors], [x.name for x in scenario.actuators],
                              [c.name for c in scenario.carriages], A=a * np.eye(1), B=np.full((1, p), 1e-3),
                              C=np.full((m, 1), 1e-3), D=np.zeros((m, p))).to_dict()


def _schedule(data: dict) -> dict:
    entry = {k: data[k] for k in "ABCD"}
    return dict(data, schedule=[{"q": [0.0, 0.0], **entry}, {"q": [0.1, 0.0], **entry}], schedule_carriage=0)


CASES = [  # (change to a good controller.json, the key the message starts with)
    (lambda d: dict(d, delay="false"), "controller.delay: must be true or false, got the string 'false'"),
    (lambda d: dict(d, delay=1), "controller.delay: must be true or false"),
    (lambda d: dict(d, sample_rate="1000"), "controller.sample_rate: must be a number"),
    (lambda d: dict(d, sample_rate=True), "controller.sample_rate: must be a number"),
    (lambda d: dict(d, A=[["0.5"]]), "controller.A[0]: must be a list of numbers"),
    (lambda d: dict(d, A=[[True]]), "controller.A[0]: must be a list of numbers"),
    (lambda d: dict(d, A=0.5), "controller.A: must be a list of rows"),
    (lambda d: dict(d, B=[d["B"][0], [1.0]]), "controller.B[1]: 1 numbers where row 0 has"),
    (lambda d: dict(d, C=[[1e308 * 10]] * len(d["C"])), "C: every entry must be finite"),
    (lambda d: {k: v for k, v in d.items() if k != "D"}, "controller.D: missing"),
    (lambda d: dict(d, sensors="v-x1"), "controller.sensors: must be a list of names"),
    (lambda d: dict(d, sensors=[1, *d["sensors"][1:]]), "controller.sensors[0]: must be a name"),
    (lambda d: dict(d, sensors=["a\nb", *d["sensors"][1:]]), "controller.sensors[0]: must be at most 100"),
    (lambda d: dict(d, settings=[]), "controller.settings: must be an object"),
    (lambda d: dict(d, method=None), "controller.method: must be a string"),
    (lambda d: dict(_schedule(d), schedule=[{k: v for k, v in e.items() if k != "q"}
                                           for e in _schedule(d)["schedule"]]),
     "controller.schedule[0].q: missing"),
    (lambda d: dict(_schedule(d), schedule_carriage="0"), "controller.schedule_carriage: must be a whole number"),
    (lambda d: dict(_schedule(d), schedule={"q": []}), "controller.schedule: must be a list"),
    (lambda d: [d], "controller: must be a JSON object"),
]


@pytest.mark.parametrize(("change", "named"), CASES)
def test_the_schema_refuses_each_bad_value_naming_its_key(scenario, change, named):
    with pytest.raises(ParameterError) as error:
        DiscreteController.from_dict(change(_good(scenario)))
    assert str(error.value).startswith(named), str(error.value)


@given(value=st.one_of(st.text(max_size=8), st.booleans(), st.none(), st.dictionaries(st.text(max_size=3),
                                                                                        st.integers(), max_size=2)))
def test_generated_wrong_types_in_a_matrix_are_refused(value):
    with pytest.raises(ParameterError, match=r"^controller\.A"):
        DiscreteController.from_dict({"sample_rate": 100.0, "sensors": ["s"], "actuators": ["a"], "A": [[value]],
                                      "B": [[0.0]], "C": [[0.0]], "D": [[0.0]]})


def test_an_unknown_key_is_warned_about(scenario):
    with pytest.warns(RuntimeWarning, match=r"^controller\.dealy: unknown key, ignored"):
        DiscreteController.from_dict(dict(_good(scenario), dealy=True))


def test_json_constants_nan_and_infinity_are_refused(scenario, tmp_path):
    text = json.dumps(_good(scenario)).replace('"A": [[0.5]]', '"A": [[NaN]]')
    (tmp_path / "controller.json").write_text(text, encoding="utf-8")
    with pytest.raises(ParameterError, match="NaN is not a JSON number"):
        DiscreteController.from_json(tmp_path)


def test_a_good_file_round_trips_and_an_unstable_one_is_warned_about(scenario, tmp_path):
    (tmp_path / "controller.json").write_text(json.dumps(_good(scenario)), encoding="utf-8")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        DiscreteController.from_json(tmp_path)
    (tmp_path / "controller.json").write_text(json.dumps(_good(scenario, a=2.0)), encoding="utf-8")
    with pytest.warns(RuntimeWarning, match=r"unstable on its own \(the spectral radius of A is 2"):
        DiscreteController.from_json(tmp_path)


@pytest.mark.parametrize("a", [2.0, 1e308])
def test_a_controller_that_blows_up_is_an_error_naming_it_and_the_sample(scenario, a):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        controller = DiscreteController.from_dict(_good(scenario, a=a))
    with pytest.raises(SimulationError) as error:
        Simulator(scenario).run(controller=controller)
    message = str(error.value)
    assert message.startswith("controller (method 'custom'): a non-finite state or command at sample "), message
    sample = int(message.split("at sample ")[1].split()[0])
    # x_k grows as a^k from the first reading: it overflows once a^k exceeds ~1e308 (a few samples for 1e308)
    expected = 1 + int(np.ceil(308 / np.log10(a))) if a > 10 else None
    if expected is not None:
        assert sample <= expected + 2
    assert 0 < sample < 1000 * scenario.simulation.duration
