"""Profile design and control on pneumatic tables: the chamber states inside, the leveling left out."""

from __future__ import annotations

import numpy as np
import pytest
from pneumatic_cases import pneumatic_dict

from controllers import feedback as fb
from controllers import profiles as po
from controllers.feedforward import compare_feedforward, feedforward_allocation, feedforward_optimal
from controllers.profiles import ModelVariant
from controllers.profiles.transcription import variant_data
from isolator import Scenario, Simulator, linearise, load_scenario, scenario_from_dict, transmissibility
from isolator.scenario.definitions import SIGNALS
from isolator.scenario.pneumatic import PneumaticIsolator

NOMINAL = (ModelVariant(),)


@pytest.fixture(scope="module")
def pneumatic():
    return load_scenario("paper-table-3-2-pneumatic")


def test_the_objective_measures_about_the_leveling_table(pneumatic):
    """The optimiser's reference (final pose moved by the air each state holds) is the simulation's
    quasi-static pose, to first order in the air's change."""
    data = variant_data(pneumatic)
    run = Simulator(pneumatic).run()
    result = run.pneumatic
    assert result is not None
    after = np.flatnonzero(run.t >= pneumatic.stop_time)[::500]
    reference = np.asarray(data.reference(run.states[after].T))
    expected = result.quasi_static[:, after]
    drift = np.max(np.abs(expected - np.asarray(data.final)[:, None]), axis=1)
    assert np.max(drift) > 1e-4  # the table does level after the stop
    np.testing.assert_allclose(reference, expected, atol=0.02 * np.max(drift))


def test_profile_optimisation_cuts_the_settling_about_the_leveling_table(pneumatic):
    result = po.optimise_profiles(pneumatic, po.ProfileSettings(variants=NOMINAL))
    base, best = result.baseline.settling_time_max, result.optimised.settling_time_max
    assert base is not None
    assert best is not None
    assert best < 0.75 * base
    # judged by the dynamic settling, as the simulation reports it
    check = Simulator(po.with_moves(pneumatic, list(result.designs))).run()
    assert best == pytest.approx(check.dynamic_settling_time_max, abs=1e-9)


def test_model_variants_scale_the_air_springs(pneumatic):
    """Stiffness x2: both chambers half as large; damping x2 too: the orifice's conductance / 4."""
    variant = ModelVariant(stiffness=2.0, damping=2.0).apply(pneumatic)
    before, after = pneumatic.isolators[0], variant.isolators[0]
    assert isinstance(before, PneumaticIsolator)
    assert isinstance(after, PneumaticIsolator)
    assert after.volume == pytest.approx(before.volume / 2)
    assert after.damping_volume == pytest.approx(before.damping_volume / 2)
    assert before.orifice is not None
    assert after.orifice is not None
    g_ratio = (after.orifice.diameter / before.orifice.diameter) ** 4
    assert g_ratio == pytest.approx(1 / 4)
    assert after.horizontal_stiffness[0] == pytest.approx(2 * before.horizontal_stiffness[0])
    # the parameter-vector scaling for sweeps does the same
    sim = Simulator(pneumatic)
    np.testing.assert_allclose(sim.scaled_parameters(2.0, 2.0), Simulator(variant).parameters, rtol=1e-12)


def _active_pneumatic() -> Scenario:
    data = pneumatic_dict(valves=True, stroke=0.8, duration=4.0)
    data["actuators"] = [
        {"name": f"{axis}-{iso['name']}", "position": iso["position"], "direction": d, "max_force": 500.0}
        for iso in data["isolators"] for axis, d in (("x", [1.0, 0, 0]), ("y", [0, 1.0, 0]), ("z", [0, 0, 1.0]))
    ]
    return scenario_from_dict(data)


def test_feedback_on_a_pneumatic_table():
    """Skyhook around air springs: stable (the groups' air, which no actuator moves, is left out of the
    check), the heave resonance damped, and the closed loop's static gain keeps the air."""
    s = _active_pneumatic()
    lin = linearise(s)
    sky = fb.skyhook(lin, damping=5e4, sample_rate=1000.0)
    loop = fb.closed_loop(lin, sky)
    assert fb.check_stability(lin, sky).stable
    assert transmissibility(loop).peak("z")[0] < 0.7 * transmissibility(lin).peak("z")[0]
    static = loop.dc_gain(["ground:z"], ["z"])
    assert static[0, 0] == pytest.approx(1.0, abs=1e-6)  # the table follows a slow floor with its air kept
    run = Simulator(s).run(feedback=fb.feedback_law(s, sky))
    assert np.all(np.isfinite(run.signals))


def test_feedforward_on_a_pneumatic_table_is_measured_about_each_runs_air():
    s = _active_pneumatic()
    comparison = compare_feedforward(s, feedforward_allocation(s))
    assert comparison.controlled_quasi_static is not None
    reduction = comparison.reduction_db()
    assert reduction["x"] < -20.0  # the carriage's reaction along x is cancelled
    assert reduction["ry"] < -6.0
    # the optimal feedforward carries the chamber pressures in its QP: it cancels what the air does as the
    # table follows its path (about -56, -12, -45 dB in x, z, ry here, valves leveling during the move;
    # without the chamber states it does no better than the allocation: -30, -3, -10 dB)
    optimal = compare_feedforward(s, feedforward_optimal(s))
    assert optimal.feedforward.info["status"] in ("Solved", "AlmostSolved")
    better = optimal.reduction_db()
    passive = optimal.deviation_peak("passive")
    largest = {"r": max(passive[k] for k in ("rx", "ry", "rz")), "t": max(passive[k] for k in "xyz")}
    moving = [k for k in SIGNALS if passive[k] > 1e-3 * largest["r" if k.startswith("r") else "t"]]
    assert set(moving) == {"x", "z", "ry"}
    for k in moving:
        assert better[k] <= reduction[k], (k, better[k], reduction[k])
    assert better["x"] < -45.0
    assert better["ry"] < -38.0
    assert better["z"] < -8.0
