"""Profile design and control on pneumatic tables: the chamber states inside, the leveling left out."""

from __future__ import annotations

import numpy as np
import pytest

from controllers import profiles as po
from controllers.profiles import ModelVariant
from controllers.profiles.transcription import variant_data
from isolator import Simulator, load_scenario
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
    assert best < 0.5 * base
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
