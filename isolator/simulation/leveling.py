"""What a pneumatic run reports besides the table's motion: pressures, sensor heights, leveling.

``docs/scenario-format.md`` ("Pneumatic isolators and leveling", Results)
fixes the columns ``p:<isolator>`` (spring chamber gauge pressure [Pa]) and
``h:<group>`` (sensor height [m], groups with a valve) and each group's
leveling time: after the stop, from when ``|h|`` stays within 1.1 x the
group's dead band.

The table's *dynamic* settling is measured about the slowly leveling table:
at each sample after the stop, the quasi-static pose is the static
equilibrium of the table with the carriages parked and every group holding
the air it has at that instant (``sum p^(1/n) V`` over its chambers, the air
mass times ``R T`` when isothermal), valves shut. The dynamic signals are the
table signals minus that pose; their settling time uses the run's 5 % bands
(a fraction of each signal's peak, or the absolute band) around zero. While
the valves move air the quasi-static pose drifts with the leveling, and the
dynamic motion is what oscillates about it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.interpolate import CubicSpline

from isolator.model.equilibrium import Equilibrium, air_in_groups, closed_rest_states
from isolator.model.variants import Model
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.scenario.pneumatic import PneumaticIsolator
from isolator.simulation.band import Band
from isolator.simulation.settling import SettlingResult, settling_metrics

__all__ = [
    "LEVEL_BAND",
    "PneumaticResult",
    "leveling_summary",
    "leveling_time",
    "metric_grid",
    "plot_leveling",
    "pneumatic_result",
    "quasi_static_signals",
    "sensor_heights",
    "valve_note",
]

#: a group is level once |h| stays within this many dead bands
LEVEL_BAND = 1.1
#: interval [s] at which the quasi-static pose is solved (a cubic spline between)
QUASI_STATIC_STEP = 0.01
#: the least rate [Hz] at which leveling times and the settling about the leveling table are read
METRIC_RATE = 1000.0


def metric_grid(samples: np.ndarray, end: float) -> np.ndarray:
    """The output samples and a grid of :data:`METRIC_RATE` up to ``end`` [s], merged (times [s]; the samples
    alone when they are as dense; grid times within 1e-9 s of a sample dropped)."""
    if samples.size > 1 and float(np.max(np.diff(samples))) <= 1.0 / METRIC_RATE * (1 + 1e-9):
        return samples
    extra = np.arange(0.0, end, 1.0 / METRIC_RATE)
    right = np.clip(np.searchsorted(samples, extra), 0, samples.size - 1)
    left = np.clip(right - 1, 0, samples.size - 1)
    near = np.minimum(np.abs(extra - samples[right]), np.abs(extra - samples[left])) < 1e-9
    return np.union1d(samples, extra[~near])


@dataclass(frozen=True)
class PneumaticResult:
    """Pressures, sensor heights and leveling of a pneumatic run.

    Attributes
    ----------
    isolator_names : tuple of str
    pressures : ndarray (isolators, N)
        Spring chamber gauge pressure ``p1 - p_atm`` [Pa].
    group_names : tuple of str
        Groups with a valve.
    heights : ndarray (groups with a valve, N)
        Sensor height from the initial equilibrium [m].
    leveling_time : dict of str to float or None
        Per group with a valve: time after the stop from which ``|h|`` stays
        within 1.1 dead bands [s]; None when not level by the end of the run.
    quasi_static : ndarray (6, N)
        The slowly leveling table's pose as table signals (NaN before the stop).
    dynamic : dict of str to SettlingResult
        Settling of the motion about the quasi-static pose, per signal.
    supply_exhausted : dict of str to float
        Per group that wanted air while a chamber was at ``p_atm + supply``:
        the first such time [s].
    """

    isolator_names: tuple[str, ...]
    pressures: np.ndarray
    group_names: tuple[str, ...]
    heights: np.ndarray
    leveling_time: dict[str, float | None]
    quasi_static: np.ndarray
    dynamic: dict[str, SettlingResult]
    supply_exhausted: dict[str, float]

    @property
    def dynamic_settling_time_max(self) -> float | None:
        """The largest dynamic settling time over the six signals [s] (None if one cannot be shown)."""
        times = [r.time for r in self.dynamic.values()]
        return None if any(v is None for v in times) else max(v for v in times if v is not None)

    @property
    def columns(self) -> dict[str, np.ndarray]:
        """``p:<isolator>`` [Pa] and ``h:<group>`` [m] columns, in order."""
        out = {f"p:{n}": self.pressures[k] for k, n in enumerate(self.isolator_names)}
        out.update({f"h:{n}": self.heights[j] for j, n in enumerate(self.group_names)})
        return out

    def to_dict(self) -> dict[str, object]:
        """JSON-ready summary: leveling times, dynamic settling, pressures at start and end, heights' peaks."""

        def num(v: float | None) -> float | None:
            return None if v is None or not math.isfinite(v) else float(v)

        return {
            "leveling_time": {k: num(v) for k, v in self.leveling_time.items()},
            "dynamic_settling_time": {k: num(r.time) for k, r in self.dynamic.items()},
            "dynamic_settling_time_max": num(self.dynamic_settling_time_max),
            "pressure": {f"p:{n}": {"start": float(self.pressures[k, 0]), "end": float(self.pressures[k, -1])}
                         for k, n in enumerate(self.isolator_names)},
            "height_peak": {f"h:{n}": float(np.max(np.abs(self.heights[j])))
                            for j, n in enumerate(self.group_names)},
            "supply_exhausted": dict(self.supply_exhausted),
        }


def plot_leveling(result: PneumaticResult, t: np.ndarray, stop_time: float, deadbands: dict[str, float],
                  title: str = "") -> Any:
    """Chamber pressures (top) and sensor heights (bottom) through the move and the leveling.

    Parameters
    ----------
    result : PneumaticResult
    t : ndarray
        Sample times [s].
    stop_time : float
        When the carriages stop [s].
    deadbands : dict of str to float
        Each valve group's dead band [m], drawn around zero height.
    title : str

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(10, 7), sharex=True, constrained_layout=True)
    styles = ("-", "--", "-.", ":")  # isolators of one group share a pressure: a style each keeps both in view
    for k, name in enumerate(result.isolator_names):
        top.plot(t, result.pressures[k] / 1e5, lw=1.6 if k % len(styles) == 0 else 1.3, ls=styles[k % len(styles)],
                 label=f"p:{name}")
    top.set_ylabel("spring chamber gauge pressure [bar]")
    top.legend(loc="best", fontsize=8, ncol=2)
    top.set_title("air spring pressures")
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for j, name in enumerate(result.group_names):
        colour = colours[j % len(colours)]
        bottom.plot(t, result.heights[j] * 1e6, lw=1.2, color=colour, label=f"h:{name}")
        level = result.leveling_time.get(name)
        if level is not None and math.isfinite(stop_time):
            bottom.axvline(stop_time + level, color=colour, ls="--", lw=1,
                           label=f"{name} level after {level:.3g} s")
    band = max(deadbands.values(), default=0.0) * 1e6
    if band > 0:
        bottom.axhspan(-LEVEL_BAND * band, LEVEL_BAND * band, color="tab:green", alpha=0.15, lw=0,
                       label=f"{LEVEL_BAND:g} x dead band")
    bottom.set_ylabel("sensor height [µm]")
    bottom.set_xlabel("time [s]")
    bottom.set_title("leveling-valve sensors")
    for ax in (top, bottom):
        if math.isfinite(stop_time):
            ax.axvline(stop_time, color="0.5", ls=":", lw=1)
        ax.grid(True, alpha=0.3)
    bottom.plot([], [], color="0.5", ls=":", label="carriages stop")
    bottom.legend(loc="lower right", fontsize=8, ncol=2)
    fig.suptitle(title or "pressures and sensor heights")
    return fig


def leveling_summary(result: PneumaticResult) -> list[str]:
    """Lines for a run's text summary: dynamic settling, leveling per group, supply trouble."""
    dyn = result.dynamic_settling_time_max
    lines = ["settling about the leveling table (largest): " + ("not available" if dyn is None else f"{dyn:.4g} s")]
    for name, value in result.leveling_time.items():
        lines.append(f"  group {name}: " + ("not level by the end of the run" if value is None
                                             else f"level {value:.4g} s after the stop"))
    for name, when in result.supply_exhausted.items():
        lines.append(f"  group {name}: air supply exhausted at t = {when:.4g} s (it needs more than its supply)")
    return lines


def sensor_heights(scenario: Scenario, states: np.ndarray, points: np.ndarray | None = None) -> np.ndarray:
    """Each group's sensor height (groups, N) [m]: world z displacement of the table point ``(x, y, 0)``
    from the reference pose, which is the initial equilibrium of a pneumatic table (``points`` (groups, 3)
    [m]: the sensors, default the scenario's)."""
    q = states[:, 3:7] / np.linalg.norm(states[:, 3:7], axis=1, keepdims=True)
    w, x, y, z = q.T
    row_z = np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=1)  # R[2, :]
    if points is None:
        points = np.array([[g.sensor[0], g.sensor[1], 0.0] for g in scenario.leveling])
    return np.asarray((states[:, 2:3] + row_z @ points.T - points[:, 2]).T)


def valve_note(scenario: Scenario, names: tuple[str, ...], p: np.ndarray, rest: np.ndarray,
               last: np.ndarray) -> tuple[bool, str]:
    """Whether a valve still moves air at a run's end (state ``last``: a sensor beyond ``LEVEL_BAND`` dead
    bands), and where the groups' sensors come to rest (``rest``, the state the free motion with every valve
    shut comes to) against their dead bands, in one phrase ("" for a table without valves); the sensors and
    dead bands of the parameter vector ``p`` (entries ``names``)."""
    value = dict(zip(names, np.asarray(p, dtype=float), strict=True))
    with_valve = [(j, g.name) for j, g in enumerate(scenario.leveling) if g.valve is not None]
    if not with_valve:
        return False, ""
    points = np.array([[value[f"leveling[{j}].sensor.x"], value[f"leveling[{j}].sensor.y"], 0.0]
                       for j in range(len(scenario.leveling))])
    heights = sensor_heights(scenario, np.vstack([last, rest]), points)
    band = {j: value[f"leveling[{j}].valve.deadband"] for j, _ in with_valve}
    active = any(abs(heights[j, 0]) > LEVEL_BAND * band[j] for j, _ in with_valve)
    groups = ", ".join(f"{name} {heights[j, 1] * 1e6:.3g} µm (dead band ±{band[j] * 1e6:.3g} µm)"
                       for j, name in with_valve)
    return active, (f"the leveling valves stop inside their dead band with the table off the level pose "
                    f"(sensors from level: {groups})")


def leveling_time(t: np.ndarray, height: np.ndarray, stop_time: float, deadband: float) -> float | None:
    """Time after ``stop_time`` from which ``|height|`` stays within 1.1 ``deadband`` [s]; None if it does
    not by the end (or the run ends before the stop)."""
    after = t >= stop_time - 1e-12
    if not np.any(after) or not math.isfinite(stop_time):
        return None
    outside = np.abs(height[after]) > LEVEL_BAND * deadband
    if outside[-1]:
        return None
    if not outside.any():
        return 0.0
    last = int(np.flatnonzero(outside)[-1])
    return float(t[after][last + 1] - stop_time)


def quasi_static_signals(
    model: Model, p: np.ndarray, t: np.ndarray, states: np.ndarray, positions: np.ndarray, reference: np.ndarray
) -> np.ndarray:
    """The table signals (6, N) of the rest a pneumatic table would take with the air each state holds.

    Parameters
    ----------
    model : Model
    p : ndarray
        Parameter vector.
    t : ndarray (N,)
        Sample times [s] (increasing).
    states : ndarray (N, n_states)
        The run's states there.
    positions : ndarray
        Carriage coordinates [m]: one configuration, or (N, n_carriages), one per sample.
    reference : ndarray
        The state the signals are measured from (the initial equilibrium's).

    Notes
    -----
    Solved every ``QUASI_STATIC_STEP`` and splined between: the air changes slowly.
    """
    stride = max(1, round(QUASI_STATIC_STEP / max(float(np.median(np.diff(t))), 1e-12))) if t.size > 1 else 1
    picked = np.unique(np.append(np.arange(0, t.size, stride), t.size - 1))
    q = np.asarray(positions, dtype=float)
    contents = air_in_groups(model, states[picked], p)
    rest = closed_rest_states(model, np.broadcast_to(p, (picked.size, p.size)), q[picked] if q.ndim == 2 else q,
                              contents)
    solved = model.variant.signals(rest, reference)
    if picked.size >= 4:
        return np.asarray(CubicSpline(t[picked], solved, axis=1)(t))
    return np.array([np.interp(t, t[picked], row) for row in solved])


def pneumatic_result(
    scenario: Scenario,
    model: Model,
    p: np.ndarray,
    t: np.ndarray,
    states: np.ndarray,
    signals: np.ndarray,
    start: Equilibrium,
    peaks: np.ndarray,
    hold: float,
    band: Band | None = None,
    fine: tuple[np.ndarray, np.ndarray] | None = None,
) -> PneumaticResult:
    """Pressures and heights at a pneumatic run's samples; leveling times and the dynamic settling (in
    ``band``, default the scenario's ``[settling]`` rule, resolved on the run's ``peaks``) read on ``fine``:
    times [s] and states on a grid of at least :data:`METRIC_RATE` (default: the samples), so that they do
    not depend on the output rate."""
    air = scenario.air
    if air is None:
        raise ValueError("pneumatic_result: not a pneumatic scenario")
    m = len(scenario.isolators)
    pressures = states[:, 13 : 13 + m].T - air.atmosphere
    sample_t, sample_heights = t, sensor_heights(scenario, states)
    if fine is not None and fine[0] is not t:  # a finer grid than the samples: read the leveling there
        t, states = fine
        signals = model.variant.signals(states, start.state)
        heights, gauge = sensor_heights(scenario, states), states[:, 13 : 13 + m].T - air.atmosphere
    else:
        heights, gauge = sample_heights, pressures
    stop = scenario.stop_time
    with_valve = [j for j, g in enumerate(scenario.leveling) if g.valve is not None]
    levels: dict[str, float | None] = {}
    exhausted: dict[str, float] = {}
    for j in with_valve:
        group = scenario.leveling[j]
        valve = group.valve
        if valve is None:
            continue
        levels[group.name] = leveling_time(t, heights[j], stop, valve.deadband)
        wants_air = -heights[j] > valve.deadband
        full = np.max(gauge[list(group.isolators)], axis=0) >= group.supply
        starved = np.flatnonzero(wants_air & full)
        if starved.size:
            exhausted[group.name] = float(t[starved[0]])
    quasi = np.full_like(signals, np.nan)
    after = np.flatnonzero(t >= stop - 1e-12) if math.isfinite(stop) else np.zeros(0, dtype=int)
    final_q = scenario.final_positions()
    if after.size and final_q is not None:
        quasi[:, after] = quasi_static_signals(model, p, t[after], states[after], final_q, start.state)
    dynamic = settling_metrics(t, np.where(np.isnan(quasi), signals, signals - quasi), np.zeros(6), stop,
                               scenario.settling if band is None else band, hold, peaks)
    names = tuple(iso.name for iso in scenario.isolators if isinstance(iso, PneumaticIsolator))
    return PneumaticResult(
        isolator_names=names,
        pressures=pressures,
        group_names=tuple(scenario.leveling[j].name for j in with_valve),
        heights=sample_heights[with_valve],
        leveling_time=levels,
        quasi_static=quasi if t is sample_t else np.array([np.interp(sample_t, t, row, left=np.nan) for row in quasi]),
        dynamic=dynamic,
        supply_exhausted=exhausted,
    )


check_public(globals(), ("PneumaticResult"))
