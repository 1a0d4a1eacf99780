"""A step's input shaper (``shaper = { kind, frequency, damping }``): read, refused when wrong, written back,
and simulated as the same shaped move a ``move=`` design gives; a sequence whose ``initial`` differs from what
its carriages hold starts from the sequence's."""

from __future__ import annotations

from dataclasses import replace

import pytest

from controllers.profiles.sequence_baselines import shaped_moves
from isolator import ScenarioError, load_scenario, scenario_from_dict
from isolator.scenario.sequence import Move, Step, sequence_table
from isolator.scenario.shapers import shaper
from isolator.simulation.sequence import run_sequence
from isolator.simulation.sequence_moves import step_profiles

SCENARIO = "paper-table-3-2-sequence"


def _with_steps(steps: list[dict]) -> dict:
    import tomllib

    from isolator.scenario.reader import resolve_scenario_path

    with open(resolve_scenario_path(SCENARIO), "rb") as handle:
        data = tomllib.load(handle)
    data["sequence"]["steps"] = steps
    return data


def test_a_step_shaper_is_read_and_written_back():
    data = _with_steps([{"x-stage": {"target": -0.5, "shaper": {"kind": "zvd", "frequency": 3.4, "damping": 0.1}}}])
    move = scenario_from_dict(data).sequence.steps[0].move("x-stage")
    assert move.shapers == (shaper("zvd", 3.4, 0.1),)
    table = sequence_table(scenario_from_dict(data).sequence)
    assert table["steps"][0]["x-stage"]["shaper"] == {"kind": "zvd", "frequency": 3.4, "damping": 0.1}


@pytest.mark.parametrize(("shaper_table", "match"), [
    ({"kind": "zvdd", "frequency": 3.4}, r"sequence\.steps\[0\]\.x-stage\.shaper\.kind: must be one of zv, zvd, ei"),
    ({"kind": "zv", "frequency": -1.0}, r"shaper\.frequency"),
    ({"kind": "zv", "frequency": 3.0, "damping": 1.0}, r"shaper\.damping: must be below 1"),
    ({"kind": "zv", "frequency": 3.0, "dampin": 0.1}, r"shaper\.dampin: unknown key; did you mean 'damping'"),
    ("zvd", r"shaper: must be a table"),
])
def test_bad_step_shapers_are_named(shaper_table, match):
    data = _with_steps([{"x-stage": {"target": -0.5, "shaper": shaper_table}}])
    with pytest.raises(ScenarioError, match=match):
        scenario_from_dict(data)


def test_a_shaped_step_is_the_shaped_design():
    """The file's shaper and ``run_sequence(move=shaped_moves(...))`` give the same profiles and run."""
    from controllers.profiles.sequence_baselines import dominant_mode

    sc = load_scenario(SCENARIO)
    sc = replace(sc, sequence=replace(sc.sequence, steps=sc.sequence.steps[:3]))
    design = shaped_moves(sc, "zv")
    q = sc.sequence.initial_positions([c.name for c in sc.carriages])
    designed, _, _ = step_profiles(sc, 0, q, design)
    assert designed[0].kind == "zv-shaped"
    by_design = run_sequence(sc, move=design)
    names = tuple(c.name for c in sc.carriages)
    configs = sc.sequence.configurations(names)
    written = []
    for k, step in enumerate(sc.sequence.steps):
        moves = []
        for name, mv in step.moves:
            mode = dominant_mode(sc, names.index(name), tuple(configs[k + 1]))
            moves.append((name, Move(mv.target, shapers=(shaper("zv", mode.frequency, mode.damping),))))
        written.append(Step(tuple(moves)))
    by_file = run_sequence(replace(sc, sequence=replace(sc.sequence, steps=tuple(written))))
    for a, b in zip(by_design.steps, by_file.steps, strict=True):
        assert a.stop == pytest.approx(b.stop, abs=1e-12)
        assert a.settled == pytest.approx(b.settled, abs=1e-9)


def test_a_sequence_starts_where_its_initial_says():
    """Built from the dataclasses with another ``initial`` than the carriages hold, the run starts at rest at
    the sequence's initial positions: a step that moves nowhere settles at once."""
    sc = load_scenario(SCENARIO)
    names = [c.name for c in sc.carriages]
    initial = (("x-stage", 0.1), ("y-stage", 0.05))
    seq = replace(sc.sequence, initial=initial, start=0.0,
                  steps=(Step((("x-stage", Move(0.1)),)),))
    result = run_sequence(replace(sc, sequence=seq))
    assert result.steps[0].stop == result.steps[0].start
    assert result.steps[0].settle == 0.0
    assert names == ["x-stage", "y-stage"]


def test_a_list_of_shapers_is_convolved_and_written_back():
    """``shaper = [ {...}, {...} ]``: the move convolved with both (its impulses every pair's product at every
    pair's sum of times), read, simulated and written back as a list."""
    tables = [{"kind": "zv", "frequency": 3.37, "damping": 0.106}, {"kind": "zv", "frequency": 6.2, "damping": 0.196}]
    data = _with_steps([{"x-stage": {"target": -0.5, "shaper": tables}}])
    sc = scenario_from_dict(data)
    move = sc.sequence.steps[0].move("x-stage")
    assert move.shapers == tuple(shaper(t["kind"], t["frequency"], t["damping"]) for t in tables)
    assert sequence_table(sc.sequence)["steps"][0]["x-stage"]["shaper"] == tables
    q = sc.sequence.initial_positions([c.name for c in sc.carriages])
    profiles, _, stop = step_profiles(sc, 0, q, None)
    one, two = move.shapers
    only_first = replace(sc, sequence=replace(sc.sequence, steps=(Step((("x-stage", Move(-0.5, shapers=(one,))),)),)))
    _, _, stop_one = step_profiles(only_first, 0, q, None)
    assert stop == pytest.approx(stop_one + two.duration, abs=1e-12)  # each shaper lengthens the move by its own
    assert profiles[0].kind == "zv+zv-shaped"
    result = run_sequence(sc)
    assert result.steps[0].settled is not None


def test_an_empty_shaper_list_is_refused():
    data = _with_steps([{"x-stage": {"target": -0.5, "shaper": []}}])
    with pytest.raises(ScenarioError, match=r"shaper: an empty list"):
        scenario_from_dict(data)


def test_a_single_shaper_given_for_the_list_is_wrapped_and_a_wrong_one_named():
    one = shaper("zv", 3.4, 0.1)
    assert Move(0.1, shapers=one).shapers == (one,)  # type: ignore[arg-type]
    with pytest.raises(ScenarioError, match=r"shapers: must be Shaper objects"):
        Move(0.1, shapers=("zv",))  # type: ignore[arg-type]
