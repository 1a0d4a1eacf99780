"""The fitted model's modes against a model-free modal estimate of the same measured H1 (sdypy-EMA's
least-squares complex-frequency estimator on the floor experiment's H1, one estimate per floor input; only the
poles are used)."""

from __future__ import annotations

import numpy as np
import pytest

from isolator.calibration import calibrate


def _stable_poles(frf: np.ndarray, f: np.ndarray, order: int) -> np.ndarray:
    """Natural frequencies [Hz] of the poles found at the two highest polynomial orders within 0.2 % of each
    other (stable in the estimator's sense; model-free: the poles of a rational fit of the data only)."""
    from sdypy import EMA

    model = EMA.Model(frf=frf, freq=f, lower=float(f[0]), upper=float(f[-1]), pol_order_high=order,
                      frf_form="accelerance")
    model.get_poles(show_progress=False)
    last, before = (np.asarray(p) for p in model.all_poles[-2:][::-1])
    fn_last = np.abs(last) / (2 * np.pi)
    fn_before = np.abs(before) / (2 * np.pi)
    lightly = -last.real / np.abs(last) < 0.3  # oscillating modes
    stable = [fn for fn, ok in zip(fn_last, lightly, strict=True)
              if ok and np.min(np.abs(fn_before - fn)) < 2e-3 * fn and f[0] < fn < f[-1]]
    return np.array(sorted(stable))


def test_fitted_modes_match_a_model_free_estimate_of_the_h1(tmp_path, mujoco_records, write_calibration):
    pytest.importorskip("sdypy.EMA")
    move, floor = mujoco_records
    result = calibrate(write_calibration(tmp_path, move, floor, 11, ("floor",)))
    curves = result.curves["floor-random"]
    # one estimate per floor input: the H1s from floor x, y and z each show their own family of modes (the
    # x/ry and y/rx pairs 1.6 % apart are resolved that way)
    poles = np.concatenate([_stable_poles(curves.measured[:, k, :], curves.x, 20) for k in range(3)])

    def within(modes: list[float]) -> int:
        return sum(bool(poles.size) and float(np.min(np.abs(poles - fn))) < 0.01 * fn for fn in modes)

    fitted = result.modes["fitted"]["frequencies_hz"]
    # four of the six modes have a pole of the estimate within 1 % (the yaw mode is barely excited by floor
    # translations; the heave pole from the measured H1 comes out about 1 % low: the estimator's leakage bias,
    # which the calibration itself removes by comparing the model through the same estimator); the datasheet
    # model's modes, 2-9 % off, match at most two
    assert within(fitted) >= 4, (fitted, poles)
    assert within(result.modes["nominal"]["frequencies_hz"]) <= 2, (result.modes["nominal"], poles)
