"""Frequency responses from measured records: multi-input H1 with multiple coherence and random error.

Welch cross-spectra of all channels at once (Hann window, 50 % overlap, each segment's mean
removed: scipy's ``detrend='constant'``, no other detrending), then per frequency bin

- ``H = Gyx Gxx^-1`` (multi-input H1, by a batched linear solve, no explicit inverse),
- the multiple coherence of each output with all inputs, ``gamma2 = (Gyx Gxx^-1 Gxy) / Gyy``,
- the random error variance of each element ``E|H_est - H|^2`` from the residual spectrum.

Conventions: ``G[a, b] = E[Z_a conj(Z_b)]`` for the segments' spectra ``Z`` (so ``Gyx`` is
``(outputs, inputs)`` and ``scipy.signal.csd(x_j, y_i)`` is ``Gyx[i, j]``), one-sided densities
[unit^2/Hz] exactly as ``scipy.signal.csd`` gives them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import fft

from isolator.errors import ParameterError
from isolator.scenario.files import check_memory

__all__ = ["COND_LIMIT", "MIN_SEGMENT_SAMPLES", "POWER_FLOOR", "FrfEstimate", "effective_averages", "h1_estimate"]

#: inputs whose normalised cross-spectral matrix has a larger condition number at a bin are singular there
COND_LIMIT = 1e10
#: a bin has input power when every input's autospectrum there exceeds this fraction of its own peak
POWER_FLOOR = 1e-12
#: the shortest Welch segment [samples]
MIN_SEGMENT_SAMPLES = 8


@dataclass(frozen=True)
class FrfEstimate:
    """A multi-input H1 estimate with its coherence and random error.

    Bins without input power (some input's autospectrum at most :data:`POWER_FLOOR` of its peak,
    e.g. the DC bin of a signal whose segments' means are removed exactly) hold NaN in ``H``,
    ``coherence`` and ``variance``.

    Attributes
    ----------
    f : ndarray, shape (nf,)
        Bin frequencies [Hz], 0 to the Nyquist frequency.
    H : ndarray, shape (outputs, inputs, nf), complex
        ``Gyx Gxx^-1`` [output unit / input unit].
    coherence : ndarray, shape (outputs, nf)
        Multiple coherence of each output with all inputs (the ordinary coherence for one input), in [0, 1].
    variance : ndarray, shape (outputs, inputs, nf)
        Random error variance ``E|H_est - H|^2`` of each element [(output unit / input unit)^2].
    averages : float
        Effective number of independent averages ``n_d`` used in ``variance``.
    segment : float
        Welch segment length used [s] (a whole number of samples).
    """

    f: np.ndarray
    H: np.ndarray
    coherence: np.ndarray
    variance: np.ndarray
    averages: float
    segment: float


def effective_averages(segments: int, nperseg: int, step: int) -> float:
    """Equivalent number of independent averages of a Hann-windowed Welch estimate.

    Welch (1967): ``n_d = K / (1 + 2 sum_m (1 - m/K) c_m^2)`` for ``K`` segments, ``c_m`` the
    correlation of the window with itself shifted by ``m`` steps (``sum w[n] w[n + m step] / sum
    w^2``). For Hann at 50 % overlap ``c_1 = 1/6`` (about 0.167) and ``c_m = 0`` beyond, so
    ``n_d ~= K / 1.056``. Overlapping segments are correlated; this is the count of independent
    segments giving the same variance (exact for a spectrum smooth over the window's bandwidth).

    Parameters
    ----------
    segments : int
        Number of segments ``K``.
    nperseg, step : int
        Segment length and hop [samples].
    """
    from scipy import signal  # imported where used: scipy.signal takes a quarter of a second

    w = signal.get_window("hann", nperseg)
    energy = float(np.dot(w, w))
    total = 0.0
    for m in range(1, segments):
        shift = m * step
        if shift >= nperseg:
            break
        c = float(np.dot(w[: nperseg - shift], w[shift:])) / energy
        total += (1.0 - m / segments) * c * c
    return segments / (1.0 + 2.0 * total)


def h1_estimate(inputs: np.ndarray, outputs: np.ndarray, rate: float, segment: float) -> FrfEstimate:
    """Multi-input H1 frequency response, multiple coherence and random error from time records.

    Parameters
    ----------
    inputs : ndarray, shape (q, N) or (N,)
        Input records (a 1-D array is one input), uniformly sampled.
    outputs : ndarray, shape (p, N) or (N,)
        Output records, sampled with the inputs.
    rate : float
        Sample rate [Hz].
    segment : float
        Welch segment length [s]; rounded to whole samples (``FrfEstimate.segment`` is the one used).

    Returns
    -------
    FrfEstimate

    Notes
    -----
    Random error (Bendat & Piersol, *Random Data*, 4th ed., ch. 9; Goodman 1965, the regression
    view): given the inputs, each bin is a least-squares fit of ``Y_k = H X_k + N_k`` over the
    averages, so ``Var(H_ij) = Gnn [Gxx^-1]_jj / n_d`` with ``Gnn`` the true residual spectrum; the
    residual spectrum measured, ``(1 - gamma2) Gyy``, has ``n_d - q`` degrees of freedom (its mean
    is ``Gnn (1 - q/n_d)``), hence

        ``variance[i, j] = (1 - gamma2_i) Gyy_ii [Gxx^-1]_jj / (n_d - q)``

    with ``n_d`` = :func:`effective_averages` (overlap-corrected). For one input this is
    ``(1 - gamma2) |H|^2 / (gamma2 (n_d - 1))``, Bendat & Piersol's ``|H|^2 (1 - gamma2) /
    (gamma2 n_d)`` (``epsilon^2`` of gain plus the phase variance) with the degree of freedom the fit uses.
    It is the random error only: leakage bias (a segment short against the slowest decay) is not in it.

    Raises
    ------
    ParameterError
        Arrays of the wrong shape or kind, non-finite samples, ``rate`` or ``segment`` not finite
        and > 0, a segment under :data:`MIN_SEGMENT_SAMPLES` samples, fewer than two segments or
        no more segments than inputs, a constant (e.g. all-zero) input or output, or inputs
        whose cross-spectral matrix is singular (condition number of the matrix normalised by its
        diagonal over :data:`COND_LIMIT`) at a bin where every input has power (each
        autospectrum over :data:`POWER_FLOOR` of its peak): the message names the collinear inputs
        by index (``inputs[0], inputs[1]``).
    """
    x = _records(inputs, "inputs")
    y = _records(outputs, "outputs")
    if x.shape[1] != y.shape[1]:
        raise ParameterError(f"outputs: {y.shape[1]} samples per channel, the inputs have {x.shape[1]}")
    if not (np.isfinite(rate) and rate > 0):
        raise ParameterError(f"rate: must be a finite sample rate > 0 Hz, got {rate}")
    if not (np.isfinite(segment) and segment > 0):
        raise ParameterError(f"segment: must be a finite length > 0 s, got {segment}")
    q, n = x.shape
    nperseg = round(segment * rate)
    if nperseg < MIN_SEGMENT_SAMPLES:
        raise ParameterError(f"segment: {segment:g} s is {nperseg} samples at {rate:g} Hz (needs at least "
                             f"{MIN_SEGMENT_SAMPLES})")
    noverlap = nperseg // 2
    step = nperseg - noverlap
    count = 1 + (n - nperseg) // step if n >= nperseg else 0
    if count < 2:
        raise ParameterError(f"segment: {segment:g} s ({nperseg} samples) leaves fewer than two segments in "
                             f"{n} samples at 50 % overlap (needs {nperseg + step}); give a shorter segment")
    n_d = effective_averages(count, nperseg, step)
    if n_d <= q:
        raise ParameterError(f"segment: {count} segments ({n_d:.3g} independent averages) for {q} inputs; the "
                             f"estimate needs more averages than inputs: give a shorter segment or a longer record")
    channels = q + y.shape[0]  # the segments' spectra and the spectral matrix, a few copies each, checked first
    check_memory(64.0 * (n * channels + (nperseg // 2 + 1) * channels**2),
                 f"segment: {n} samples of {channels} channels in segments of {nperseg}",
                 "give a shorter segment or a shorter record")
    _check_constant(x, "inputs")
    _check_constant(y, "outputs")
    f, G = _spectral_matrix(np.vstack([x, y]), rate, nperseg)
    Gxx, Gyx = G[:, :q, :q], G[:, q:, :q]
    Gyy = G[:, q:, q:].diagonal(axis1=1, axis2=2).real
    valid = _valid_bins(Gxx, f)
    nf, p = f.size, y.shape[0]
    H = np.full((p, q, nf), np.nan, dtype=complex)
    coherence = np.full((p, nf), np.nan)
    variance = np.full((p, q, nf), np.nan)
    if valid.any():
        # H Gxx = Gyx  <=>  Gxx^T H^T = Gyx^T; one solve also gives diag(Gxx^-1) (= diag of (Gxx^T)^-1)
        rhs = np.concatenate([Gyx[valid].transpose(0, 2, 1), np.broadcast_to(np.eye(q), (int(valid.sum()), q, q))],
                             axis=2)
        solved = np.linalg.solve(Gxx[valid].transpose(0, 2, 1), rhs)
        Hv = solved[:, :, :p].transpose(0, 2, 1)  # (bins, p, q)
        inv_diag = solved[:, :, p:].diagonal(axis1=1, axis2=2).real  # (bins, q)
        gyy = Gyy[valid]
        explained = np.einsum("bij,bij->bi", Hv, Gyx[valid].conj()).real
        gamma2 = np.clip(explained / gyy, 0.0, 1.0)
        residual = (1.0 - gamma2) * gyy  # Gnn per output
        H[:, :, valid] = Hv.transpose(1, 2, 0)
        coherence[:, valid] = gamma2.T
        variance[:, :, valid] = (residual[:, :, None] * inv_diag[:, None, :] / (n_d - q)).transpose(1, 2, 0)
    return FrfEstimate(f=f, H=H, coherence=coherence, variance=variance, averages=n_d, segment=nperseg / rate)


def _records(values: np.ndarray, name: str) -> np.ndarray:
    """The channels as a real (channels, samples) float array, checked finite."""
    a = np.asarray(values)
    if np.iscomplexobj(a) or not (np.issubdtype(a.dtype, np.number) or a.dtype == bool):
        raise ParameterError(f"{name}: must be real numbers, got dtype {a.dtype}")
    a = np.atleast_2d(a.astype(float))
    if a.ndim != 2 or a.shape[0] == 0 or a.shape[1] == 0:
        raise ParameterError(f"{name}: must be a (channels, samples) array with at least one channel, got shape "
                             f"{np.shape(values)}")
    bad = ~np.isfinite(a)
    if bad.any():
        channel, sample = np.argwhere(bad)[0]
        raise ParameterError(f"{name}[{channel}]: sample {sample} is {a[channel, sample]} (samples must be finite)")
    return a


def _check_constant(a: np.ndarray, name: str) -> None:
    """Refuse a channel with no signal once its mean is removed (zero, constant)."""
    flat = np.ptp(a, axis=1) == 0
    if flat.any():
        k = int(np.argmax(flat))
        raise ParameterError(f"{name}[{k}]: is constant ({a[k, 0]:g} throughout): no signal once its mean is "
                             "removed")


def segment_spectra(z: np.ndarray, rate: float, nperseg: int, bins: np.ndarray | None = None) -> np.ndarray:
    """Welch's segments' spectra (channels, bins, segments) of ``z`` (channels, N): Hann, 50 % overlap, each
    segment's mean removed, scaled as ``scipy.signal.spectrogram`` (complex, density); all bins, or ``bins``
    (indices) only. One definition for the records' H1 and the model's (:mod:`.estimator_view`)."""
    from scipy import signal  # imported where used: scipy.signal takes a quarter of a second

    window = signal.get_window("hann", nperseg)
    step = nperseg - nperseg // 2
    segments = np.lib.stride_tricks.sliding_window_view(z, nperseg, axis=-1)[..., ::step, :]
    spectra = fft.rfft(segments * window, axis=-1, workers=-1)  # (channels, segments, nperseg // 2 + 1)
    # removing a segment's mean removes mean * (the window's spectrum) at each bin
    spectra -= segments.mean(axis=-1)[..., None] * fft.rfft(window)
    if bins is not None:
        spectra = spectra[..., bins]
    return np.swapaxes(spectra, -1, -2) * np.sqrt(1.0 / (rate * float(np.sum(window**2))))


def _spectral_matrix(z: np.ndarray, rate: float, nperseg: int) -> tuple[np.ndarray, np.ndarray]:
    """Bin frequencies [Hz] and the one-sided Welch cross-spectral matrix ``G[f, a, b] = E[Z_a conj(Z_b)]``.

    The segments' spectra (:func:`segment_spectra`, half a segment's overlap), then the average of
    their outer products, scaled as ``scipy.signal.csd``.
    """
    f = np.fft.rfftfreq(nperseg, 1.0 / rate)
    Z = segment_spectra(z, rate, nperseg).transpose(1, 0, 2)  # (nf, channels, segments)
    G = (Z @ Z.conj().transpose(0, 2, 1)) / Z.shape[2]
    one_sided = np.full(f.size, 2.0)
    one_sided[0] = 1.0
    if nperseg % 2 == 0:
        one_sided[-1] = 1.0
    return f, G * one_sided[:, None, None]


def _valid_bins(Gxx: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Bins where every input has power (``Gxx`` solved there); refuse inputs singular at such a bin."""
    auto = Gxx.diagonal(axis1=1, axis2=2).real  # (nf, q)
    q = auto.shape[1]
    positive = np.all(auto > 0, axis=1)
    cond = np.full(f.size, np.inf)
    vectors = np.zeros((f.size, q), dtype=complex)
    if positive.any():
        scale = 1.0 / np.sqrt(auto[positive])
        normalised = Gxx[positive] * scale[:, :, None] * scale[:, None, :]  # unit diagonal: scale-free
        eigvals, eigvecs = np.linalg.eigh(normalised)
        smallest = eigvals[:, 0]
        cond[positive] = np.where(smallest > 0, eigvals[:, -1] / np.where(smallest > 0, smallest, 1.0), np.inf)
        vectors[positive] = eigvecs[:, :, 0]
    powered = positive & np.all(auto > POWER_FLOOR * auto.max(axis=0), axis=1)
    if not powered.any():
        raise ParameterError(f"inputs: no frequency bin where every input has power (over {POWER_FLOOR:g} of its "
                             "peak): the inputs excite disjoint bands")
    singular = powered & (cond > COND_LIMIT)
    if singular.any():
        worst = int(np.argmax(np.where(singular, cond, -1.0)))
        weight = np.abs(vectors[worst])
        involved = np.flatnonzero(weight > 1e-3 * weight.max())
        names = ", ".join(f"inputs[{j}]" for j in involved)
        span = f[singular]
        where = f"{span[0]:.4g} Hz" if span.size == 1 else f"{span.size} bins from {span[0]:.4g} to {span[-1]:.4g} Hz"
        number = f"{cond[worst]:.3g}" if np.isfinite(cond[worst]) else "infinite"
        raise ParameterError(f"inputs: {names} are collinear (their cross-spectral matrix is singular at {where}, "
                             f"condition number {number} > {COND_LIMIT:g}): measure independent inputs or leave "
                             "one out")
    return powered
