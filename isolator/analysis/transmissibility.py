"""Transmissibility (floor to table) and compliance (force to table) of the parked table."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from isolator.analysis.linear import FORCE_INPUTS, GROUND_INPUTS
from isolator.analysis.signal_names import signals, to_control
from isolator.model.equilibrium import DOF_NAMES
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario

if TYPE_CHECKING:  # python-control takes most of a second to import: imported where used
    import control

__all__ = ["FrequencyResponse", "LinearSystem", "compliance", "default_frequencies", "transmissibility"]


@runtime_checkable
class LinearSystem(Protocol):
    """What a frequency response needs: a :class:`~isolator.analysis.linear.LinearModel`, or a closed loop
    around one (``controllers.feedback.ClosedLoop``)."""

    @property
    def scenario(self) -> Scenario: ...

    @property
    def eigenvalues(self) -> np.ndarray: ...

    def frequency_response(self, frequency_hz: np.ndarray, inputs: Sequence[str] | None = None,
                           outputs: Sequence[str] | None = None) -> np.ndarray: ...


def default_frequencies(lin: LinearSystem, count: int = 1000) -> np.ndarray:
    """Log-spaced frequencies [Hz] from a decade below the slowest mode (at most 0.1 Hz)
    to a decade above the fastest (at least 100 Hz)."""
    f_modes = np.abs(lin.eigenvalues) / (2 * np.pi)
    f_modes = f_modes[f_modes > 1e-9 * max(1.0, float(f_modes.max(initial=0.0)))]  # not the air-mass integrators
    lo = min(0.1, float(f_modes.min()) / 10) if f_modes.size else 0.1
    hi = max(100.0, float(f_modes.max()) * 10) if f_modes.size else 100.0
    return np.logspace(np.log10(lo), np.log10(hi), count)


@dataclass(frozen=True)
class FrequencyResponse:
    """A 6x6 frequency response of the table: transmissibility or compliance.

    Attributes
    ----------
    kind : {"transmissibility", "compliance"}
    frequency_hz : ndarray (nf,)
        [Hz].
    response : ndarray (nf, 6, 6) complex
        Row: table signal ``x .. rz`` at the mass centre; column: the floor's
        motion along / about the same axes (transmissibility, [m/m], [rad/rad],
        cross terms [m/rad], [rad/m]) or the force / moment at the mass centre
        (compliance, [m/N], [rad/(N m)], ...).
    inputs : tuple of str
        Input names of the columns.
    lin : LinearModel or ClosedLoop
        The system the response is of (used to refine peaks exactly).
    """

    kind: str
    frequency_hz: np.ndarray
    response: np.ndarray
    inputs: tuple[str, ...]
    lin: LinearSystem

    def _same_axis(self, axis: str) -> int:
        if axis not in DOF_NAMES:
            raise ValueError(f"axis: must be one of {', '.join(DOF_NAMES)}, got '{axis}'")
        return DOF_NAMES.index(axis)

    def magnitude(self, axis: str) -> np.ndarray:
        """|H| from the same-axis input to the table signal ``axis``."""
        k = self._same_axis(axis)
        return np.abs(self.response[:, k, k])

    def _exact(self, axis: str, f: float) -> float:
        k = self._same_axis(axis)
        h = self.lin.frequency_response(np.array([f]), [self.inputs[k]], [DOF_NAMES[k]])
        return float(np.abs(h[0, 0, 0]))

    def peak(self, axis: str) -> tuple[float, float]:
        """Largest same-axis |H| and its frequency [Hz], refined between grid points."""
        mag = self.magnitude(axis)
        i = int(np.argmax(mag))
        f = self.frequency_hz
        if 0 < i < f.size - 1:
            res = minimize_scalar(
                lambda x: -self._exact(axis, 10**x),
                bounds=(np.log10(f[i - 1]), np.log10(f[i + 1])),
                method="bounded",
                options={"xatol": 1e-10},
            )
            if -res.fun >= mag[i]:
                return float(-res.fun), float(10**res.x)
        return float(mag[i]), float(f[i])

    def isolation_onset(self, axis: str) -> float | None:
        """Frequency [Hz] above which the same-axis transmissibility stays below 1.

        None when it does not fall below 1 within the frequencies computed
        (or for a compliance, which has no such frequency).
        """
        if self.kind != "transmissibility":
            return None
        mag = self.magnitude(axis)
        above = mag >= 1.0
        if not above.any():
            return float(self.frequency_hz[0])
        last = int(np.flatnonzero(above)[-1])
        if last == mag.size - 1:
            return None
        lo, hi = np.log10(self.frequency_hz[last]), np.log10(self.frequency_hz[last + 1])
        return float(10 ** brentq(lambda x: self._exact(axis, 10**x) - 1.0, lo, hi, xtol=1e-12))

    def frd(self) -> control.FrequencyResponseData:
        """The 6x6 response as a python-control ``FrequencyResponseData`` (omega in rad/s)."""
        import control  # python-control takes most of a second to import: only when needed
        data = np.moveaxis(self.response, 0, -1)
        return control.frd(
            data, 2 * np.pi * self.frequency_hz, inputs=signals(self.inputs), outputs=list(DOF_NAMES),
            name=to_control(f"{self.kind} of {self.lin.scenario.name}"),
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``frequency_hz``, ``magnitude`` (same-axis, keyed ``x .. rz``), and per axis
        ``peak``, ``peak_frequency_hz`` and (transmissibility) ``isolation_above_hz``."""
        out: dict[str, Any] = {
            "kind": self.kind,
            "frequency_hz": [float(f) for f in self.frequency_hz],
            "magnitude": {a: [float(v) for v in self.magnitude(a)] for a in DOF_NAMES},
        }
        peaks = {a: self.peak(a) for a in DOF_NAMES}
        out["peak"] = {a: p[0] for a, p in peaks.items()}
        out["peak_frequency_hz"] = {a: p[1] for a, p in peaks.items()}
        if self.kind == "transmissibility":
            out["isolation_above_hz"] = {a: self.isolation_onset(a) for a in DOF_NAMES}
        return out

    def summary(self) -> str:
        """A text table of peaks (and isolation onset) per axis."""
        unit = {"transmissibility": ("m/m", "rad/rad"), "compliance": ("m/N", "rad/(N m)")}[self.kind]
        head = f"axis  peak {self.kind:<16}  at [Hz]"
        if self.kind == "transmissibility":
            head += "   isolates above [Hz]"
        lines = [head]
        for a in DOF_NAMES:
            value, f = self.peak(a)
            u = unit[1] if a.startswith("r") else unit[0]
            line = f"{a:>4}  {value:>10.4g} {u:<13}  {f:>7.4g}"
            if self.kind == "transmissibility":
                onset = self.isolation_onset(a)
                line += f"   {onset:>10.4g}" if onset is not None else "   (not within range)"
            lines.append(line)
        return "\n".join(lines)

    def plot(self, title: str = "") -> Any:
        """Bode plot of the same-axis responses (python-control conventions: log-log magnitude,
        phase in degrees, frequency in Hz); translations left, rotations right. Returns the figure."""
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(2, 2, figsize=(11, 7), sharex=True, layout="constrained",
                                 gridspec_kw={"height_ratios": [2, 1]})
        f = self.frequency_hz
        for col, group in enumerate((DOF_NAMES[:3], DOF_NAMES[3:])):
            for a in group:
                k = DOF_NAMES.index(a)
                h = self.response[:, k, k]
                (line,) = axes[0, col].loglog(f, np.abs(h), label=a)
                axes[1, col].semilogx(f, np.degrees(np.unwrap(np.angle(h))), color=line.get_color())
                value, fp = self.peak(a)
                axes[0, col].plot([fp], [value], "o", color=line.get_color(), ms=4)
            if self.kind == "transmissibility":
                axes[0, col].axhline(1.0, color="0.5", lw=0.8, ls="--", label="|T| = 1")
                unit = "[m/m]" if col == 0 else "[rad/rad]"
                axes[0, col].set_ylabel(f"|transmissibility| {unit}")
            else:
                axes[0, col].set_ylabel("|compliance| " + ("[m/N]" if col == 0 else "[rad/(N m)]"))
            axes[0, col].set_title(("translations" if col == 0 else "rotations") + " (dots: peaks)")
            axes[0, col].legend(fontsize=9)
            axes[1, col].set_ylabel("phase [deg]")
            axes[1, col].set_xlabel("frequency [Hz]")
            for ax in axes[:, col]:
                ax.grid(True, which="both", alpha=0.3)
        source = "floor motion" if self.kind == "transmissibility" else "force / moment at the mass centre"
        fig.suptitle(title or f"{self.kind.capitalize()}: same-axis {source} to table motion "
                     f"({self.lin.scenario.name})")
        return fig


def transmissibility(lin: LinearSystem, frequency_hz: np.ndarray | None = None) -> FrequencyResponse:
    """Floor motion to table motion at the mass centre, the full 6x6 matrix.

    Parameters
    ----------
    lin : LinearModel or ClosedLoop
        The linearised table (:func:`linearise`), or a closed loop
        (:func:`controllers.feedback.closed_loop`).
    frequency_hz : ndarray, optional
        [Hz]; default :func:`default_frequencies`.

    Returns
    -------
    FrequencyResponse
        ``response`` (6, 6, frequencies), complex: table x, y, z [m] and rx, ry, rz [rad] per floor x, y, z
        [m] and rx, ry, rz [rad] (dimensionless on the diagonal).

    Examples
    --------
    >>> from isolator import linearise, load_scenario, transmissibility
    >>> t = transmissibility(linearise(load_scenario("paper-table-3-2")))
    >>> peak, frequency = t.peak("z")
    >>> round(peak, 2), round(frequency, 2)
    (4.69, 3.4)
    >>> round(t.isolation_onset("z"), 2)
    4.85
    """
    return _response(lin, "transmissibility", GROUND_INPUTS, frequency_hz)


def compliance(lin: LinearSystem, frequency_hz: np.ndarray | None = None) -> FrequencyResponse:
    """Force and moment at the mass centre to table motion, the full 6x6 matrix.

    Parameters
    ----------
    lin : LinearModel or ClosedLoop
        The linearised table (:func:`linearise`), or a closed loop
        (:func:`controllers.feedback.closed_loop`).
    frequency_hz : ndarray, optional
        [Hz]; default :func:`default_frequencies`.

    Returns
    -------
    FrequencyResponse
        ``response`` (6, 6, frequencies), complex: table x, y, z [m] and rx, ry, rz [rad] per force x, y, z
        [N] and torque about x, y, z [N m] at the mass centre.
    """
    return _response(lin, "compliance", FORCE_INPUTS, frequency_hz)


def _response(
    lin: LinearSystem, kind: str, inputs: tuple[str, ...], frequency_hz: np.ndarray | None
) -> FrequencyResponse:
    f = default_frequencies(lin) if frequency_hz is None else np.asarray(frequency_hz, dtype=float)
    return FrequencyResponse(kind, f, lin.frequency_response(f, inputs, DOF_NAMES), inputs, lin)


check_public(globals(), ("FrequencyResponse", "compliance", "transmissibility"))
