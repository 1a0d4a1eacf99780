"""Floor motion: prescribed profiles per axis and floor vibration spectra."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from isolator.scenario.arguments import check_public
from isolator.scenario.profiles import Profile

__all__ = ["SIGNALS", "FloorSpectrum", "Ground"]

#: names of the six table signals, in order
SIGNALS: tuple[str, ...] = ("x", "y", "z", "rx", "ry", "rz")


@dataclass(frozen=True)
class FloorSpectrum:
    """A floor vibration spectrum, per world axis.

    Attributes
    ----------
    kind : {"third-octave", "psd"}
        ``third-octave``: RMS velocity [m/s] in the one-third-octave band of each
        centre frequency; ``psd``: velocity power spectral density [(m/s)^2/Hz].
    frequency : ndarray
        Band centres or PSD frequencies [Hz], increasing.
    values : dict of str to ndarray
        Per axis ``x``, ``y``, ``z`` (axes not given have no floor motion).
    """

    kind: str
    frequency: np.ndarray
    values: dict[str, np.ndarray]

    @property
    def edges(self) -> np.ndarray:
        """Frequencies [Hz] where the velocity PSD may jump or bend: a third-octave spectrum's band edges (the
        geometric means of adjacent centres, and as far beyond the first and last), a PSD's points."""
        fs = np.asarray(self.frequency, dtype=float)
        if self.kind == "psd":
            return fs
        inner = np.sqrt(fs[:-1] * fs[1:])
        return np.concatenate([[fs[0] ** 2 / inner[0]], inner, [fs[-1] ** 2 / inner[-1]]])

    def velocity_psd(self, axis: str, frequency_hz: np.ndarray) -> np.ndarray:
        """The floor's one-sided velocity PSD [(m/s)^2/Hz] along world ``axis`` at ``frequency_hz`` [Hz]; zero
        outside the data and on axes not given.

        A PSD is interpolated log-log between its points (linearly where it holds zeros); a third-octave
        spectrum's band RMS is spread evenly over each whole band, edges at :attr:`edges`.
        """
        f = np.asarray(frequency_hz, dtype=float)
        if axis not in self.values:
            return np.zeros_like(f)
        fs, vs = np.asarray(self.frequency, dtype=float), np.asarray(self.values[axis], dtype=float)
        if self.kind == "psd":
            out = np.zeros_like(f)
            inside = (f >= fs[0]) & (f <= fs[-1])
            if np.all(vs > 0):
                out[inside] = np.exp(np.interp(np.log(f[inside]), np.log(fs), np.log(vs)))
            else:
                out[inside] = np.interp(f[inside], fs, vs)
            return out
        edges = self.edges
        lower, upper = edges[:-1], edges[1:]
        density = vs**2 / (upper - lower)
        idx = np.searchsorted(upper, f, side="left")
        return np.where((f >= lower[0]) & (f <= upper[-1]), density[np.clip(idx, 0, fs.size - 1)], 0.0)

    def band_rms(self) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """The RMS velocity [m/s] in each one-third-octave band and its centre [Hz]: a third-octave spectrum's
        own values; a PSD integrated over the bands (centres ``10^(n/10)`` Hz) its frequencies reach, each band
        cut to them. Overflow gives infinity, not an error."""
        fs = np.asarray(self.frequency, dtype=float)
        if self.kind != "psd":
            return fs, {a: np.asarray(v, dtype=float) for a, v in self.values.items()}
        n = np.arange(round(10 * np.log10(fs[0])), round(10 * np.log10(fs[-1])) + 1)
        low = np.clip(10.0 ** ((n - 0.5) / 10), fs[0], fs[-1])
        high = np.clip(10.0 ** ((n + 0.5) / 10), fs[0], fs[-1])
        grid = np.geomspace(low, np.maximum(high, low), 33, axis=-1)  # (bands, 33)
        with np.errstate(over="ignore", invalid="ignore"):
            rms = {a: np.sqrt(np.trapezoid(self.velocity_psd(a, grid), grid, axis=-1)) for a in self.values}
        return 10.0 ** (n / 10), rms


@dataclass(frozen=True)
class Ground:
    """Prescribed floor motion and an optional floor vibration spectrum.

    Attributes
    ----------
    motion : dict of str to Profile
        Floor translation [m] along ``x, y, z`` and rotation [rad] about ``rx, ry, rz``
        (world axes, rotations about the world origin), each a profile of time.
    spectrum : FloorSpectrum or None
    """

    motion: dict[str, Profile] = field(default_factory=dict)
    spectrum: FloorSpectrum | None = None

    def displacement(self, t: np.ndarray, piece_time: np.ndarray | None = None) -> np.ndarray:
        """Floor displacement and its rate, shape ``(*t.shape, 12)``: 6 values then 6 rates."""
        t = np.asarray(t, dtype=float)
        out = np.zeros((*t.shape, 12))
        for k, axis in enumerate(SIGNALS):
            if axis in self.motion:
                q, v, _ = self.motion[axis].evaluate(t, piece_time)
                out[..., k] = q
                out[..., 6 + k] = v
        return out

    @property
    def breakpoints(self) -> tuple[float, ...]:
        """Times [s] where a floor acceleration may jump."""
        return tuple(sorted({b for p in self.motion.values() for b in p.breakpoints}))


check_public(globals(), ("FloorSpectrum", "Ground"))
