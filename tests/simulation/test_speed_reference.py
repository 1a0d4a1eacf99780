"""Issue 36: the speed work changes no number. Every result of the batch, the sweep, single runs and the
free-motion verdicts on the bundled scenarios equals the reference written by the code before it
(``tests/simulation/data/speed_reference.npz``, see ``tests/speed_reference.py``), bit for bit. The pneumatic
numbers (``batch-pneumatic/``, ``single6/``, ``single7/``) were written again when the DOP853 steps began to end on
the leveling valves' switches (:mod:`isolator.simulation.valve_events`): they moved by up to 2.4e-5 of a signal's
peak, the error of the steps across the switches before; every other number is the first reference's."""

from __future__ import annotations

import numpy as np
import pytest
from speed_reference import REFERENCE, compute


@pytest.fixture(scope="module")
def now() -> dict[str, np.ndarray]:
    return compute()


@pytest.fixture(scope="module")
def stored() -> dict[str, np.ndarray]:
    with np.load(REFERENCE, allow_pickle=False) as data:
        return {key: data[key] for key in data.files}


def test_the_same_numbers_are_computed(now, stored):
    assert sorted(now) == sorted(stored)


@pytest.mark.parametrize("group", ["batch/", "batch-paper/", "batch-short/", "batch-pneumatic/", "single", "sweep/"])
def test_every_number_is_the_references_bit_for_bit(now, stored, group):
    keys = [key for key in stored if key.startswith(group)]
    assert keys
    for key in keys:
        np.testing.assert_array_equal(now[key], stored[key], err_msg=key, strict=True)
