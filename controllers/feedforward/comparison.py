"""What the feedforward buys: the passive run against the run with feedforward, one settling band."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import SIGNALS, Scenario
from isolator.simulation.leveling import quasi_static_signals
from isolator.simulation.response import Response
from isolator.simulation.settling import Band
from isolator.simulation.simulator import Simulator

from .allocation import Feedforward, feedforward_allocation

__all__ = ["FeedforwardComparison", "compare_feedforward", "path_deviation", "run_quasi_static", "settling_in_band"]


def path_deviation(run: Response, quasi_static: np.ndarray) -> dict[str, float]:
    """Largest |signal - quasi-static path| per signal of a run [m or rad], the path given at the
    run's samples, shape (6, N).

    Parameters
    ----------
    run : Response
        A run of the scenario.
    quasi_static : ndarray
        (6, N): the quasi-static path at the run's samples [m, rad].

    Returns
    -------
    dict of str to float
        The largest deviation per signal name [m or rad].
    """
    dev = np.max(np.abs(run.signals - quasi_static), axis=1)
    return dict(zip(SIGNALS, (float(v) for v in dev), strict=True))


def settling_in_band(run: Response, band: Band | Mapping[str, float]) -> dict[str, float | None]:
    """Settling time per signal [s] of a run in a given band (a :class:`Band`, or six half-widths by
    signal [m or rad]), about the run's final value (None where the run cannot show it).

    Measured as the simulator measures its own band (``Response.with_band``: on the dense output or the
    internal grid), so ``isolator simulate --band`` with the band's half-widths gives the same numbers.

    Parameters
    ----------
    run : Response
        A run.
    band : Band or mapping of str to float
        The band, or its half-widths by signal name [m or rad].

    Returns
    -------
    dict of str to float or None
        Settling time per signal [s after the stop]; None where the run cannot show it.
    """
    chosen = band if isinstance(band, Band) else Band.absolute(band)
    return run.with_band(chosen).settling_time


@dataclass(frozen=True)
class FeedforwardComparison:
    """The passive run against the run with feedforward, judged with one settling band.

    Attributes
    ----------
    passive, controlled : Response
    quasi_static : ndarray (6, N)
        The quasi-static path at the samples [m, rad]. Pneumatic tables: the
        rest with the air the passive run's groups hold at each sample (the
        valves move air, so each run has its own).
    band : Band
        5 % of the passive run's peaks (kind ``baseline``), its six half-widths [m or rad].
    settling : dict of str to dict
        ``passive`` and ``controlled``: settling time per signal [s] (None if
        the run cannot show it) in that band.
    feedforward : Feedforward
    controlled_quasi_static : ndarray (6, N) or None
        Pneumatic tables: the controlled run's own quasi-static path [m, rad] (its valves move other air);
        None otherwise.
    """

    passive: Response
    controlled: Response
    quasi_static: np.ndarray
    band: Band
    settling: dict[str, dict[str, float | None]]
    feedforward: Feedforward
    controlled_quasi_static: np.ndarray | None = None

    def deviation_peak(self, which: str) -> dict[str, float]:
        """Largest |signal - quasi-static path| per signal [m or rad] of ``passive`` or ``controlled``."""
        if which == "passive" or self.controlled_quasi_static is None:
            reference = self.quasi_static
        else:
            reference = self.controlled_quasi_static
        return path_deviation(self.passive if which == "passive" else self.controlled, reference)

    def reduction_db(self) -> dict[str, float]:
        """Peak deviation from the quasi-static path, controlled over passive [dB] per signal."""
        p, c = self.deviation_peak("passive"), self.deviation_peak("controlled")
        return {k: 20 * math.log10(max(c[k], 1e-300) / p[k]) if p[k] > 0 else 0.0 for k in SIGNALS}

    def settling_time_max(self, which: str) -> float | None:
        values = self.settling[which].values()
        return None if any(v is None for v in values) else max(values)  # type: ignore[type-var]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``passive`` and ``controlled`` (``peak``, ``deviation_peak``,
        ``settling_time``, ``settling_time_max``), ``band``, ``reduction_db``, ``max_force``."""
        out: dict[str, Any] = {"name": self.passive.name, "method": self.feedforward.method}
        for which, r in (("passive", self.passive), ("controlled", self.controlled)):
            out[which] = {
                "peak": r.peak,
                "deviation_peak": self.deviation_peak(which),
                "settling_time": self.settling[which],
                "settling_time_max": self.settling_time_max(which),
            }
        out["band"] = self.band.to_dict()
        out["reduction_db"] = self.reduction_db()
        out["max_force"] = self.feedforward.max_force
        if self.feedforward.info:
            out["optimisation"] = self.feedforward.info
        return out

    def summary(self) -> str:
        """A text table per signal: deviation peaks, reduction, settling times."""
        red = self.reduction_db()
        dp, dc = self.deviation_peak("passive"), self.deviation_peak("controlled")
        lines = [
            f"{self.passive.name}: feedforward by {self.feedforward.method} (deviation from the quasi-static path; "
            "settling band 5 % of the passive peak)",
            self.band.describe(),
            f"{'signal':>6}  {'passive dev.':>12}  {'with ff':>12}  {'change':>9}  "
            f"{'settling passive':>16}  {'with ff':>8}",
        ]
        for k in SIGNALS:
            sp, sc = self.settling["passive"][k], self.settling["controlled"][k]
            unit = "µrad" if k.startswith("r") else "µm"
            lines.append(
                f"{k:>6}  {dp[k] * 1e6:>7.4g} {unit:<4}  {dc[k] * 1e6:>7.4g} {unit:<4}  {red[k]:>6.1f} dB  "
                f"{'-' if sp is None else f'{sp:.4g} s':>16}  {'-' if sc is None else f'{sc:.4g} s':>8}"
            )
        forces = self.feedforward.max_force.items()
        lines.append("largest actuator force: " + ", ".join(f"{n} {f:.0f} N" for n, f in forces))
        return "\n".join(lines)


def compare_feedforward(scenario: Scenario, feedforward: Feedforward | None = None) -> FeedforwardComparison:
    """Simulate the scenario without and with the feedforward forces.

    Both runs' settling times use one band per signal: 5 % of the passive
    run's peak (the issue's criterion), about the final static equilibrium.

    Parameters
    ----------
    scenario : Scenario
        The scenario, with ``[[actuators]]`` (or a bundled scenario's name, or a TOML file's path).
    feedforward : Feedforward, optional
        The forces to judge; default :func:`feedforward_allocation` of the scenario.

    Returns
    -------
    FeedforwardComparison
        Both runs, their deviations from the quasi-static path [m, rad], the band and the settling times [s]
        of each.
    """
    ff = feedforward_allocation(scenario) if feedforward is None else feedforward
    sim = Simulator(scenario)
    passive = sim.run()
    controlled = sim.run(forces=ff.forces)
    band = Band.of_baseline("passive", passive.peak)
    settling = {"passive": settling_in_band(passive, band), "controlled": settling_in_band(controlled, band)}
    if not scenario.is_pneumatic:
        return FeedforwardComparison(passive, controlled, ff.path(passive.t).T, band, settling, ff)
    return FeedforwardComparison(passive, controlled, run_quasi_static(sim, passive), band, settling, ff,
                                 run_quasi_static(sim, controlled))


def run_quasi_static(sim: Simulator, run: Response) -> np.ndarray:
    """Pneumatic runs: the table signals (6, N) of the rest with the air each sample's groups hold,
    the carriages where they are (:func:`isolator.simulation.leveling.quasi_static_signals`), measured from
    the run's first state, its initial equilibrium.

    Parameters
    ----------
    sim : Simulator
        The simulator of the pneumatic scenario.
    run : Response
        One of its runs.

    Returns
    -------
    ndarray
        (6, N): x, y, z [m] and rx, ry, rz [rad] at the run's samples.
    """
    return quasi_static_signals(sim.model, sim.parameters, run.t, run.states, run.q.T, run.states[0])


check_public(globals())
