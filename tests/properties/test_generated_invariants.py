"""Invariants that hold exactly, on generated valid scenarios (hypothesis; HYPOTHESIS_PROFILE=thorough for more).

- the mirror image of a scenario (y -> -y) gives the mirror image of its response: y, rx, rz flip sign,
  x, z, ry stay;
- every mass, stiffness and damping times one factor (the box inertia follows) leaves the response as it is;
- carriages that never move leave the table at rest;
- the metrics do not depend on the output sample rate (5 Hz, 50 Hz, 1 kHz: peaks and settling instants
  from the integrator's dense output).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scenario_strategies import mirrored, scaled, scenario_dicts

from conftest import make
from isolator import ScenarioError, Simulator, stability

#: simulations cost more than checks: half the profile's examples
RUNS = settings(max_examples=max(4, settings.default.max_examples // 2))
MIRROR = np.array([1.0, -1.0, 1.0, -1.0, 1.0, -1.0])[:, None]


def _standing(data):
    """The scenario, or ``assume`` it away when the reader refuses it or the table would tip."""
    try:
        scenario = make(data)
    except ScenarioError:
        assume(False)
    assume(stability(scenario).stable)
    return scenario


def _run(data):
    return Simulator(_standing(data)).run()


def _close(a, b, scale):
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-9 * scale + 1e-15)


@RUNS
@given(scenario_dicts(min_carriages=1))
def test_a_mirrored_scenario_responds_mirrored(data):
    r = _run(data)
    m = _run(mirrored(data))
    scale = np.abs(r.signals).max()
    _close(m.signals, MIRROR * r.signals, scale)
    for name in ("x", "y", "z", "rx", "ry", "rz"):
        assert m.peak[name] == pytest.approx(r.peak[name], rel=1e-7, abs=1e-12 * scale)


@RUNS
@given(scenario_dicts(min_carriages=1), st.sampled_from([0.25, 0.5, 2.0, 8.0]))
def test_scaling_every_mass_stiffness_and_damping_changes_nothing(data, factor):
    r = _run(data)
    s = _run(scaled(data, factor))
    _close(s.signals, r.signals, np.abs(r.signals).max())
    for name, t in r.settling_time.items():
        if t is None:
            assert s.settling_time[name] is None
        else:
            assert s.settling_time[name] == pytest.approx(t, abs=1e-9)


@RUNS
@given(scenario_dicts(moving=False, min_carriages=1))
def test_carriages_that_never_move_leave_the_table_at_rest(data):
    r = _run(data)
    assert np.abs(r.signals).max() < 1e-10  # the static equilibrium's own residual (~1e-12 m), nothing more


@RUNS
@given(scenario_dicts(min_carriages=1, duration=6.0))
def test_metrics_do_not_depend_on_the_output_sample_rate(data):
    fine = _run({**data, "simulation": {**data["simulation"], "sample_rate": 1000.0}})
    for rate in (5.0, 50.0):
        coarse = _run({**data, "simulation": {**data["simulation"], "sample_rate": rate}})
        for name in fine.peak:
            assert coarse.peak[name] == pytest.approx(fine.peak[name], rel=1e-6)
            t_fine, t_coarse = fine.settling_time[name], coarse.settling_time[name]
            assert (t_fine is None) == (t_coarse is None)
            if t_fine is not None:
                assert t_coarse == pytest.approx(t_fine, abs=1e-4)
