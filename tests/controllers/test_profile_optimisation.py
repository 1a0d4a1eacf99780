"""Profile optimisation: its model against the simulation, the paper targets, transcriptions, failures."""

from __future__ import annotations

import json

import casadi as ca
import numpy as np
import pytest

from controllers import profiles as po
from controllers.profiles import ModelVariant, evaluate_move, move_designs, shaped_scenario, with_moves
from controllers.profiles.objective import peak_floor
from controllers.profiles.problem import Problem
from controllers.profiles.transcription import variant_data
from isolator import OptimisationError, ParameterError, Simulator, load_scenario
from isolator.cli.app import main

NOMINAL = (ModelVariant(),)


@pytest.fixture(scope="module")
def paper():
    return load_scenario("paper-table-3-2")


@pytest.fixture(scope="module")
def settled(paper):
    return po.optimise_profiles(paper, po.ProfileSettings(variants=NOMINAL))


def test_the_optimisers_phase_integration_agrees_with_the_simulation(paper):
    """The shooting model (phases that stretch with the parameters) against the simulator's grid."""
    base = evaluate_move(paper, "paper", 0.5)
    designs = move_designs(paper, "scurve")
    designs = (designs[0].with_values([0.5, 0.19, 0.45, 0.3, 8.0, 1.0]), designs[1].with_values(
        [0.62, 0.08, 0.4, 0.2, 5.0, 0.6]))
    data = [variant_data(paper)]
    problem = Problem(paper, designs, po.ProfileSettings(variants=NOMINAL, step_angle=0.1), data,
                      peak_floor(base.peak), 0.5, 8.0)
    x_stop, _, _, _ = problem.run.trajectory(data[0], None)
    sense = ca.Function("s", [problem.theta], [problem.run.sense(x_stop, data[0].start_state)])
    at_stop = np.asarray(sense(problem.x0[: problem.n_theta])).ravel()[:6]
    scenario = with_moves(paper, designs)
    run = Simulator(scenario).run()
    k = np.argmin(np.abs(run.t - scenario.stop_time))
    assert abs(run.t[k] - scenario.stop_time) < 1e-3
    scale = np.max(np.abs(run.signals), axis=1)
    assert np.allclose(at_stop, run.signals[:, k], atol=2e-3 * scale.max(), rtol=0)
    assert np.all(np.abs(at_stop - run.signals[:, k]) <= 0.02 * scale)


def test_settling_target_on_the_paper_scenario(settled):
    """At most 10 % of the paper profile's settling time, with a move at most 5 % longer (true simulation)."""
    base, best = settled.baseline, settled.optimised
    assert base.settling_time_max == pytest.approx(2.31, abs=0.02)
    assert best.settling_time_max <= 0.1 * base.settling_time_max
    assert best.move_time <= 1.05 * base.move_time + 1e-6
    assert all(d.fits(1e-6) for d in settled.designs)
    assert settled.status in ("Solve_Succeeded", "Solved_To_Acceptable_Level")


def test_multiple_shooting_finds_the_same_optimum(paper, settled):
    multiple = po.optimise_profiles(paper, po.ProfileSettings(variants=NOMINAL, transcription="multiple"))
    assert multiple.objective_value == pytest.approx(settled.objective_value, rel=0.02)
    assert multiple.optimised.settling_time_max <= 0.1 * multiple.baseline.settling_time_max


def test_a_warm_start_from_the_answer_keeps_the_gain(paper, settled):
    again = po.optimise_profiles(paper, po.ProfileSettings(variants=NOMINAL), warm_start=settled)
    assert again.objective_value <= 1.2 * settled.objective_value
    assert again.optimised.settling_time_max <= 0.1 * again.baseline.settling_time_max
    assert again.optimised.move_time <= 1.05 * again.baseline.move_time + 1e-6


def test_cycle_objective_beats_zv_shaping(paper):
    result = po.optimise_profiles(paper, po.ProfileSettings(variants=NOMINAL, objective="cycle"))
    zv = evaluate_move(shaped_scenario(paper, "zv", list(result.baseline.peak.values())), "zv", 0.5)
    assert result.optimised.cycle_time < zv.cycle_time
    assert result.optimised.cycle_time < result.baseline.cycle_time


def test_a_solver_failure_says_so_and_keeps_the_best_feasible_point(paper):
    with pytest.raises(OptimisationError, match="IPOPT Maximum_Iterations_Exceeded after 1 iterations") as info:
        po.optimise_profiles(paper, po.ProfileSettings(variants=NOMINAL, max_iterations=1, screen=False))
    result = info.value.result
    assert result is not None
    assert "best feasible point kept" in str(info.value)
    assert result.optimised.move_time <= 1.05 * result.baseline.move_time + 1e-6


def test_bad_settings_are_named(paper):
    with pytest.raises(ParameterError, match="objective: must be one of settling, cycle"):
        po.optimise_profiles(paper, po.ProfileSettings(objective="fast"))
    with pytest.raises(ParameterError, match="max_move_time_increase: must be a finite fraction >= 0"):
        po.optimise_profiles(paper, po.ProfileSettings(max_move_time_increase=float("nan")))


def test_command_writes_json_and_a_scenario_that_simulates(tmp_path, capsys):
    out = tmp_path / "opt.toml"
    assert main(["optimise-profile", "--json", "--out", str(out)]) == 0
    data = json.loads(capsys.readouterr().out)
    for key in ("baseline", "optimised"):
        assert set(data[key]) >= {"move_time", "settling_time_max", "cycle_time"}
    assert len(data["robustness"]["optimised"]) == 7
    assert max(data["robustness"]["optimised"]) < 0.1 * min(data["robustness"]["baseline"])
    run = Simulator(load_scenario(out)).run()
    assert run.settling_time_max == pytest.approx(data["optimised"]["settling_time_max"], abs=1e-3)
    assert load_scenario(out).carriages[0].profile.kind == "scurve"


def test_profile_study_writes_figures_and_report(tmp_path, capsys):
    assert main(["study", "profiles", "--quick", "--out", str(tmp_path)]) == 0
    for name in ("profiles.png", "response.png", "times.png", "robustness.png"):
        assert (tmp_path / name).stat().st_size > 20_000
    report = (tmp_path / "report.md").read_text()
    for method in ("| ZV |", "| time-optimal |", "optimised (cycle)"):
        assert method in report
    assert "target at most 10 %" in report


def test_trapezoids_can_be_designed_too_and_gain_less(paper, settled):
    """A rectangular braking pulse cannot cancel modes damped at 10-20 %; an S-curve's two ramps can."""
    trap = po.optimise_profiles(paper, po.ProfileSettings(variants=NOMINAL, shape="trapezoid"))
    assert {d.shape for d in trap.designs} == {"trapezoid"}
    assert trap.optimised.settling_time_max < trap.baseline.settling_time_max
    assert trap.optimised.settling_time_max > settled.optimised.settling_time_max
    assert trap.scenario.carriages[0].profile.settings["type"] == "trapezoid"
