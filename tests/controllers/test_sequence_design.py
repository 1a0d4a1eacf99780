"""Sequences designed for throughput: never slower step by step, within the carriages' limits, and the
written scenario re-simulated as written gives the reported total time."""

from __future__ import annotations

import json

import pytest

from controllers.profiles.sequence_design import optimise_sequence, write_sequence_scenario
from isolator import ParameterError, ScenarioError, load_scenario
from isolator.cli.app import main
from isolator.simulation.sequence import run_sequence

SCENARIO = "paper-table-3-2-sequence"


@pytest.fixture(scope="module")
def optimised():
    return optimise_sequence(load_scenario(SCENARIO), samples=8, rounds=1)


def test_the_optimised_sequence_is_faster_and_never_slower_step_by_step(optimised):
    before, after = optimised.before, optimised.after
    assert after.total_time < before.total_time
    assert after.throughput > before.throughput
    for b, a in zip(before.steps, after.steps, strict=True):
        assert a.end - a.start <= b.end - b.start + 2e-3
    for design in optimised.designs.values():
        assert design["after"] <= design["before"]


def test_designed_moves_stay_within_the_carriages_limits(optimised):
    limits = {c.name: c.limits for c in optimised.scenario.carriages}
    for step in optimised.scenario.sequence.steps:
        for name, move in step.moves:
            lim = limits[name]
            assert move.velocity is None or 0 < move.velocity <= lim.velocity
            assert move.acceleration is None or 0 < move.acceleration <= lim.acceleration
            assert move.jerk is None or 0 < move.jerk <= lim.jerk
            assert move.delay >= 0


def test_the_written_scenario_reproduces_the_reported_total(optimised, tmp_path):
    path = write_sequence_scenario(SCENARIO, optimised.scenario, tmp_path / "optimised.toml")
    again = run_sequence(load_scenario(path))
    assert again.total_time == pytest.approx(optimised.after.total_time, abs=1e-9)
    for a, b in zip(again.steps, optimised.after.steps, strict=True):
        assert a.settled == pytest.approx(b.settled, abs=1e-9)


def test_a_scenario_without_a_sequence_is_refused():
    with pytest.raises(ScenarioError, match=r"^sequence: the scenario has no \[sequence\]"):
        optimise_sequence(load_scenario("paper-table-3-2"))
    with pytest.raises(ParameterError, match=r"^samples: must be a whole number >= 2"):
        optimise_sequence(load_scenario(SCENARIO), samples=1)


def test_optimise_profile_command_on_a_sequence(tmp_path, capsys):
    out = tmp_path / "opt.toml"
    assert main(["optimise-profile", SCENARIO, "--samples", "4", "--json", "--out", str(out)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["after"]["total_time"] <= data["before"]["total_time"]
    assert data["throughput_gain"] >= 0
    assert run_sequence(load_scenario(out)).total_time == pytest.approx(data["after"]["total_time"], abs=1e-9)


def test_single_move_options_are_refused_on_a_sequence(capsys):
    assert main(["optimise-profile", SCENARIO, "--shape", "trapezoid"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith("isolator: error: --shape: designs a single move")


def test_too_few_samples_are_named_on_the_command_line(capsys):
    assert main(["optimise-profile", SCENARIO, "--samples", "1"]) == 2
    assert capsys.readouterr().err.strip() == "isolator: error: --samples: must be a whole number >= 2, got 1"


@pytest.mark.parametrize("family", ["zv+zv", "zvd+zv", "zv+zv+zv"])
def test_the_design_vector_reaches_the_intended_limits_delays_and_shapers(family):
    """Two carriages, several shapers each: every entry of the search vector lands where _box says."""
    import numpy as np

    from controllers.profiles import sequence_design as sd
    from controllers.profiles.sequence_baselines import dominant_modes_at

    sc = load_scenario(SCENARIO)
    names = tuple(c.name for c in sc.carriages)
    step = sc.sequence.steps[0]  # moves both carriages
    parked = tuple(sc.sequence.configurations(names)[1])
    kinds = sd.FAMILIES[family]
    n, m = 2, len(kinds)
    modes = [dominant_modes_at(sc, i, parked)[:m] for i in range(n)]
    low, high, start = sd._box(m, n)
    assert low.size == 3 * n + (n - 1) + 2 * n * m
    x = low + (high - low) * np.linspace(0.1, 0.9, low.size)  # distinct values, inside the box
    moves = dict(sd._candidate(sc, step, list(names), x, kinds, modes).moves)
    for k, name in enumerate(names):
        lim = sc.carriages[k].limits
        mv = moves[name]
        assert mv.velocity == pytest.approx(lim.velocity * np.exp(x[3 * k]))
        assert mv.jerk == pytest.approx(lim.jerk * np.exp(x[3 * k + 2]))
        assert mv.delay == (0.0 if k == 0 else pytest.approx(x[3 * n]))
        for j, train in enumerate(mv.shapers):
            assert train.kind == kinds[j]
            assert train.frequency == pytest.approx(modes[k][j].frequency * np.exp(x[4 * n - 1 + k * m + j]))
            assert train.damping == pytest.approx(x[4 * n - 1 + n * m + k * m + j])
    at_start = dict(sd._candidate(sc, step, list(names), start, kinds, modes).moves)
    for k, name in enumerate(names):
        assert [t.damping for t in at_start[name].shapers] == pytest.approx([md.damping for md in modes[k]])
