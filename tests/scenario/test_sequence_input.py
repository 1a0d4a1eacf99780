"""``[sequence]`` keys: read, defaults, per-step limits and delays, written back, the serpentine raster, and every
bad value one :class:`ScenarioError` naming its key."""

from __future__ import annotations

import copy
import dataclasses
import math
import tomllib
from typing import Any

import pytest

from conftest import base_dict
from isolator import load_scenario, scenario_from_dict
from isolator.errors import ParameterError, ScenarioError
from isolator.scenario.sequence import (
    Move,
    Step,
    StepSequence,
    parse_pattern,
    raster_steps,
    sequence_table,
    sequence_toml,
)
from isolator.scenario.validation import validate_scenario

PROBE = {"name": "probe", "position": [0.3, 0.0, 0.45]}
LIMITS = {"velocity": 0.2, "acceleration": 0.5, "jerk": 5.0}


def sequence_dict(sequence: dict[str, Any] | None = None, **extra: Any) -> dict[str, Any]:
    """:func:`base_dict` with two stages (x, and y riding on it), full limits, no profiles, a probe window and
    a two-step ``[sequence]`` (or ``sequence``)."""
    data = base_dict(points=[PROBE], windows=[{"point": "probe", "translation": 5e-8}], **extra)
    x = data["carriages"][0]
    del x["profile"]
    x["limits"] = dict(LIMITS)
    y = {"name": "y-stage", "mass": 40.0, "parent": "x-stage", "axis": [0.0, 1.0, 0.0], "origin": [0.0, 0.0, 0.15],
         "limits": {"velocity": 0.083, "acceleration": 0.5, "jerk": 5.0}}
    data["carriages"].append(y)
    data["sequence"] = sequence if sequence is not None else {
        "measure": 0.1, "steps": [{"x-stage": 0.1}, {"x-stage": 0.2, "y-stage": 0.05}]}
    return data


def _error(data: dict[str, Any]) -> str:
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(copy.deepcopy(data))
    return str(info.value)


def test_sequence_read_with_defaults():
    sc = scenario_from_dict(sequence_dict())
    seq = sc.sequence
    assert seq is not None
    assert seq.measure == 0.1
    assert seq.start == 0.0
    assert seq.initial == ()
    assert seq.steps == (Step((("x-stage", Move(0.1)),)), Step((("x-stage", Move(0.2)), ("y-stage", Move(0.05)))))
    assert seq.steps[1].targets == {"x-stage": 0.2, "y-stage": 0.05}
    # the carriages are held at the initial positions (q = 0 by default): a plain run keeps them parked
    assert sc.stop_time == 0.0
    assert list(sc.initial_positions()) == [0.0, 0.0]
    assert seq.configurations(["x-stage", "y-stage"]).tolist() == [[0.0, 0.0], [0.1, 0.0], [0.2, 0.05]]


def test_inline_moves_and_initial():
    data = sequence_dict({"measure": 0.0, "start": 0.5, "initial": {"x-stage": -0.3},
                          "steps": [{"x-stage": {"target": 0.1, "velocity": 0.15, "acceleration": 0.4, "jerk": 4.0,
                                                 "delay": 0.05}, "y-stage": 0.02}]})
    sc = scenario_from_dict(data)
    seq = sc.sequence
    assert seq is not None
    assert seq.initial == (("x-stage", -0.3),)
    assert sc.initial_positions().tolist() == [-0.3, 0.0]
    move = seq.steps[0].move("x-stage")
    assert move == Move(0.1, 0.15, 0.4, 4.0, 0.05)
    assert move is not None
    assert move.limits(0.2, 0.5, 5.0) == (0.15, 0.4, 4.0)
    assert Move(0.1, velocity=0.1).limits(0.2, 0.5, 5.0) == (0.1, 0.5, 5.0)
    assert seq.steps[0].move("y-stage") == Move(0.02)
    assert seq.steps[0].move("z-stage") is None


def test_written_sequence_reads_back_the_same():
    data = sequence_dict({"measure": 0.125, "start": 0.5, "initial": {"x-stage": -0.3, "y-stage": 0.01},
                          "steps": [{"x-stage": {"target": 0.1 / 3, "velocity": 0.15, "delay": 0.05}},
                                    {"y-stage": {"target": 0.02, "jerk": 2.5}, "x-stage": 0.2}]})
    seq = scenario_from_dict(data).sequence
    assert seq is not None
    table = sequence_table(seq)
    assert table["steps"][1] == {"y-stage": {"target": 0.02, "jerk": 2.5}, "x-stage": 0.2}
    text = sequence_toml(seq)
    assert text.startswith("[sequence]\nmeasure = 0.125\n")
    again = dict(data, sequence=tomllib.loads(text)["sequence"])
    assert scenario_from_dict(again).sequence == seq
    assert scenario_from_dict(dict(data, sequence=table)).sequence == seq


def test_bundled_sequence_scenario():
    sc = load_scenario("paper-table-3-2-sequence")
    seq = sc.sequence
    assert seq is not None
    assert len(seq.steps) == 20
    assert seq.measure == 0.1
    grid = seq.configurations([c.name for c in sc.carriages])[1:]
    assert sorted({round(x, 9) for x in grid[:, 0]}) == [-0.2, -0.1, 0.0, 0.1, 0.2]
    assert sorted({round(y, 9) for y in grid[:, 1]}) == [-0.15, -0.05, 0.05, 0.15]
    # the steps written out by hand are the raster --pattern builds
    assert _targets(seq.steps) == _targets(raster_steps(["x-stage=-0.2:0.2:5", "y-stage=-0.15:0.15:4"]))


@pytest.mark.parametrize(("change", "key", "words"), [
    (lambda d: d["sequence"]["steps"].append({"z-stage": 0.1}), "sequence.steps[2].z-stage", "unknown carriage"),
    (lambda d: d["sequence"].update(initial={"z-stage": 0.1}), "sequence.initial.z-stage", "unknown carriage"),
    (lambda d: d["sequence"]["steps"].append({"x-stage": 1.5}), "sequence.steps[2].x-stage", "half-length"),
    (lambda d: d["sequence"]["steps"].append({"y-stage": 0.6}), "sequence.steps[2].y-stage", "half-width"),
    (lambda d: d["sequence"].update(initial={"x-stage": -1.2}), "sequence.initial.x-stage", "half-length"),
    (lambda d: d["carriages"][0]["limits"].pop("jerk"), "carriages[0].limits.jerk", "missing"),
    (lambda d: d["carriages"][1].pop("limits"), "carriages[1].limits.velocity", "missing"),
    (lambda d: d["carriages"][0].update(profile={"type": "scurve", "start": 0.0, "stroke": 0.1, "velocity": 0.1,
                                                  "acceleration": 0.5, "jerk": 5.0}),
     "carriages[0].profile", "no profile"),
    (lambda d: d["sequence"].update(steps=[]), "sequence.steps", "empty"),
    (lambda d: d["sequence"].update(steps={"x-stage": 0.1}), "sequence.steps", "list"),
    (lambda d: d["sequence"]["steps"].append({}), "sequence.steps[2]", "names no carriage"),
    (lambda d: d["sequence"]["steps"].append(0.1), "sequence.steps[2]", "table"),
    (lambda d: d["sequence"].update(measure=-0.1), "sequence.measure", ">= 0"),
    (lambda d: d["sequence"].pop("measure"), "sequence.measure", "missing"),
    (lambda d: d["sequence"].update(start=-1.0), "sequence.start", ">= 0"),
    (lambda d: d["sequence"].update(measure=math.nan), "sequence.measure", "finite"),
    (lambda d: d["sequence"]["steps"].append({"x-stage": math.inf}), "sequence.steps[2].x-stage", "finite"),
    (lambda d: d["sequence"]["steps"].append({"x-stage": "0.1"}), "sequence.steps[2].x-stage", "number"),
    (lambda d: d["sequence"].update(initial={"x-stage": math.nan}), "sequence.initial.x-stage", "finite"),
    (lambda d: d["sequence"].update(initial=0.1), "sequence.initial", "table"),
    (lambda d: d["sequence"]["steps"].append({"x-stage": {"target": 0.1, "velocity": 0.3}}),
     "sequence.steps[2].x-stage.velocity", "above the carriage's limit carriages[0].limits.velocity = 0.2"),
    (lambda d: d["sequence"]["steps"].append({"x-stage": {"target": 0.1, "jerk": 6.0}}),
     "sequence.steps[2].x-stage.jerk", "above the carriage's limit"),
    (lambda d: d["sequence"]["steps"].append({"x-stage": {"target": 0.1, "acceleration": 0.0}}),
     "sequence.steps[2].x-stage.acceleration", "> 0"),
    (lambda d: d["sequence"]["steps"].append({"x-stage": {"target": 0.1, "delay": -0.1}}),
     "sequence.steps[2].x-stage.delay", ">= 0"),
    (lambda d: d["sequence"]["steps"].append({"x-stage": {"velocity": 0.1}}),
     "sequence.steps[2].x-stage.target", "missing"),
    (lambda d: d["sequence"]["steps"].append({"x-stage": {"targte": 0.1}}),
     "sequence.steps[2].x-stage.targte", "did you mean 'target'"),
    (lambda d: d["sequence"].update(mesure=0.1), "sequence.mesure", "did you mean"),
    (lambda d: d.update(sequnce=d.pop("sequence")), "sequnce", "did you mean 'sequence'"),
])
def test_bad_sequence_is_named(change, key, words):
    data = sequence_dict()
    change(data)
    message = _error(data)
    assert message.startswith(f"{key}:"), message
    assert words in message, message


def test_carriage_without_profile_needs_a_sequence():
    data = sequence_dict()
    del data["sequence"]
    assert _error(data) == "carriages[0].profile: missing"


def test_scenarios_built_from_dataclasses_are_checked_too():
    sc = scenario_from_dict(sequence_dict())
    seq = sc.sequence
    assert seq is not None
    bad = dataclasses.replace(seq, steps=(Step((("x-stage", Move(0.1, velocity=1.0)),)),))
    with pytest.raises(ScenarioError, match=r"sequence\.steps\[0\]\.x-stage\.velocity"):
        validate_scenario(dataclasses.replace(sc, sequence=bad))
    moving = dataclasses.replace(sc.carriages[0], profile=load_scenario("paper-table-3-2").carriages[0].profile)
    with pytest.raises(ScenarioError, match=r"carriages\[0\]\.profile: with \[sequence\]"):
        validate_scenario(dataclasses.replace(sc, carriages=(moving, sc.carriages[1])))


# -- raster patterns ---------------------------------------------------------------------------------------


def _targets(steps: tuple[Step, ...]) -> list[dict[str, float]]:
    return [{k: round(v, 9) for k, v in s.targets.items()} for s in steps]


def test_raster_is_serpentine():
    steps = raster_steps(["x-stage=0:0.3:4", "y-stage=0:0.2:3"])
    assert _targets(steps) == [
        {"x-stage": 0.0, "y-stage": 0.0}, {"x-stage": 0.1}, {"x-stage": 0.2}, {"x-stage": 0.3},
        {"y-stage": 0.1}, {"x-stage": 0.2}, {"x-stage": 0.1}, {"x-stage": 0.0},
        {"y-stage": 0.2}, {"x-stage": 0.1}, {"x-stage": 0.2}, {"x-stage": 0.3},
    ]
    assert _targets(raster_steps(["y-stage=0.1:-0.1:3"])) == [{"y-stage": 0.1}, {"y-stage": 0.0}, {"y-stage": -0.1}]
    assert _targets(raster_steps([("x-stage", [0.5]), ("y-stage", [0.0, 0.1])])) == [
        {"x-stage": 0.5, "y-stage": 0.0}, {"y-stage": 0.1}]


@pytest.mark.parametrize(("patterns", "words"), [
    (["x-stage=0:0.3"], "NAME=START:STOP:COUNT"),
    (["x-stage:0:0.3:4"], "NAME=START:STOP:COUNT"),
    (["=0:0.3:4"], "NAME=START:STOP:COUNT"),
    (["x-stage=0:a:4"], "NAME=START:STOP:COUNT"),
    (["x-stage=0:0.3:0"], "NAME=START:STOP:COUNT"),
    (["x-stage=0:0.3:2.5"], "NAME=START:STOP:COUNT"),
    (["x-stage=0:nan:2"], "NAME=START:STOP:COUNT"),
    (["x-stage=0:0.3:1"], "COUNT 1"),
    ([], "one or two"),
    (["a=0:1:2", "b=0:1:2", "c=0:1:2"], "one or two"),
    (["a=0:1:2", "a=0:1:3"], "twice"),
])
def test_bad_patterns(patterns, words):
    with pytest.raises(ParameterError, match="--pattern") as info:
        raster_steps(patterns)
    assert words in str(info.value)


def test_parse_pattern_is_inclusive():
    name, values = parse_pattern(" x-stage =0:0.3:7")
    assert name == "x-stage"
    assert values.tolist() == pytest.approx([0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3])


@pytest.mark.parametrize(("sequence", "key"), [
    (StepSequence(math.nan, (Step((("x-stage", Move(0.1)),)),)), "sequence.measure"),
    (StepSequence(-0.1, (Step((("x-stage", Move(0.1)),)),)), "sequence.measure"),
    (StepSequence(0.1, (Step((("x-stage", Move(0.1)),)),), start=math.inf), "sequence.start"),
    (StepSequence(0.1, ()), "sequence.steps"),
    (StepSequence(0.1, (Step(()),)), "sequence.steps[0]"),
    (StepSequence(0.1, (Step((("x-stage", Move(math.nan)),)),)), "sequence.steps[0].x-stage"),
    (StepSequence(0.1, (Step((("x-stage", Move(0.1, velocity=0.0)),)),)), "sequence.steps[0].x-stage.velocity"),
    (StepSequence(0.1, (Step((("x-stage", Move(0.1, delay=-1.0)),)),)), "sequence.steps[0].x-stage.delay"),
    (StepSequence(0.1, (Step((("x-stage", Move(0.1)),)),), initial=(("x-stage", math.nan),)),
     "sequence.initial.x-stage"),
])
def test_sequences_built_from_dataclasses_are_checked(sequence, key):
    sc = scenario_from_dict(sequence_dict())
    with pytest.raises(ScenarioError) as info:
        validate_scenario(dataclasses.replace(sc, sequence=sequence))
    assert str(info.value).startswith(f"{key}:"), str(info.value)
