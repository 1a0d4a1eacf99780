"""Issue 36: the speed work changes no number. Every result of the batch, the sweep, single runs and the
free-motion verdicts on the bundled scenarios equals the reference written by the code before it
(``tests/simulation/data/speed_reference.npz``, see ``tests/speed_reference.py``): the statuses, the
reasons and which signals settle exactly; the numbers within round-off (``ROUND_OFF`` relative), because
the peaks and settling instants are now computed in the compiled loop (``cpp/dense_metrics.cpp``, whose
fused multiply-adds round differently from numpy: 2e-13 at most over the reference), where the code
before them computed them in numpy; every other number was bit for bit before that step, and is within
round-off now. The pneumatic numbers (``batch-pneumatic/``, ``single6/``, ``single7/``) were written again
when the DOP853 steps began to end on the leveling valves' switches (:mod:`isolator.simulation.valve_events`):
they moved by up to 2.4e-5 of a signal's peak, the error of the steps across the switches before; every
other number is the first reference's."""

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


#: the largest relative difference from the reference a number may have (round-off of ~1e-16 per operation)
ROUND_OFF = 1e-12
#: a settling instant is a root of a signal's dense polynomial minus its band, where the signal crosses the band
#: at a shallow slope: the round-off of the stages (eight SIMD lanes with fused multiply-adds on an AVX-512 CPU,
#: four elsewhere) moves it by up to ~1e-9 of itself (measured: 1.1e-9 on this machine at the commit that
#: wrote the reference)
CROSSING = 1e-8
#: numbers below this (m, rad, s) are round-off of zero (a free motion's offset of 1e-31 m)
ZERO = 1e-20


@pytest.mark.parametrize("group", ["batch/", "batch-paper/", "batch-short/", "batch-pneumatic/", "single", "sweep/"])
def test_every_number_is_the_references_within_round_off(now, stored, group):
    keys = [key for key in stored if key.startswith(group)]
    assert keys
    for key in keys:
        got, want = now[key], stored[key]
        assert got.shape == want.shape, key
        assert got.dtype.kind == want.dtype.kind, key
        if want.dtype.kind != "f":  # statuses, reasons, verdicts: the same words
            np.testing.assert_array_equal(got, want, err_msg=key, strict=True)
            continue
        np.testing.assert_array_equal(np.isnan(got), np.isnan(want), err_msg=key)  # the same signals settle
        # round-off of the array's largest number: a signal that does not move (a peak of 1e-16 m, round-off
        # itself) has no relative digits to keep
        scale = float(np.nanmax(np.abs(want), initial=0.0)) if want.size else 0.0
        rtol = CROSSING if key.endswith("settling") else ROUND_OFF
        np.testing.assert_allclose(got, want, rtol=rtol, atol=max(rtol * scale, ZERO), equal_nan=True, err_msg=key)
