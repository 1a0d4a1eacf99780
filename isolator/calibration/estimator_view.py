"""The model's frequency response as the Welch H1 estimator sees it.

A Welch H1 of a lightly damped table is biased on any record of practical length: its segments are windowed
(peaks lowered and widened) and each segment's output also answers input from before it. On a long record that
bias is far larger than the estimate's random error, so the model is put through the same estimator: the
linear model's response to the measured floor signals is computed (``Y = H X`` on a zero-padded FFT grid,
the table at rest before the record), and its H1 is taken from the same segments as the record's, all
after a warm-up of six of the slowest mode's decay times (the record's and the model's start transients
gone), with the same window, overlap and detrending. It is linear in ``H``, so the derivatives of the model's
H1 are the H1 of its derivatives' responses: exact.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import fft

from isolator.calibration.spectra import segment_spectra

__all__ = ["EstimatorView"]

#: lines beyond the band's edges the model's response is computed on, in bins of the segment (the Hann
#: window's leakage from further away is below 1e-5)
MARGIN_BINS = 10.0


@dataclass(frozen=True)
class EstimatorView:
    """What the H1 of the record's segments sees of a response given on :attr:`lines`.

    Attributes
    ----------
    lines : ndarray (nl,)
        Frequencies [Hz] of the padded FFT grid the response is needed on (the band and a margin).
    picks : ndarray (nl,) of int
        Their indices in the padded grid.
    spectrum : ndarray (m, n_pad // 2 + 1)
        The floor signals' spectrum, zero-padded.
    n, start, nperseg, n_pad : int
        Record samples, the first sample used (after the warm-up), samples per segment, the padded length.
    rate : float
        [Hz]
    bins : ndarray (nb,) of int
        The fitted bins among the Welch frequencies.
    gxx_inverse : ndarray (nb, m, m)
        The floor signals' cross-spectral matrix, inverted, at those bins.
    segments : ndarray (m, nb, segments)
        The floor signals' segment spectra at those bins, conjugated.
    """

    lines: np.ndarray
    picks: np.ndarray
    spectrum: np.ndarray
    n: int
    start: int
    nperseg: int
    n_pad: int
    rate: float
    bins: np.ndarray
    gxx_inverse: np.ndarray
    segments: np.ndarray

    @classmethod
    def of(cls, inputs: np.ndarray, rate: float, nperseg: int, start: int, bins: np.ndarray, f: np.ndarray,
           pad: int) -> EstimatorView:
        """The view of the Welch bins ``bins`` (indices into the Welch frequencies ``f`` [Hz]) of segments of
        ``nperseg`` samples from sample ``start`` on, for floor signals ``inputs`` (m, N) at ``rate`` [Hz];
        the FFT grid padded by ``pad`` samples (longer than the table's memory)."""
        n = inputs.shape[1]
        n_pad = fft.next_fast_len(n + pad, real=True)
        grid = np.fft.rfftfreq(n_pad, 1.0 / rate)
        margin = MARGIN_BINS * rate / nperseg
        picks = np.flatnonzero((grid > 0) & (grid >= f[bins].min() - margin) & (grid <= f[bins].max() + margin))
        spectrum = fft.rfft(inputs, n_pad, axis=1)
        zx = segment_spectra(inputs[:, start:], rate, nperseg, bins)
        gxx = np.einsum("ibs,jbs->bij", zx, zx.conj())
        return cls(grid[picks], picks, spectrum, n, start, nperseg, n_pad, rate, bins, np.linalg.inv(gxx),
                   zx.conj())

    def seen(self, h: np.ndarray) -> np.ndarray:
        """The H1 (..., outputs, m, nb) of a response ``h`` (..., outputs, m, nl) given on :attr:`lines` (floor
        signal to output); leading axes (parameter derivatives) are kept."""
        lead = h.shape[:-3]
        outputs = h.shape[-3]
        y_lines = np.einsum("...sml,ml->...sl", h, self.spectrum[:, self.picks])
        full = np.zeros((*lead, outputs, self.spectrum.shape[1]), dtype=complex)
        full[..., self.picks] = y_lines
        y = fft.irfft(full, self.n_pad, axis=-1)[..., self.start : self.n]
        zy = segment_spectra(y.reshape(-1, y.shape[-1]), self.rate, self.nperseg, self.bins)
        gyx = np.einsum("ybs,jbs->byj", zy, self.segments)
        h1 = gyx @ self.gxx_inverse  # (nb, channels, m)
        return np.moveaxis(h1.reshape(self.bins.size, *lead, outputs, -1), 0, -1)
