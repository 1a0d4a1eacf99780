"""The model's frequency response as the Welch H1 estimator sees it.

A Welch spectrum is the true one smoothed by the power spectrum of the segment's window, ``|W(f)|^2`` (Hann:
a main lobe of +-2 bins): near a lightly damped resonance the estimate is biased (peaks lowered and widened)
by far more than its random error on a long record. So the model is compared through the same window: with
``X(v)`` the floor signals' spectrum over the whole record (resolution ``1 / duration``),

``Gxx(f) = sum_v |W(f - v)|^2 X(v) X(v)^H``,  ``Gyx(f) = sum_v |W(f - v)|^2 H(v) X(v) X(v)^H``,
``H_seen(f) = Gyx(f) Gxx(f)^-1``

(the expected H1 of the model driven by the measured floor), linear in ``H`` so that its parameter
derivatives follow exactly from the model's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import get_window

__all__ = ["WindowView"]

#: fine lines each side of a bin taken into its sum, in bins of the segment (Hann's main lobe is 2)
REACH = 4.0


@dataclass(frozen=True)
class WindowView:
    """What the H1 of ``bins`` [Hz] sees of a response given on ``fine`` [Hz].

    Attributes
    ----------
    fine : ndarray (nfine,)
        The whole record's frequency lines the bins draw on [Hz].
    weights : ndarray (bins, nfine)
        ``|W(f - v)|^2``, normalised per bin.
    xx : ndarray (nfine, m, m)
        ``X(v) X(v)^H`` of the floor signals.
    """

    fine: np.ndarray
    weights: np.ndarray
    xx: np.ndarray

    @classmethod
    def of(cls, inputs: np.ndarray, rate: float, segment: float, bins: np.ndarray) -> WindowView:
        """The view of ``bins`` [Hz] of a Welch estimate with Hann segments of ``segment`` [s] of ``inputs``
        (m, N) sampled at ``rate`` [Hz]."""
        n = inputs.shape[1]
        nperseg = round(segment * rate)
        x = np.fft.rfft(inputs - inputs.mean(axis=1, keepdims=True), axis=1)
        lines = np.fft.rfftfreq(n, 1.0 / rate)
        width = REACH * rate / nperseg
        keep = (lines >= bins.min() - width) & (lines <= bins.max() + width) & (lines > 0)
        fine = lines[keep]
        offsets = bins[:, None] - fine[None, :]
        near = np.abs(offsets) <= width
        window = get_window("hann", nperseg)
        k = np.arange(nperseg)
        weights = np.zeros(offsets.shape)
        rows, cols = np.nonzero(near)
        for lo in range(0, rows.size, 4096):  # |sum_k w_k exp(-2j pi d k / rate)|^2 at each offset d
            d = offsets[rows[lo : lo + 4096], cols[lo : lo + 4096]]
            weights[rows[lo : lo + 4096], cols[lo : lo + 4096]] = np.abs(
                np.exp(-2j * np.pi * d[:, None] * k[None, :] / rate) @ window) ** 2
        weights /= weights.sum(axis=1, keepdims=True)
        xs = x[:, keep]
        return cls(fine, weights, np.einsum("in,jn->nij", xs, xs.conj()))

    def seen(self, h: np.ndarray) -> np.ndarray:
        """The H1 (outputs, m, bins) of a response ``h`` (..., outputs, m, nfine) given on :attr:`fine`;
        leading axes (parameter derivatives) are kept."""
        gxx = np.einsum("bn,nij->bij", self.weights, self.xx)
        gyx = np.einsum("bn,...snj,njk->...bsk", self.weights, np.moveaxis(h, -1, -2), self.xx)
        solved = np.linalg.solve(np.swapaxes(gxx, -1, -2)[(None,) * (gyx.ndim - 3)],
                                 np.swapaxes(gyx, -1, -2))  # (H Gxx = Gyx)^T
        return np.moveaxis(np.swapaxes(solved, -1, -2), -3, -1)
