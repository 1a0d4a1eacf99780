"""Generated invalid inputs, one field broken at a time (hypothesis).

Through every door the same rule (:mod:`isolator.scenario.rules`) and an error that starts with the key:
the file reader and the command line (exit status 2, one line on stderr, no traceback), scenarios built
from the dataclasses directly (the same message as the reader's), ``Simulator.run(changes=..., p=...)``
and ``linearise(parameters=...)`` (a ParameterError naming the entry).
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import math

import numpy as np
import pytest
import tomli_w
from hypothesis import given
from hypothesis import strategies as st
from scenario_strategies import NAN, broken_scenarios, scenario_dicts

from conftest import base_dict, make
from isolator import ParameterError, ScenarioError, Simulator, linearise
from isolator.cli.app import main
from isolator.scenario.rules import RULES, rule_for


def _reader_error(data) -> str:
    with pytest.raises(ScenarioError) as caught:
        make(data)
    return str(caught.value)


@given(broken_scenarios())
def test_the_reader_names_the_broken_key(case):
    data, path, _, _ = case
    assert _reader_error(data).startswith(path)


@given(broken_scenarios())
def test_the_command_line_exits_2_with_one_line_naming_the_key(tmp_path_factory, case):
    data, path, _, _ = case
    file = tmp_path_factory.mktemp("broken") / "broken.toml"
    file.write_text(tomli_w.dumps(data))
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(["simulate", str(file), "--json"])
    assert status == 2
    assert "Traceback" not in err.getvalue()
    lines = err.getvalue().strip().splitlines()
    assert len(lines) == 1, err.getvalue()
    assert path in lines[0]
    assert out.getvalue() == ""


# -- scenarios built from the dataclasses: the reader's message, word for word ----------------------
def _break_dataclass(scenario, path: str, value):
    """The scenario with the field at a key path replaced through the dataclasses (None: not a field)."""
    parts = path.replace("]", "").replace("[", ".").split(".")
    section, *rest = parts
    if section in ("isolators", "carriages"):
        index, field, *component = rest
        items = list(getattr(scenario, section))
        item = items[int(index)]
        if field == "profile" or not hasattr(item, field):
            return None
        if component:
            vector = list(getattr(item, field))
            vector[int(component[0])] = value
            value = tuple(vector)
        elif field == "axis":
            value = tuple(value)
        items[int(index)] = dataclasses.replace(item, **{field: value})
        return dataclasses.replace(scenario, **{section: tuple(items)})
    if section == "table":
        field, *component = rest
        if component:
            vector = list(getattr(scenario.table, field))
            vector[int(component[0])] = value
            value = tuple(vector)
        return dataclasses.replace(scenario, table=dataclasses.replace(scenario.table, **{field: value}))
    if section == "simulation":
        return dataclasses.replace(scenario, simulation=dataclasses.replace(scenario.simulation, **{rest[0]: value}))
    if section == "gravity":
        return dataclasses.replace(scenario, gravity=value)
    return None


@given(broken_scenarios())
def test_a_scenario_built_from_dataclasses_is_refused_as_the_file_is(case):
    data, path, value, original = case
    expected = _reader_error(data)
    refused, broken = "", None
    try:
        broken = _break_dataclass(make(original), path, value)
    except ParameterError as exc:  # a bad number: the dataclass refuses it when built, in the reader's words
        refused = str(exc)
    if refused:
        assert refused.split(": ", 1)[1] == expected.split(": ", 1)[1]
        return
    if broken is None:
        return  # a profile's keys: its builders refuse them (tests/scenario), there is no dataclass field
    with pytest.raises(ScenarioError) as caught:
        Simulator(broken)
    assert str(caught.value) == expected
    with pytest.raises(ScenarioError) as again:
        linearise(broken)
    assert str(again.value) == expected


# -- parameter vectors -------------------------------------------------------------------------------
def _bad_values(name: str) -> list[float]:
    rule = rule_for(name)
    assert rule is not None, f"{name}: a parameter without a rule in isolator.scenario.rules"
    out = [NAN, math.inf, -math.inf] if rule.low is None else [NAN, math.inf]
    if rule.low is not None:
        out += [rule.low if rule.low_open else rule.low - 1.0, rule.low - 1e6]
    if rule.high is not None:
        out.append(rule.high + 1.0)
    return out


@st.composite
def broken_parameters(draw):
    data = draw(scenario_dicts(min_carriages=1))
    sim = Simulator(make(data))
    names = sim.layout.names
    i = draw(st.integers(0, len(names) - 1))
    rule = rule_for(names[i])
    if rule is not None and rule.unit:
        grow = draw(st.sampled_from([0.5, 2.0, NAN]))  # the component's magnitude grows: never a unit vector
        value = sim.parameters[i] + (grow if sim.parameters[i] >= 0 else -grow)
    elif rule is not None and rule.triangle:
        value = draw(st.sampled_from([NAN, 0.0, -1.0, 1e3 * float(np.max(sim.parameters[2:5]))]))
    else:
        value = draw(st.sampled_from(_bad_values(names[i])))
    return sim, i, value


@given(broken_parameters())
def test_changes_are_checked_by_the_same_rules(case):
    sim, i, value = case
    name = sim.layout.names[i]
    with pytest.raises(ParameterError) as caught:
        sim.run(changes={name: value})
    assert str(caught.value).startswith(f"changes[{name!r}]: ")


@given(broken_parameters())
def test_a_whole_parameter_vector_is_checked_entry_by_entry(case):
    sim, i, value = case
    p = sim.parameters.copy()
    p[i] = value
    name = sim.layout.names[i]
    rule = rule_for(name)
    vector = rule is not None and (rule.unit or rule.triangle) and rule.problem(value) is None
    head, _, component = name.rpartition(".")
    for argument, call in (("p", lambda: sim.run(p=p)),
                           ("parameters", lambda: linearise(sim.scenario, parameters=p))):
        with pytest.raises(ParameterError) as caught:
            call()
        if vector:  # a direction or the inertia as a whole: the three entries named
            first = i - "xyz".index(component)
            assert str(caught.value).startswith(f"{argument}[{first}:{first + 3}] ({head}): ")
        else:
            assert str(caught.value).startswith(f"{argument}[{i}] ({name}): ")


def test_the_issues_example_and_a_typo():
    sim = Simulator(make(base_dict()))
    with pytest.raises(ParameterError, match=r"^changes\['isolators\[0\]\.damping\.z'\]: must be >= 0, got -5$"):
        sim.run(changes={"isolators[0].damping.z": -5})
    with pytest.raises(ParameterError, match=r"did you mean 'isolators\[0\]\.damping\.z'"):
        sim.run(changes={"isolators[0].dampng.z": 1.0})
    with pytest.raises(ParameterError, match=r"^p: must be a vector of \d+ numbers"):
        sim.run(p=sim.parameters[:-1])


def test_every_parameter_has_a_rule():
    """No parameter name falls outside the rules (spring-damper and pneumatic layouts)."""
    from isolator import ParameterLayout, load_scenario

    for name in ("paper-table-3-2", "paper-table-3-2-active", "paper-table-3-2-pneumatic"):
        for parameter in ParameterLayout.of(load_scenario(name)).names:
            assert rule_for(parameter) is not None, parameter
    assert all(not (r.unit and r.triangle) for r in RULES.values())
