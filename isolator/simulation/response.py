"""The result of a transient simulation: signals, metrics, plot and CSV."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, cast

import numpy as np

from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import SIGNALS
from isolator.scenario.readable import clean_time, without_dust
from isolator.scenario.sensors import Sensor
from isolator.simulation.elastic_figure import plot_elastic
from isolator.simulation.leveling import PneumaticResult, leveling_summary, plot_leveling
from isolator.simulation.points import PointSet
from isolator.simulation.response_csv import response_dict, write_response_csv
from isolator.simulation.settling import Band, SettlingResult
from isolator.simulation.window_settling import WindowResult, moves_per_hour, plot_windows

__all__ = ["Response"]

_UNITS = {"x": "µm", "y": "µm", "z": "µm", "rx": "µrad", "ry": "µrad", "rz": "µrad"}


@dataclass(frozen=True)
class Response:
    """Table motion over time for one scenario and model.

    Attributes
    ----------
    name : str
        Scenario name.
    model : str
        "exact" or "paper".
    t : ndarray (N,)
        Sample times [s].
    signals : ndarray (6, N)
        ``x, y, z`` [m] and ``rx, ry, rz`` [rad]: displacement of the table's
        mass centre from its initial static equilibrium and rotation vector of
        R(t) R0^T (``docs/scenario-format.md``).
    carriage_names : tuple of str
    q : ndarray (n, N)
        Carriage coordinates [m].
    stop_time : float
        When the last carriage stops [s] (inf: never), a time on the run's clock.
    move_start : float
        When the first carriage starts moving [s]; the move time is
        ``stop_time - move_start``, not the stop time.
    final : ndarray (6,) or None
        The signals' static equilibrium values with the carriages at their
        final positions (None when a carriage never stops).
    settling : dict of str to SettlingResult
        Per signal: settling time [s] (or None with a reason), peak, band.
    band : Band
        The band the settling times are measured in, resolved on this run (its
        six half-widths); :meth:`with_band` measures the run in another.
    state_history : ndarray (N, n_states) or callable
        The model's state at the samples, or a function computing it (read
        :attr:`states`).
    actuator_names : tuple of str
    actuator_forces : ndarray (n_actuators, N)
        Forces the actuators applied [N] (after saturation and lag).
    point_set : PointSet or None
        The scenario's ``[[points]]`` (read their motion with :meth:`point`).
    window_result : WindowResult or callable or None
        With ``[[windows]]``: the window settling (read :attr:`windows`).
    sensor_set : tuple of Sensor
        The scenario's ``[[sensors]]`` (read their signals with :meth:`sensor`, :attr:`sensor_signals`).
    pneumatic_result : PneumaticResult or callable or None
        Pressures, heights, leveling times of a pneumatic run, or their function (read :attr:`pneumatic`).
    deadbands : dict of str to float
        Each leveling group's valve dead zone [m] (pneumatic runs).
    remeasure : callable or None
        Measures the run again in another band (what :meth:`with_band` calls).
    point_history : ndarray or None
        (3 n_points, N): the ``[[points]]``' world displacement [m] (read with :meth:`point`).
    sensor_history : ndarray or callable or None
        (n_sensors, N): the sensors' readings [SI], or their function (read :attr:`sensor_signals`).
    """

    name: str
    model: str
    t: np.ndarray
    signals: np.ndarray
    carriage_names: tuple[str, ...]
    q: np.ndarray
    stop_time: float
    final: np.ndarray | None
    settling: dict[str, SettlingResult]
    band: Band
    state_history: np.ndarray | Callable[[], np.ndarray] = field(repr=False)
    actuator_names: tuple[str, ...] = ()
    actuator_forces: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)), repr=False)
    pneumatic_result: PneumaticResult | Callable[[], PneumaticResult] | None = field(default=None, repr=False)
    deadbands: dict[str, float] = field(default_factory=dict, repr=False)
    move_start: float = 0.0
    remeasure: Callable[[Band], tuple[dict[str, SettlingResult], Band, Any]] | None = field(
        default=None, repr=False, compare=False)
    point_set: PointSet | None = field(default=None, repr=False)
    window_result: WindowResult | Callable[[], WindowResult] | None = field(default=None, repr=False, compare=False)
    point_history: np.ndarray | None = field(default=None, repr=False, compare=False)
    sensor_set: tuple[Sensor, ...] = field(default=(), repr=False)
    sensor_history: np.ndarray | Callable[[], np.ndarray] | None = field(default=None, repr=False, compare=False)

    def _evaluated(self, name: str) -> Any:
        """The field ``name``, computed on first use: a callable there is called once and replaced by its value."""
        value = getattr(self, name)
        if callable(value):
            value = value()
            object.__setattr__(self, name, value)
        return value

    @property
    def point_names(self) -> tuple[str, ...]:
        """The scenario's ``[[points]]`` names."""
        return () if self.point_set is None else self.point_set.names

    @property
    def point_signals(self) -> np.ndarray:
        """Every point's world displacement from its position at the initial equilibrium (points, 3, N) [m]
        (exact rotation of the lever arm); computed from the states on first use."""
        if self.point_history is None:
            object.__setattr__(self, "point_history", np.zeros((0, 3, self.t.size)) if self.point_set is None
                               or not self.point_set.names else self.point_set.displacements(self.states))
        return cast(np.ndarray, self.point_history)

    @property
    def sensor_names(self) -> tuple[str, ...]:
        """The scenario's ``[[sensors]]`` names."""
        return tuple(s.name for s in self.sensor_set)

    @property
    def sensor_signals(self) -> np.ndarray:
        """Every sensor's noise-free signal (sensors, N) in its SI quantity (the columns ``s:<sensor>``)."""
        return np.zeros((0, self.t.size)) if self.sensor_history is None else self._evaluated("sensor_history")

    def sensor(self, name: str) -> np.ndarray:
        """The sensor ``name``'s signal (N,) [m, m/s or m/s^2] (a KeyError names the known ones)."""
        return self.sensor_signals[_index_of(name, self.sensor_names, "sensor")]

    def point(self, name: str, elastic: bool = False) -> np.ndarray:
        """The point ``name``'s world displacement ``x, y, z`` from its initial position (3, N) [m]; ``elastic``:
        its elastic translation ``ex, ey, ez`` from the initial equilibrium (table axes; 0 on a rigid top)."""
        if self.point_set is None:
            raise KeyError(f"point: unknown '{name}' (this run has no points)")
        i = self.point_set.index(name)
        return self.point_set.elastic(self.states)[i] if elastic else self.point_signals[i]

    @property
    def windows(self) -> WindowResult | None:
        """With ``[[windows]]``: each window's settling time after the stop, read on a >= 1 kHz grid of the
        dense output (:mod:`isolator.simulation.window_settling`); computed on first use. Else None."""
        result: WindowResult | None = self._evaluated("window_result")
        return result

    @property
    def window_settling_time(self) -> list[float | None]:
        """Per ``[[windows]]`` block, in order: settling time after the stop [s] (None: not shown)."""
        return [] if self.windows is None else list(self.windows.settling_time)

    @property
    def window_settling_time_max(self) -> float | None:
        """The largest window settling time [s]; None without windows or when one is not shown."""
        return None if self.windows is None else self.windows.settling_time_max

    @property
    def moves_per_hour(self) -> float | None:
        """Moves per hour [1/h] of a machine repeating this move and waiting after each until every window
        holds: ``3600 / (stop_time - move_start + window_settling_time_max)``; None without windows."""
        if self.windows is None or not math.isfinite(self.stop_time):
            return None
        return moves_per_hour(self.stop_time - self.move_start, self.window_settling_time_max)

    def plot_windows(self, title: str = "") -> Any:
        """Each window's point deviation from its settled position against time, the window shaded.

        Returns
        -------
        matplotlib.figure.Figure

        Raises
        ------
        ValueError
            For a run without ``[[windows]]``.
        """
        if self.windows is None:
            raise ValueError("plot_windows: the scenario has no [[windows]]")
        return plot_windows(self.windows, self.stop_time,
                            title or f"{self.name}: settling windows ({self.model} model)")

    def with_band(self, band: Band) -> Response:
        """The same run measured in another settling band (as if given ``band`` from the start)."""
        if self.remeasure is None:
            raise ValueError("with_band: this response keeps no way to measure it again")
        settling, resolved, pneumatic = self.remeasure(band)
        return replace(self, settling=settling, band=resolved, pneumatic_result=pneumatic)

    @property
    def pneumatic(self) -> PneumaticResult | None:
        """Pneumatic runs: pressures, sensor heights, leveling and the settling about the leveling table
        (:mod:`isolator.simulation.leveling`); computed on first use. None for spring-damper tables."""
        result: PneumaticResult | None = self._evaluated("pneumatic_result")
        return result

    @property
    def leveling_time(self) -> dict[str, float | None]:
        """Pneumatic runs: per group with a valve, when it stays level after the stop [s] (else empty)."""
        return {} if self.pneumatic is None else dict(self.pneumatic.leveling_time)

    @property
    def dynamic_settling_time_max(self) -> float | None:
        """Pneumatic runs: settling of the motion about the slowly leveling table [s]
        (:mod:`isolator.simulation.leveling`); otherwise the ordinary settling time."""
        return self.settling_time_max if self.pneumatic is None else self.pneumatic.dynamic_settling_time_max

    @property
    def states(self) -> np.ndarray:
        """The model's state at the samples (N, n_states), for checks; evaluated on first use."""
        history: np.ndarray = self._evaluated("state_history")
        return history

    @property
    def signal_names(self) -> tuple[str, ...]:
        return SIGNALS

    def signal(self, name: str) -> np.ndarray:
        """One table signal by name (``x`` ... ``rz``)."""
        if name not in SIGNALS:
            raise KeyError(f"signal: unknown '{name}' (one of {', '.join(SIGNALS)})")
        return self.signals[SIGNALS.index(name)]

    @property
    def peak(self) -> dict[str, float]:
        """max |s| over the run, per signal [m or rad]."""
        return {k: r.peak for k, r in self.settling.items()}

    @property
    def settling_time(self) -> dict[str, float | None]:
        """Settling time after the stop per signal [s]; None where the run cannot show it."""
        return {k: r.time for k, r in self.settling.items()}

    @property
    def settling_time_max(self) -> float | None:
        """The scenario's settling time: the largest over the six signals [s]."""
        times = list(self.settling_time.values())
        if any(v is None for v in times):
            return None
        return max(times)  # type: ignore[type-var]

    def to_dict(self) -> dict[str, Any]:
        """Summary as plain JSON-ready types (the ``isolator simulate --json`` object)."""
        return response_dict(self)

    def to_csv(self, path: str | Path) -> Path:
        """Write ``t,x,y,z,rx,ry,rz,q:<carriage>...`` [s, m, rad], then ``<point>:x,<point>:y,<point>:z``
        per ``[[points]]`` entry [m], ``s:<sensor>`` per ``[[sensors]]`` entry (its SI quantity, noise-free),
        ``f:<actuator>...`` [N] when actuators applied forces, then for pneumatic runs ``p:<isolator>...``
        [Pa] and ``h:<group>...`` [m], to ``path``."""
        return write_response_csv(self, path)

    def summary(self) -> str:
        """A text table of peaks, final values and settling times per signal."""
        lines = [
            f"{self.name} ({self.model} model): "
            + (f"the carriages move from t = {self.move_start:.4g} s and never stop (a sine)"
               if math.isinf(self.stop_time) else
               f"the carriages move from t = {self.move_start:.4g} s to their stop at t = {self.stop_time:.4g} s "
               f"(move time {clean_time(self.stop_time - self.move_start):.4g} s)"),
            f"{'signal':>6}  {'peak':>12}  {'final':>12}  {'settling [s]':>12}",
        ]
        for i, k in enumerate(SIGNALS):
            r = self.settling[k]
            scale = 1e6
            unit = _UNITS[k]
            # rounding dust (below 1e-12 of the signal's own size) reads as 0
            final = "-" if self.final is None else \
                f"{float(without_dust(self.final[i], max(r.peak, abs(self.final[i])))) * scale:.4g} {unit}"
            st = "-" if r.time is None else f"{r.time:.4g}"
            lines.append(f"{k:>6}  {r.peak * scale:>7.4g} {unit:<4}  {final:>12}  {st:>12}")
        tmax = self.settling_time_max
        lines.append(
            "settling time (largest): "
            + (f"{tmax:.4g} s" if tmax is not None else "not available")
        )
        lines.append(self.band.describe())
        for k, r in self.settling.items():
            if r.reason and r.reason != "does not move":
                lines.append(f"  {k}: {r.reason}")
        if self.windows is not None:
            lines += self.windows.summary_lines()
        if self.pneumatic is not None:
            lines += leveling_summary(self.pneumatic)
        return "\n".join(lines)

    def plot_leveling(self, title: str = "") -> Any:
        """Pneumatic runs: chamber pressures and sensor heights through the move and the leveling.

        Returns
        -------
        matplotlib.figure.Figure

        Raises
        ------
        ValueError
            For a spring-damper run.
        """
        result = self.pneumatic
        if result is None:
            raise ValueError("plot_leveling: not a pneumatic run")
        return plot_leveling(result, self.t, self.stop_time, self.deadbands,
                             title or f"{self.name}: air springs and leveling")

    def plot(self, fig: Any = None, label: str | None = None) -> Any:
        """Rotations (left) and translations (right) over time, as in the paper's Fig. 3.5.

        Returns
        -------
        matplotlib.figure.Figure
        """
        import matplotlib.pyplot as plt

        zoom = elastic = None
        if fig is None:
            bends = self.point_set is not None and bool(self.point_set.elastic_columns)  # a top that bends
            fig = plt.figure(figsize=(11, 13 if bends else 10), constrained_layout=True)
            grid = fig.add_gridspec(4 + bends, 2, height_ratios=(1, 1, 1, 1.1, 1.1)[:4 + bends])
            first = fig.add_subplot(grid[0, 0])
            for row, col in ((0, 1), (1, 0), (1, 1), (2, 0), (2, 1)):
                fig.add_subplot(grid[row, col], sharex=first)
            zoom = fig.add_subplot(grid[3, :]) if self.final is not None and math.isfinite(self.stop_time) else None
            elastic = fig.add_subplot(grid[4, :], sharex=first) if bends else None
        axes = np.asarray(fig.axes[:6]).reshape(3, 2)
        for row in range(3):
            for col, name in enumerate((SIGNALS[3 + row], SIGNALS[row])):
                ax = axes[row, col]
                i = SIGNALS.index(name)
                ax.plot(self.t, self.signals[i] * 1e6, lw=1.0, label=label or self.model)
                r = self.settling[name]
                if self.final is not None and math.isfinite(self.stop_time):
                    f = self.final[i] * 1e6
                    ax.axvline(self.stop_time, color="0.5", ls=":", lw=1)
                    ax.fill_between([self.stop_time, self.t[-1]], f - r.band * 1e6, f + r.band * 1e6,
                                    color="tab:green", alpha=0.15, lw=0)
                    if r.time is not None and r.time > 0:
                        ax.axvline(self.stop_time + r.time, color="tab:red", ls="--", lw=1)
                ax.set_ylabel(f"{name} [{_UNITS[name]}]")
                ax.grid(True, alpha=0.3)
        for ax in axes[-1]:
            ax.set_xlabel("time [s]")
        axes[0, 0].set_title("rotations")
        axes[0, 1].set_title("translations")
        tmax = self.settling_time_max
        st = f"settling {tmax:.3g} s after the stop" if tmax is not None else "settling: n/a"
        fig.suptitle(f"{self.name}: table response ({self.model} model); {st}\nband: {self.band.how()} (shaded)")
        handles = [
            plt.Line2D([], [], color="tab:blue", label="table motion"),
            plt.Rectangle((0, 0), 1, 1, color="tab:green", alpha=0.15, label=f"settling band ({self.band.kind})"),
            plt.Line2D([], [], color="0.5", ls=":", label="carriages stop"),
            plt.Line2D([], [], color="tab:red", ls="--", label="settled"),
        ]
        if label is None:
            axes[0, 1].legend(handles=handles, loc="upper left", fontsize=8)
        if zoom is not None:
            self._plot_residual(zoom)
        if elastic is not None and self.point_set is not None:
            plot_elastic(elastic, self.t, self.point_set.names, self.point_set.elastic(self.states), self.stop_time)
        return fig

    def _plot_residual(self, ax: Any) -> None:
        """After the stop, each signal's distance from its final value in units of its band (settled below 1)."""
        if self.final is None:
            return
        after = self.t >= self.stop_time
        for i, name in enumerate(SIGNALS):
            band = self.settling[name].band
            if band <= 0 or self.settling[name].reason == "does not move":
                continue
            ax.semilogy(self.t[after] - self.stop_time, np.abs(self.signals[i, after] - self.final[i]) / band,
                        lw=1.0, label=name)
        ax.axhline(1.0, color="k", ls="--", lw=1.2, label="band edge")
        ax.set_ylim(1e-3, None)
        ax.set_xlabel("time after the carriages stop [s]")
        ax.set_ylabel("|signal - final| / band [-]")
        ax.set_title("residual vibration after the stop, in units of each signal's settling band (settled below 1)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(loc="upper right", fontsize=8, ncol=7)


check_public(globals(), ("Response"))


def _index_of(name: str, names: tuple[str, ...], what: str) -> int:
    if name not in names:
        raise KeyError(f"{what}: unknown '{name}' ({what}s: {', '.join(names) or 'none'})")
    return names.index(name)
