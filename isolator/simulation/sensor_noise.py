"""Sensor noise as the contract draws it (``docs/scenario-format.md``, "Error budget: random disturbances and
noise at the points"): a sequence of samples at the controller's rate ``fs`` whose one-sided PSD below
``fs/2`` is the sensor's ``noise_psd``, or white noise of its ``noise`` RMS per sample.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from isolator.scenario.arguments import check_public
from isolator.scenario.random_sources import SpectralDensity
from isolator.scenario.sensors import Sensor

__all__ = ["sensor_noise", "shaped_noise"]


def shaped_noise(white: np.ndarray, density: SpectralDensity, sample_rate: float) -> np.ndarray:
    """Gaussian noise of one-sided PSD ``density`` from standard-normal samples, by FFT synthesis.

    Each column of ``white`` (samples at ``sample_rate``, one column per signal) is filtered circularly:
    ``irfft(rfft(w) * sqrt(S(f_k) * fs / 2), n)`` at ``f_k = k fs / n``. White unit-variance samples have the
    flat one-sided PSD ``2 / fs``, so the result has the PSD ``S(f)`` below ``fs / 2`` (a stationary, circular
    sequence of period ``n``); a flat ``S = 2 sigma^2 / fs`` gives ``sigma * w``.

    Parameters
    ----------
    white : ndarray (n,) or (n, signals)
        Standard-normal samples, one per tick.
    density : SpectralDensity
        The one-sided PSD [SI^2/Hz].
    sample_rate : float
        ``fs`` [Hz], the rate of the samples.

    Returns
    -------
    ndarray
        The shape of ``white`` [SI].
    """
    w = np.asarray(white, dtype=float)
    n = w.shape[0]
    f = np.fft.rfftfreq(n, 1.0 / sample_rate)
    gain = np.sqrt(density(f) * sample_rate / 2.0)
    return np.fft.irfft(np.fft.rfft(w, axis=0) * gain.reshape((-1,) + (1,) * (w.ndim - 1)), n, axis=0)


def sensor_noise(sensors: Sequence[Sensor], white: np.ndarray, sample_rate: float) -> np.ndarray:
    """Every sensor's noise at the controller's ticks from one standard-normal draw per tick and sensor.

    Parameters
    ----------
    sensors : sequence of Sensor
        The scenario's sensors: a column of ``white`` each.
    white : ndarray (ticks, sensors)
        Standard-normal samples.
    sample_rate : float
        The controller's rate [Hz] (the ticks' spacing is its inverse).

    Returns
    -------
    ndarray (ticks, sensors)
        [SI]: ``noise * w`` for a sensor with white ``noise`` (RMS per sample), :func:`shaped_noise` of its
        column for one with ``noise_psd``, zero for a noiseless one.
    """
    out = white * np.array([s.noise for s in sensors], dtype=float)
    for i, s in enumerate(sensors):
        if s.noise_psd is not None:
            out[:, i] = shaped_noise(white[:, i], s.noise_psd, sample_rate)
    return out


check_public(globals())
