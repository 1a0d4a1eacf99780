"""The top's compliance at a point: the datasheet's second curve beside the isolators' transmissibility.

``docs/scenario-format.md``, ``isolator compliance``: the table on its isolators, carriages parked, the floor
still; a unit force at a point along a world axis; the world displacement of a response point (by default the
same) along the same axis [m/N]. On a rigid top it is the rigid-body line (the six modes of the table on its
isolators, then the mass line falling as ``1/f^2``); on a top that bends its elastic modes add their peaks. It
is the linear model's response (:func:`isolator.analysis.frequency_response.state_space_response`, as
``transmissibility --compliance``) to the force's weights on its inputs
(:func:`isolator.analysis.elastic_outputs.point_force_weights`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from isolator.analysis.elastic_outputs import point_force_weights
from isolator.analysis.frequency_response import state_space_response
from isolator.analysis.linear import LinearModel
from isolator.analysis.modes import modes
from isolator.errors import ParameterError
from isolator.scenario.arguments import check_public
from isolator.scenario.rules import closest

__all__ = ["PointCompliance", "point_compliance"]

_AXES = {"x": 0, "y": 1, "z": 2}


@dataclass(frozen=True)
class PointCompliance:
    """A compliance curve between two table points.

    Attributes
    ----------
    point, response : str
        Where the force acts and where the displacement is read.
    axis : str
        The world axis of both (``x``, ``y`` or ``z``).
    frequency_hz : ndarray (nf,)
    response_values : ndarray (nf,) complex
        Displacement per force [m/N].
    mode_frequencies_hz : ndarray
        The table's modes on its isolators [Hz] (marked on the plot), with their names in ``mode_names``.
    """

    point: str
    response: str
    axis: str
    frequency_hz: np.ndarray
    response_values: np.ndarray
    mode_frequencies_hz: np.ndarray
    mode_names: tuple[str, ...]

    @property
    def magnitude(self) -> np.ndarray:
        """[m/N]."""
        return np.abs(self.response_values)

    @property
    def phase_deg(self) -> np.ndarray:
        """[deg]."""
        return np.degrees(np.angle(self.response_values))

    def to_dict(self) -> dict[str, Any]:
        """The contract's JSON: ``frequency_hz``, ``magnitude`` [m/N], ``phase_deg``."""
        return {"frequency_hz": self.frequency_hz.tolist(), "magnitude": self.magnitude.tolist(),
                "phase_deg": self.phase_deg.tolist()}

    def table(self) -> tuple[list[str], np.ndarray]:
        """The CSV's header and columns (nf, 3)."""
        return ["frequency_hz", "magnitude", "phase_deg"], np.column_stack(
            [self.frequency_hz, self.magnitude, self.phase_deg])

    def summary(self) -> str:
        """The peaks of the curve within its band, one line each, strongest first (at most eight)."""
        mag = self.magnitude
        peaks = [k for k in range(1, mag.size - 1) if mag[k] >= mag[k - 1] and mag[k] > mag[k + 1]]
        peaks = sorted(peaks, key=lambda k: -mag[k])[:8]
        head = (f"compliance at {self.response} along {self.axis} per newton at {self.point} along {self.axis}, "
                f"{self.frequency_hz[0]:.4g}-{self.frequency_hz[-1]:.4g} Hz")
        rows = [f"  peak {mag[k]:.4g} m/N at {self.frequency_hz[k]:.4g} Hz" for k in sorted(peaks)]
        return "\n".join([head, *rows] if rows else [head, "  no peak inside the band"])

    def plot(self, title: str = "") -> Any:
        """Log-log magnitude with the modes marked, phase below; returns the figure."""
        import matplotlib.pyplot as plt

        fig, (ax, bx) = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True, height_ratios=(3, 1),
                                     layout="constrained")
        ax.loglog(self.frequency_hz, self.magnitude, color="tab:blue", lw=1.5,
                  label=f"{self.response}:{self.axis} per force at {self.point}:{self.axis}")
        lo, hi = self.frequency_hz[0], self.frequency_hz[-1]
        shown = [(f, n) for f, n in zip(self.mode_frequencies_hz, self.mode_names, strict=True) if lo <= f <= hi]
        labelled = 0.0
        for k, (f, _) in enumerate(shown):
            ax.axvline(f, color="0.6", lw=0.7, ls=":", label="modes on the isolators" if k == 0 else None)
            group = [n for g, n in shown if f <= g < 1.15 * f]
            if f >= 1.15 * labelled:  # one label for modes closer than 15 % (the rigid ones crowd)
                labelled = f
                ax.annotate(", ".join(group), (f, 1.0), xycoords=("data", "axes fraction"), rotation=90,
                            fontsize=7, va="top", ha="right", color="0.35")
        ax.set_ylabel("compliance [m/N]")
        ax.grid(which="both", alpha=0.3)
        ax.legend(loc="lower left", fontsize=8)
        bx.semilogx(self.frequency_hz, self.phase_deg, color="tab:blue", lw=1.0)
        bx.set_ylabel("phase [deg]")
        bx.set_xlabel("frequency [Hz]")
        bx.set_ylim(-185, 185)
        bx.set_yticks([-180, -90, 0, 90, 180])
        bx.grid(which="both", alpha=0.3)
        fig.suptitle(title or "Compliance of the table on its isolators")
        return fig


def _point(lin: LinearModel, name: str, option: str) -> Any:
    names = [p.name for p in lin.scenario.points]
    for p in lin.scenario.points:
        if p.name == name:
            return p
    near = closest(name, names)
    hint = f"; did you mean '{near}'?" if near else ""
    known = ", ".join(names) or "none; add [[points]]"
    raise ParameterError(f"{option}: no point named '{name}'{hint} (points: {known})")


def point_compliance(lin: LinearModel, point: str, axis: str = "z", response: str | None = None,
                     frequency_hz: np.ndarray | None = None) -> PointCompliance:
    """The compliance between two of the scenario's ``[[points]]`` along a world axis.

    Parameters
    ----------
    lin : LinearModel
        The parked table (:func:`isolator.analysis.linear.linearise`).
    point : str
        Where a unit force acts.
    axis : {"x", "y", "z"}
        The world axis of the force and of the displacement read.
    response : str, optional
        Where the displacement is read (default: ``point``, the driving-point compliance).
    frequency_hz : ndarray, optional
        [Hz] (default 2000 from 1 Hz to 2 kHz, log-spaced).

    Returns
    -------
    PointCompliance

    Examples
    --------
    >>> from isolator import linearise, load_scenario
    >>> from isolator.analysis.point_compliance import point_compliance
    >>> c = point_compliance(linearise(load_scenario("paper-table-3-2-budget")), "probe", "z")
    >>> bool(c.magnitude[-1] < c.magnitude[0])
    True
    """
    if axis not in _AXES:
        raise ParameterError(f"--axis: must be x, y or z, got {axis!r}")
    source = _point(lin, point, "--point")
    target = _point(lin, response if response is not None else point, "--response")
    f = np.geomspace(1.0, 2000.0, 2000) if frequency_hz is None else np.asarray(frequency_hz, dtype=float)
    direction = np.eye(3)[_AXES[axis]]
    weights = point_force_weights(lin, source.position, direction, getattr(source, "feet", None),
                                  f"points ({source.name})")
    used = np.nonzero(weights)[0]
    names = [lin.input_names[i] for i in used]
    h = state_space_response(lin.system, f, names, [f"{target.name}:{axis}"])  # (nf, 1, inputs)
    values = h[:, 0, :] @ weights[used]
    m = modes(lin)
    return PointCompliance(source.name, target.name, axis, f, values, m.frequencies_hz, m.dominant)


check_public(globals(), ("PointCompliance", "point_compliance"))
