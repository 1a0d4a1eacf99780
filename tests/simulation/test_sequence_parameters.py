"""``run_sequence(parameters=...)``: a design's parameter vector runs as the scenario edited to it would."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from isolator import ParameterError, Simulator, load_scenario, scenario_from_dict
from isolator.scenario.reader import resolve_scenario_path
from isolator.simulation.sequence import run_sequence

SCENARIO = "paper-table-3-2-sequence"


def test_a_parameter_vector_runs_as_the_edited_scenario():
    sc = load_scenario(SCENARIO)
    sim = Simulator(sc)
    p = sim.parameters.copy()
    for i, name in enumerate(sim.layout.names):
        if ".damping." in name:
            p[i] *= 2.0
    with open(resolve_scenario_path(SCENARIO), "rb") as handle:
        data = tomllib.load(handle)
    for iso in data["isolators"]:
        iso["damping"] = [2.0 * v for v in iso["damping"]]
    data["sequence"]["steps"] = data["sequence"]["steps"][:3]
    edited = run_sequence(scenario_from_dict(data))
    short = scenario_from_dict({**data, "isolators": load_toml_isolators()})
    designed = run_sequence(short, parameters=p)
    assert designed.total_time == pytest.approx(edited.total_time, abs=1e-9)
    assert run_sequence(short).total_time > designed.total_time + 0.5  # more damping settles sooner


def load_toml_isolators():
    with open(resolve_scenario_path(SCENARIO), "rb") as handle:
        return tomllib.load(handle)["isolators"]


def test_a_bad_parameter_vector_is_named():
    sc = load_scenario(SCENARIO)
    with pytest.raises(ParameterError, match=r"^parameters: must be a vector of \d+ numbers"):
        run_sequence(sc, parameters=np.zeros(3))
