"""Vibration criteria: the table's one-third-octave velocity from a floor spectrum, and its VC class.

The generic vibration criterion curves (VC-A 50 µm/s, halving per letter to
VC-G 0.78 µm/s) are one-third-octave band RMS velocities that a point must
stay below in every band from 1 to 80 Hz. Here the floor's spectrum (band
velocities or a velocity PSD per world axis) is passed through the
linearised table: the table's velocity PSD in direction ``d`` at a point is
``sum_j |H_dj(f)|^2 S_j(f)``, the floor axes taken as uncorrelated, and each
band's RMS is the square root of its integral over the band.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from isolator.analysis.linear import LinearModel
from isolator.errors import ParameterError, ScenarioError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import FloorSpectrum
from isolator.scenario.random_sources import VC_CLASSES

__all__ = ["VC_CLASSES", "VibrationCriteria", "third_octave_bands", "vibration_criteria"]


_POINTS_PER_BAND = 64


def third_octave_bands(low: float = 1.0, high: float = 80.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Base-10 one-third-octave bands whose centres lie in [low, high] (ANSI S1.11 / IEC 61260).

    Returns
    -------
    centres, lower, upper : ndarray
        [Hz]; exact centres ``10^(n/10)``, edges a factor ``10^(1/20)`` either side.
    """
    for name, value in (("low", low), ("high", high)):
        if isinstance(value, bool) or not isinstance(value, int | float | np.floating) \
                or not (math.isfinite(value) and 0 < value <= 1e6):
            raise ParameterError(f"{name}: must be a band centre in (0, 1e6] Hz, got {value!r}")
    n = np.arange(int(np.ceil(10 * np.log10(low) - 1e-9)), int(np.floor(10 * np.log10(high) + 1e-9)) + 1)
    if n.size == 0:
        raise ParameterError(f"low, high: no one-third-octave band centre between low = {low:g} Hz and high = "
                             f"{high:g} Hz (low must be at most high)")
    centres = 10.0 ** (n / 10)
    return centres, centres * 10 ** (-1 / 20), centres * 10 ** (1 / 20)


@dataclass(frozen=True)
class VibrationCriteria:
    """One-third-octave RMS velocities of the floor and of a table point, and their VC classes.

    Attributes
    ----------
    point : str
        ``mass centre`` or the name of a ``[[points]]`` entry.
    centres : ndarray (nb,)
        Band centres [Hz].
    floor : dict of str to ndarray
        Floor RMS velocity per band [m/s], per axis ``x, y, z``.
    table : dict of str to ndarray
        Table RMS velocity per band at the point [m/s], per direction ``x, y, z``.
    """

    point: str
    centres: np.ndarray
    floor: dict[str, np.ndarray]
    table: dict[str, np.ndarray]

    @staticmethod
    def _class(levels: dict[str, np.ndarray]) -> str:
        worst = max(float(v.max()) for v in levels.values())
        met = [name for name, limit in VC_CLASSES.items() if worst <= limit]
        return met[-1] if met else "above VC-A"

    @property
    def table_class(self) -> str:
        """The best VC class the table point meets in all three directions (or ``above VC-A``)."""
        return self._class(self.table)

    @property
    def floor_class(self) -> str:
        """The best VC class the floor meets on the axes given."""
        return self._class({k: v for k, v in self.floor.items() if v.any()} or self.floor)

    @property
    def table_max(self) -> float:
        """Largest band RMS velocity of the table point [m/s]."""
        return max(float(v.max()) for v in self.table.values())

    def to_dict(self) -> dict[str, Any]:
        return {
            "point": self.point,
            "band_centres_hz": [float(f) for f in self.centres],
            "floor_rms_velocity": {a: [float(x) for x in v] for a, v in self.floor.items()},
            "table_rms_velocity": {a: [float(x) for x in v] for a, v in self.table.items()},
            "floor_class": self.floor_class,
            "table_class": self.table_class,
        }

    def plot(self, title: str = "") -> Any:
        """Floor and table band velocities against the VC curves; returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(9, 6), layout="constrained")
        colours = {"x": "tab:blue", "y": "tab:orange", "z": "tab:green"}
        styles = {"x": "--", "y": ":", "z": "-."}
        for axis, v in self.floor.items():
            if v.any():
                ax.loglog(self.centres, v * 1e6, styles[axis], marker=".", color=colours[axis], label=f"floor {axis}")
        for axis, v in self.table.items():
            ax.loglog(self.centres, np.maximum(v, 1e-30) * 1e6, "-", marker="o", ms=4, color=colours[axis],
                      label=f"table {axis} at {self.point}")
        for name, limit in VC_CLASSES.items():
            ax.axhline(limit * 1e6, color="0.6", lw=0.8)
            ax.text(self.centres[-1] * 1.05, limit * 1e6, name, va="center", fontsize=8, color="0.3")
        top = max(max(float(v.max()) for v in self.floor.values()), VC_CLASSES["VC-A"]) * 1e6 * 3
        table_min = min(float(v.min()) for v in self.table.values())
        bottom = min(VC_CLASSES["VC-G"] * 1e6 / 3, max(table_min * 1e6 / 2, 1e-4))
        ax.set_ylim(bottom, top)
        ax.set_xlim(self.centres[0] / 1.2, self.centres[-1] * 1.4)
        ax.set_xlabel("one-third-octave band centre frequency [Hz]")
        ax.set_ylabel("RMS velocity in the band [µm/s]")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8, loc="lower left")
        ax.set_title(title or f"Vibration criteria: floor {self.floor_class}, table {self.table_class}")
        return fig


def vibration_criteria(
    lin: LinearModel,
    spectrum: FloorSpectrum | None = None,
    point: str | None = None,
    low: float = 1.0,
    high: float = 80.0,
) -> VibrationCriteria:
    """The table's one-third-octave RMS velocity at a point and the VC class it meets.

    Parameters
    ----------
    lin : LinearModel
        From :func:`isolator.analysis.linear.linearise`.
    spectrum : FloorSpectrum, optional
        The floor's spectrum; default: the scenario's ``[ground.spectrum]``.
    point : str, optional
        A ``[[points]]`` name; default: the table's mass centre.
    low, high : float
        Band centres considered [Hz] (the VC curves: 1 to 80 Hz).

    Returns
    -------
    VibrationCriteria
        The band centres [Hz], the floor's and the table's one-third-octave RMS velocities [m/s] and the
        best VC class each meets.

    Raises
    ------
    ScenarioError
        No spectrum given and none in the scenario.
    ParameterError
        An unknown point.
    """
    if spectrum is None:
        ground = lin.scenario.ground
        spectrum = ground.spectrum if ground is not None else None
    if spectrum is None:
        raise ScenarioError("ground.spectrum: no floor spectrum given (pass one, or add [ground.spectrum])")
    if point is None:
        outputs, label = ["x", "y", "z"], "mass centre"
    else:
        names = [p.name for p in lin.scenario.points]
        if point not in names:
            raise ParameterError(f"point: no point named '{point}' in [[points]] (have: {', '.join(names) or 'none'})")
        outputs, label = [f"{point}:{a}" for a in "xyz"], point
    centres, lower, upper = third_octave_bands(low, high)
    # midpoint rule on log-spaced cells that tile each band exactly
    cells = lower[:, None] * (upper / lower)[:, None] ** (np.arange(_POINTS_PER_BAND + 1) / _POINTS_PER_BAND)
    f = np.sqrt(cells[:, :-1] * cells[:, 1:])
    width = np.diff(cells, axis=1)
    flat = f.ravel()
    h = lin.frequency_response(flat, [f"ground:{a}" for a in "xyz"], outputs)  # (nf, 3, 3)
    floor_psd = np.stack([spectrum.velocity_psd(a, flat) for a in "xyz"], axis=1)  # (nf, 3)
    table_psd = np.einsum("fij,fj->fi", np.abs(h) ** 2, floor_psd)

    def band_rms(psd: np.ndarray) -> np.ndarray:
        return np.sqrt(np.sum(psd.reshape(f.shape) * width, axis=1))

    floor = {a: band_rms(floor_psd[:, j]) for j, a in enumerate("xyz") if a in spectrum.values}
    table = {a: band_rms(table_psd[:, j]) for j, a in enumerate("xyz")}
    return VibrationCriteria(label, centres, floor, table)


check_public(globals(), ("VibrationCriteria", "vibration_criteria"))
