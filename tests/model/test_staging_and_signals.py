"""The model's vectorised and staged forms against their direct ones: the staged right-hand side,
batched equilibria, rotation vectors against one reference per row, the series rotation vector.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import asymmetric_3d_dict
from isolator import (
    Simulator,
    UnstableTableError,
    load_scenario,
    scenario_from_dict,
)
from isolator.model.equilibrium import static_equilibria, static_equilibrium
from isolator.model.signals import relative_rotation_vector
from isolator.model.variants import EXACT


def test_the_staged_right_hand_side_is_the_right_hand_side():
    rng = np.random.default_rng(3)
    data = asymmetric_3d_dict()
    data["actuators"] = [{"name": "z1", "position": [0.5, 0.2, -0.1], "direction": [0, 0, 1], "max_force": 100.0}]
    data["ground"] = {"z": {"type": "sine", "amplitude": 1e-6, "omega": 20.0}}
    for sc in (load_scenario("paper-table-3-2"), scenario_from_dict(data)):
        sim = Simulator(sc)
        model, p = sim.model, sim.parameters
        for _ in range(5):
            x = rng.normal(size=13) * 1e-2
            x[3:7] = [1.0, 0.02, -0.01, 0.03]
            u = rng.normal(size=model.layout.input_size) * 0.2
            direct = np.asarray(model.rhs(x, u, p)).ravel()
            staged = np.asarray(model.staged_rhs(x, model.staged_inputs(u, p), p)).ravel()
            assert np.allclose(staged, direct, rtol=1e-12, atol=1e-12 * np.abs(direct).max())


def test_batched_equilibria_match_one_at_a_time_and_name_the_failing_run():
    sc = load_scenario("paper-table-3-2")
    sim = Simulator(sc)
    params = np.array([sim.scaled_parameters(k, c) for k, c in ((0.5, 1.0), (1.0, 2.0), (2.0, 4.0))])
    many = static_equilibria(sim.model, params, sc.initial_positions())
    for p, eq in zip(params, many, strict=True):
        one = static_equilibrium(sim.model, p, sc.initial_positions())
        assert np.allclose(eq.pose, one.pose, rtol=0, atol=1e-14)
        assert np.allclose(np.sort_complex(eq.eigenvalues), np.sort_complex(one.eigenvalues), rtol=1e-9, atol=1e-9)
    soft = params.copy()
    soft[1] = sim.scaled_parameters(1e-4, 1.0)  # far too soft: the table tips
    with pytest.raises(UnstableTableError, match=r"^run 1: "):
        static_equilibria(sim.model, soft, sc.initial_positions())


def test_rotation_vectors_against_one_reference_per_row():
    rng = np.random.default_rng(1)
    q = rng.normal(size=(6, 4))
    refs = rng.normal(size=(6, 4))
    rows = relative_rotation_vector(q, refs)
    one_by_one = np.vstack([relative_rotation_vector(q[i : i + 1], refs[i]) for i in range(6)])
    assert np.allclose(rows, one_by_one, rtol=1e-14, atol=1e-14)


def test_the_series_rotation_vector_is_exact_up_to_the_divergence_limit():
    from isolator.model.signals import signal_function

    signals = signal_function(EXACT, 13)
    rng = np.random.default_rng(4)
    for angle in (1e-6, 1e-3, 0.05, 0.2):
        for _ in range(20):
            axis = rng.normal(size=3)
            axis /= np.linalg.norm(axis)
            ref = rng.normal(size=4)
            ref /= np.linalg.norm(ref)
            turn = np.r_[np.cos(angle / 2), np.sin(angle / 2) * axis]
            q = np.r_[turn[0] * ref[0] - turn[1:] @ ref[1:],
                      turn[0] * ref[1:] + ref[0] * turn[1:] + np.cross(turn[1:], ref[1:])]
            q *= rng.choice([-1.0, 1.0]) * rng.uniform(0.5, 2.0)  # either sign, any scale
            x, r = np.zeros(13), np.zeros(13)
            x[3:7], r[3:7] = q, ref
            series = np.asarray(signals(x, r)).ravel()[3:]
            assert np.allclose(series, angle * axis, rtol=0, atol=1e-15 + 2e-15 * angle)
            assert np.allclose(series, relative_rotation_vector(q[None], ref)[0], rtol=0, atol=1e-15)
