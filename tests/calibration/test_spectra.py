"""Multi-input H1 (isolator.calibration.spectra): the FRF, the coherence and the random error checked
against known systems, and every bad argument one error line."""

from __future__ import annotations

import re

import numpy as np
import pytest
from scipy import signal

from isolator.calibration.spectra import COND_LIMIT, FrfEstimate, effective_averages, h1_estimate
from isolator.errors import ParameterError

RATE = 100.0  # [Hz]
B1 = signal.firwin(9, 0.3)
B2 = 0.5 * signal.firwin(7, 0.6)
BZ, AZ = signal.butter(2, 0.2)


def _system(n: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.random.Generator]:
    """Two correlated inputs (x2 = 0.7 x1 + 0.5 e2, e1 and e2 independent white) through a 2x2 system
    of FIR and second-order paths: inputs (2, n) and noise-free outputs (2, n)."""
    rng = np.random.default_rng(seed)
    e1, e2 = rng.standard_normal(n), rng.standard_normal(n)
    x = np.vstack([e1, 0.7 * e1 + 0.5 * e2])
    y = np.vstack([
        signal.lfilter(B1, 1.0, x[0]) + signal.lfilter(BZ, AZ, x[1]),
        signal.lfilter(B2, 1.0, x[0]) - 0.5 * signal.lfilter(B1, 1.0, x[1]),
    ])
    return x, y, rng


#: the inputs' cross-spectral matrix of _system (one-sided density of unit white noise: 2 / rate)
GXX = 2.0 / RATE * np.array([[1.0, 0.7], [0.7, 0.49 + 0.25]])


def _true_frf(f: np.ndarray) -> np.ndarray:
    """The exact (outputs, inputs, nf) frequency response of _system."""
    def fr(b: np.ndarray, a: np.ndarray | float = 1.0) -> np.ndarray:
        return signal.freqz(b, a, worN=f, fs=RATE)[1]

    return np.array([[fr(B1), fr(BZ, AZ)], [fr(B2), -0.5 * fr(B1)]])


def test_single_input_matches_scipy_welch():
    """One input: H is scipy's csd / welch and the coherence scipy's coherence, bin by bin."""
    rng = np.random.default_rng(0)
    x = rng.standard_normal(5000) + 3.0  # an offset: removed per segment (detrend='constant')
    y = signal.lfilter(B1, 1.0, x) + 0.2 * rng.standard_normal(5000)
    est = h1_estimate(x, y, RATE, segment=2.56)
    assert isinstance(est, FrfEstimate)
    f, gxy = signal.csd(x, y, fs=RATE, window="hann", nperseg=256)
    _, gxx = signal.welch(x, fs=RATE, window="hann", nperseg=256)
    _, coh = signal.coherence(x, y, fs=RATE, window="hann", nperseg=256)
    np.testing.assert_allclose(est.f, f)
    np.testing.assert_allclose(est.H[0, 0], gxy / gxx, rtol=1e-10)
    np.testing.assert_allclose(est.coherence[0], coh, rtol=1e-10, atol=1e-12)
    assert est.H.shape == (1, 1, f.size)
    assert est.variance.shape == (1, 1, f.size)
    assert est.segment == pytest.approx(2.56)
    # one input: the variance is (1 - g2) |H|^2 / (g2 (n_d - 1))
    g2 = est.coherence[0]
    np.testing.assert_allclose(est.variance[0, 0], (1 - g2) * np.abs(est.H[0, 0]) ** 2 / (g2 * (est.averages - 1)),
                               rtol=1e-9)


def test_effective_averages_hann_half_overlap():
    """Welch's count: c = 1/6 for Hann at 50 %, so n_d = K / (1 + 2 (1 - 1/K) / 36)."""
    for k in (2, 15, 127):
        assert effective_averages(k, 1024, 512) == pytest.approx(k / (1 + 2 * (1 - 1 / k) / 36), rel=1e-4)
    assert effective_averages(10, 1000, 1000) == 10.0  # no overlap: independent


def test_correlated_inputs_need_the_multi_input_estimate():
    """x2 = 0.7 x1 + noise: the single-input estimate Gyx_j / Gxx_jj takes the other path's share
    (H_i1 + 0.7 H_i2 ...), off by 75 % or more of the element's peak; Gyx Gxx^-1 recovers the true
    FRF within 1.5 % of the peak (leakage bias about 0.9 % at worst) over 1-45 Hz (Nyquist 50 Hz)."""
    x, y, rng = _system(2**16, seed=3)
    y = y + 1e-3 * rng.standard_normal(y.shape)
    est = h1_estimate(x, y, RATE, segment=10.24)
    band = (est.f >= 1.0) & (est.f <= 45.0)
    true = _true_frf(est.f)
    peak = np.abs(true).max(axis=2, keepdims=True)
    multi = (np.abs(est.H - true) / peak)[:, :, band]
    assert multi.max() < 0.015
    assert np.median(multi) < 0.002
    for i in range(2):
        for j in range(2):
            _, gyx = signal.csd(x[j], y[i], fs=RATE, window="hann", nperseg=1024)
            _, gxx = signal.welch(x[j], fs=RATE, window="hann", nperseg=1024)
            single = np.abs(gyx / gxx - true[i, j]) / peak[i, j]
            assert single[band].max() > 0.7, (i, j)


def test_coherence_is_one_on_periodic_noise_free_data():
    """y = a circular filter of x, x periodic with a third of the segment: each segment's spectrum has
    lines on every third bin only, and the Hann window (3 bins wide) mixes no two lines into one bin,
    so Y_k(f) / X_k(f) is the same in every segment at every bin: coherence 1 to rounding, and H at the
    line bins is the filter's exact DFT. (With a random x and an FIR, leakage leaves 1 - gamma2 ~ 1e-3.)"""
    period, nper = 256, 768
    rng = np.random.default_rng(5)
    one = rng.standard_normal(period)
    kernel = np.zeros(period)
    kernel[:9] = B1
    kernel[:3] += [0.3, -0.2, 0.1]
    frf = np.fft.rfft(kernel)
    y_one = np.fft.irfft(np.fft.rfft(one) * frf, n=period)
    x, y = np.tile(one, 40), np.tile(y_one, 40)
    est = h1_estimate(x, y, RATE, segment=nper / RATE)
    # bins 0 and 1 hold no line (the mean is removed): no input power, NaN
    assert np.isnan(est.coherence[0, :2]).all()
    np.testing.assert_allclose(est.coherence[0, 2:], 1.0, atol=1e-9)
    np.testing.assert_allclose(est.H[0, 0, 3::3], frf[1:], rtol=1e-9)
    np.testing.assert_allclose(est.variance[0, 0, 2:], 0.0, atol=1e-9 * np.abs(frf).max() ** 2)


def test_coherence_is_one_for_static_multi_input_gains():
    """y = A x (correlated inputs): H = A and multiple coherence 1 at every bin, to rounding."""
    x, _, _ = _system(8192, seed=6)
    a = np.array([[2.0, -3.0], [0.5, 0.25], [1.0, 1.0]])
    est = h1_estimate(x, a @ x, RATE, segment=5.12)
    np.testing.assert_allclose(est.coherence, 1.0, atol=1e-9)
    np.testing.assert_allclose(est.H, np.broadcast_to(a[:, :, None], est.H.shape), atol=1e-9)


def test_coherence_drops_with_output_noise_as_predicted():
    """White output noise N = 2 sigma^2 / rate on the signal S = h Gxx h^H: gamma2 = S / (S + N),
    spanning 0 to 0.97 over the band. Each bin within 4 standard deviations of the estimate
    (sqrt(2) gamma (1 - gamma2) / sqrt(n_d)) plus its bias (~ q (1 - gamma2) / n_d) and 2e-3 of
    leakage; the median error under 0.015."""
    x, y, rng = _system(2**18, seed=4)
    sigma = 0.3
    est = h1_estimate(x, y + sigma * rng.standard_normal(y.shape), RATE, segment=10.24)
    band = (est.f >= 1.0) & (est.f <= 45.0)
    true = _true_frf(est.f)
    s = np.einsum("ijf,jk,ikf->if", true, GXX, true.conj()).real
    g2 = (s / (s + 2 * sigma**2 / RATE))[:, band]
    assert g2.min() < 0.05
    assert g2.max() > 0.9
    got = est.coherence[:, band]
    n_d = est.averages
    tol = 4 * np.sqrt(2 * g2) * (1 - g2) / np.sqrt(n_d) + 2 * 2 * (1 - g2) / n_d + 2e-3
    assert np.all(np.abs(got - g2) <= tol)
    assert np.median(np.abs(got - g2)) < 0.015


@pytest.mark.parametrize(("n", "nperseg"), [(2**14, 256), (2**14, 2048)])
def test_variance_matches_monte_carlo(n, nperseg):
    """The predicted E|H_est - H|^2 against 200 output-noise seeds on fixed inputs (the conditional
    variance, as a measurement has it), for about 120 and 14 effective averages.

    The median over the 4 elements x bins of empirical / predicted (mean of the 200 predictions) is
    0.99 (n_d = 120) and 0.987 (n_d = 14.3) with this formula; the test allows 3 %. It would fail:
    - counting the overlapped segments as independent (n_d = K): the ratio rises by
      (K - q) / (n_d - q) = 1.056 (K = 127) and 1.060 (K = 15): 1.045 and 1.047;
    - without the degrees of freedom (n_d in place of n_d - q), at n_d = 14.3: x 0.86;
    - anything off by a factor 2.
    Those alternatives are computed below and asserted to fail."""
    x, y, _ = _system(n, seed=2)
    seeds = 200
    h, predicted = [], []
    for seed in range(seeds):
        noise = 0.3 * np.random.default_rng(1000 + seed).standard_normal(y.shape)
        est = h1_estimate(x, y + noise, RATE, segment=nperseg / RATE)
        h.append(est.H)
        predicted.append(est.variance)
    hs = np.array(h)[:, :, :, 2:-2]  # DC and Nyquist bins apart (real there)
    empirical = np.mean(np.abs(hs - hs.mean(axis=0)) ** 2, axis=0) * seeds / (seeds - 1)
    ratio = np.median(empirical / np.mean(predicted, axis=0)[:, :, 2:-2])
    assert ratio == pytest.approx(1.0, abs=0.03)
    k = 1 + (n - nperseg) // (nperseg // 2)
    n_d, q = est.averages, 2
    assert abs(ratio * (k - q) / (n_d - q) - 1) > 0.03  # overlap ignored
    assert abs(ratio * 2 - 1) > 0.03
    assert abs(ratio / 2 - 1) > 0.03
    if n_d < 30:
        assert abs(ratio * (n_d - q) / n_d - 1) > 0.03  # no degrees-of-freedom correction


def test_fast_enough_for_a_long_record():
    """13 channels x 60,000 samples: one STFT and batched solves (about 0.05 s; well under 1 s)."""
    rng = np.random.default_rng(1)
    est = h1_estimate(rng.standard_normal((3, 60000)), rng.standard_normal((10, 60000)), 500.0, 8.0)
    assert est.H.shape == (10, 3, 2001)


# --- errors ------------------------------------------------------------------------------------


def _refused(pattern: str, inputs: np.ndarray, outputs: np.ndarray, rate: float = RATE, segment: float = 1.0) -> str:
    with pytest.raises(ParameterError) as info:
        h1_estimate(inputs, outputs, rate, segment)
    message = str(info.value)
    assert "\n" not in message
    assert re.search(pattern, message), message
    return message


def test_shapes_must_match():
    rng = np.random.default_rng(0)
    _refused(r"^outputs: 900 samples per channel, the inputs have 1000", rng.standard_normal((2, 1000)),
             rng.standard_normal((1, 900)))
    _refused(r"^inputs: must be a \(channels, samples\) array", np.zeros((2, 3, 100)), np.zeros((1, 100)))
    _refused(r"^outputs: must be a \(channels, samples\) array.*\(0, 1000\)", rng.standard_normal(1000),
             np.zeros((0, 1000)))
    _refused(r"^inputs: must be real numbers", rng.standard_normal(1000) * 1j, rng.standard_normal(1000))


def test_non_finite_samples():
    rng = np.random.default_rng(0)
    x, y = rng.standard_normal((2, 1000)), rng.standard_normal((1, 1000))
    x[1, 417] = np.nan
    _refused(r"^inputs\[1\]: sample 417 is nan", x, y)
    y[0, 3] = np.inf
    _refused(r"^outputs\[0\]: sample 3 is inf", x[:1], y)


@pytest.mark.parametrize(("rate", "segment", "pattern"), [
    (0.0, 1.0, r"^rate: must be a finite sample rate > 0 Hz, got 0.0"),
    (-5.0, 1.0, r"^rate: .* got -5.0"),
    (np.nan, 1.0, r"^rate: .* got nan"),
    (RATE, 0.0, r"^segment: must be a finite length > 0 s"),
    (RATE, 0.07, r"^segment: 0.07 s is 7 samples at 100 Hz \(needs at least 8\)"),
    (RATE, 8.0, r"^segment: 8 s \(800 samples\) leaves fewer than two segments in 1000 samples"),
])
def test_bad_rate_or_segment(rate, segment, pattern):
    rng = np.random.default_rng(0)
    _refused(pattern, rng.standard_normal(1000), rng.standard_normal(1000), rate, segment)


def test_more_averages_than_inputs():
    rng = np.random.default_rng(0)
    _refused(r"^segment: 3 segments .* for 3 inputs", rng.standard_normal((3, 2000)), rng.standard_normal(2000),
             segment=10.0)


def test_zero_or_constant_input_or_output():
    rng = np.random.default_rng(0)
    x = rng.standard_normal((3, 4000))
    x[2] = 0.0
    _refused(r"^inputs\[2\]: is constant \(0 throughout\)", x, rng.standard_normal(4000))
    _refused(r"^outputs\[1\]: is constant \(9.81 throughout\)", x[:2], np.vstack([x[0], np.full(4000, 9.81)]))


def test_identical_inputs_are_named():
    rng = np.random.default_rng(0)
    a, b = rng.standard_normal((2, 4000))
    message = _refused(r"^inputs: inputs\[0\], inputs\[2\] are collinear", np.vstack([a, b, a]),
                       a + b)
    assert "inputs[1]" not in message
    assert f"> {COND_LIMIT:g}" in message


def test_dependent_inputs_are_named():
    """x3 = 2 x1 - x2: all three take part; a scaled copy is as singular as a copy."""
    rng = np.random.default_rng(1)
    a, b, c = rng.standard_normal((3, 4000))
    _refused(r"^inputs: inputs\[0\], inputs\[1\], inputs\[2\] are collinear", np.vstack([a, b, 2 * a - b, c])[:3],
             c)
    _refused(r"^inputs: inputs\[0\], inputs\[1\] are collinear", np.vstack([a, -3e-4 * a]), b)


def test_nearly_collinear_inputs_pass_with_a_large_variance():
    """x2 = x1 + 1e-3 noise is not singular: estimated, its ill-conditioning shown by the variance."""
    rng = np.random.default_rng(2)
    a, b, n = rng.standard_normal((3, 2**14))
    x = np.vstack([a, a + 1e-3 * b])
    est = h1_estimate(x, a + 0.1 * n, RATE, segment=2.56)
    well = h1_estimate(np.vstack([a, b]), a + 0.1 * n, RATE, segment=2.56)
    assert np.nanmedian(est.variance) > 1e4 * np.nanmedian(well.variance)
