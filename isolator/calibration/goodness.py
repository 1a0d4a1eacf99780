"""Does a calibration's fit explain its records? Each experiment's weighted residuals against their chi-square
distribution, and what a misfit most likely means (a record in other units, a flipped sensor).

Each experiment's residuals are divided by their own noise estimate, so at a fit within the noise their mean
square is known: 1 for a move (each sample's noise from the record), ``1 / ENBW`` for a floor experiment (each
H1 bin's random error was widened by the Hann window's equivalent noise bandwidth, since neighbouring bins are
correlated). The test's statistic is the mean square over that, the **ratio** (about 1 at a fit within the
noise; ``s^2`` over the experiment's degrees of freedom, its share of the fitted parameters taken out). Under
the noise model the ratio is ``chi2(nu) / nu`` with ``nu`` the experiment's effective degrees of freedom:

- move: the samples, less the experiment's share of the parameters; the noise of each channel is an estimate
  (median absolute second difference) whose relative spread, :data:`NOISE_ESTIMATE_SPREAD` ``/ sqrt(n)`` for
  ``n`` samples, adds ``4 spread^2 / n`` per channel (weighted by its share) to the ratio's variance ``2 / nu``;
  ``nu`` is then ``2 / variance``;
- floor: the bins' real and imaginary parts over the equivalent noise bandwidth (correlated neighbours).

A fit fails the test where the ratio exceeds the ``1 -`` :data:`SIGNIFICANCE` quantile of ``chi2(nu) / nu``.
A misfit is then explained where it can be: a move whose residuals (a floor experiment whose record) jump at one
instant (a jump from one sample to the next :data:`JUMP` times their typical one, at most :data:`FEW` samples)
has a bad sample there (a spike, a step): its time and size in sigma (of the channel's noise) are named; a
record whose channels are a power of ten (within a factor of 2) or ``1 / g`` times the model's in magnitude
(RMS, against the nominal model: a fit forced by a record in other units is no reference) is in other units; a
channel of the model's magnitude (within a factor of 2) but about ``-1`` times it (least-squares scale on the
fitted model) is a sensor whose direction is flipped; the table sensor whose channel holds the largest mean
square residual is named.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from isolator.calibration.experiments import ENBW_HANN, FloorExperiment, MoveExperiment
from isolator.scenario.sensors import Sensor

__all__ = ["FEW", "JUMP", "NOISE_ESTIMATE_SPREAD", "SIGNIFICANCE", "Goodness", "goodness_of_fit", "misfit_message"]

#: the test's false-alarm probability for one experiment at a fit within the noise
SIGNIFICANCE = 1e-3
#: relative standard deviation of :func:`~isolator.calibration.experiments.noise_estimate` times sqrt(samples)
#: on white noise (Monte Carlo: ``tests/calibration/test_goodness.py``)
NOISE_ESTIMATE_SPREAD = 1.42
#: standard gravity [m/s^2]: a record in g is 1/g times the model's
GRAVITY = 9.80665
#: a jump of the residuals from one sample to the next this many times their typical one (robust spread) is a
#: bad sample (white noise: the largest of a million is about 5)
JUMP = 12.0
#: the most samples such jumps may touch for the misfit to be named as sitting there
FEW = 3
#: units a record in another unit most likely used, by quantity and power of ten of its scale on the model's
_UNITS = {"acceleration": {3: "mm/s^2", 6: "um/s^2", 9: "nm/s^2"},
          "velocity": {3: "mm/s", 6: "um/s", 9: "nm/s"},
          "displacement": {3: "mm", 6: "um", 9: "nm"}}
_PLURAL = {"acceleration": "accelerations", "velocity": "velocities", "displacement": "displacements"}


@dataclass(frozen=True)
class Goodness:
    """One experiment's goodness of fit.

    Attributes
    ----------
    experiment : str
        Its name.
    file : str
        Its record's file name.
    ratio : float
        Mean square weighted residual over its expectation at a fit within the noise (about 1 then).
    limit : float
        The ratio's ``1 - SIGNIFICANCE`` quantile at a fit within the noise.
    dof : float
        The effective degrees of freedom of the ratio's chi-square distribution.
    worst : str
        The table sensor whose channel misfits most (largest mean square weighted residual).
    scales : dict of str to float
        Each table sensor's least-squares scale of its record on the fitted model (1 when they agree).
    diagnosis : str
        What the misfit most likely means ("" when nothing stands out).
    jump : tuple of (str, float, float) or None
        Where a move's misfit sits when a few samples carry it: the sensor, the time [s] and the jump's size
        [sigma of the channel's noise].
    """

    experiment: str
    file: str
    ratio: float
    limit: float
    dof: float
    worst: str
    scales: dict[str, float]
    diagnosis: str
    jump: tuple[str, float, float] | None = None

    @property
    def ok(self) -> bool:
        """Whether the ratio is within its limit."""
        return self.ratio <= self.limit


def goodness_of_fit(experiment: FloorExperiment | MoveExperiment, file: str, r: np.ndarray, n_params: float,
                    fitted: np.ndarray, nominal: np.ndarray | None = None) -> Goodness:
    """The goodness of one experiment's fit.

    Parameters
    ----------
    experiment : FloorExperiment or MoveExperiment
    file : str
        Its record's file name (for messages).
    r : ndarray (m,)
        Its weighted residuals at the fit (``experiment.residuals(p).r``).
    n_params : float
        Its share of the fitted parameters (the parameters times its share of all residuals).
    fitted : ndarray
        The fitted model's prediction: the H1 (table sensors, floor sensors, bins) of a floor experiment, the
        signals (table sensors, samples) of a move.
    nominal : ndarray, optional
        The same at the scenario's values (the magnitudes a record in other units is judged by; default
        ``fitted``).

    Returns
    -------
    Goodness
    """
    sensors = experiment.table
    m = r.size
    reference = np.asarray(fitted if nominal is None else nominal).reshape(len(sensors), -1)
    jump = None
    if isinstance(experiment, FloorExperiment):
        expected, nu = 1.0 / ENBW_HANN, max((m - n_params) / ENBW_HANN, 1.0)
        per_channel = (r.reshape(2, len(sensors), -1) ** 2).mean(axis=(0, 2))
        measured = experiment.H1.reshape(len(sensors), -1)
        model = np.asarray(fitted).reshape(len(sensors), -1)
        jump = _jump(experiment.samples, experiment.t, (*sensors, *experiment.floor))
    else:
        jump = _jump(r.reshape(len(sensors), -1), experiment.t, sensors)
        expected = 1.0
        per_channel = (r.reshape(len(sensors), -1) ** 2).mean(axis=1)
        measured, model = experiment.y, np.asarray(fitted)
        samples = experiment.y.shape[1]
        share = 1.0 / len(sensors)
        variance = 2.0 / max(m - n_params, 1.0) + len(sensors) * share**2 * 4 * NOISE_ESTIMATE_SPREAD**2 / samples
        nu = 2.0 / variance
    ratio = float(r @ r) / max(m - n_params, 1.0) / expected
    from scipy import stats  # imported where used: scipy.stats takes a quarter of a second

    limit = float(stats.chi2.ppf(1.0 - SIGNIFICANCE, nu) / nu)
    scales = {s.name: _scale(a, b) for s, a, b in zip(sensors, measured, model, strict=True)}
    sizes = {s.name: _magnitude(a, b) for s, a, b in zip(sensors, measured, reference, strict=True)}
    worst = sensors[int(np.argmax(per_channel))].name
    kind = "floor" if isinstance(experiment, FloorExperiment) else "move"
    judged = {name: (math.nan if jump is not None and name == jump[0] else k) for name, k in sizes.items()}
    diagnosis = _diagnosis(kind, file, sensors, scales, judged)  # a channel with a bad sample: no unit judged
    if jump is not None:
        where = (f"the misfit sits at t = {jump[1]:.6g} s in {jump[0]}: a jump of {jump[2]:.3g} sigma from one "
                 f"sample to the next (a spike or a step in the record?)")
        diagnosis = f"{where}; {diagnosis}" if diagnosis else where
    return Goodness(experiment.name, file, ratio, limit, nu, worst, scales, diagnosis, jump)


def _jump(r: np.ndarray, t: np.ndarray, sensors: tuple[Sensor, ...]) -> tuple[str, float, float] | None:
    """Where a few samples carry a misfit: each channel (a move's residuals, a floor record's samples, in sigma)
    jumping from one sample to the next :data:`JUMP` times the typical jump, at no more than :data:`FEW`
    neighbouring samples (a spike: two jumps, up and down; a step: one). The sensor, the time [s] and the largest
    jump [sigma]; else None."""
    if r.shape[1] < 8:
        return None
    d = np.diff(r, axis=1)
    centre = np.median(d, axis=1, keepdims=True)
    spread = 1.4826 * np.median(np.abs(d - centre), axis=1, keepdims=True)
    z = np.abs(d - centre) / np.maximum(spread, 1e-300)
    channels, at = np.nonzero(z > JUMP)
    if at.size == 0 or at.max() - at.min() >= FEW:
        return None
    k = int(np.argmax(np.abs(d[channels, at])))
    c, i = int(channels[k]), int(at[k])
    return sensors[c].name, float(t[i + 1]), float(abs(d[c, i]))


def _magnitude(measured: np.ndarray, model: np.ndarray) -> float:
    """The RMS of ``measured`` over the RMS of ``model`` (NaN without a model signal)."""
    den = float(np.sqrt(np.mean(np.abs(model) ** 2)))
    return float(np.sqrt(np.mean(np.abs(measured) ** 2))) / den if den > 0 else math.nan


def _scale(measured: np.ndarray, model: np.ndarray) -> float:
    """The least-squares scale ``k`` of ``measured ~ k model`` (real part for complex data)."""
    den = float(np.sum(np.abs(model) ** 2))
    return float(np.real(np.vdot(model, measured)) / den) if den > 0 else math.nan


def _power_of_ten(k: float) -> int | None:
    """The power of ten (not 0) ``|k|`` is within a factor of 2 of, else None."""
    if not math.isfinite(k) or k <= 0:
        return None
    j = round(math.log10(k))
    return j if j != 0 and abs(math.log10(k) - j) < math.log10(2.0) else None


def _diagnosis(kind: str, file: str, sensors: tuple[Sensor, ...], scales: dict[str, float],
               sizes: dict[str, float]) -> str:
    """A record in other units (each channel's magnitude on the nominal model), or flipped sensors (of the
    model's magnitude, their scale on the fitted model about -1)."""
    by_unit: dict[tuple[str, str], list[str]] = {}
    flipped = [s.name for s in sensors if -2.0 < scales[s.name] < -0.5 and 0.5 < sizes[s.name] < 2.0]
    for s in sensors:
        k = sizes[s.name]
        if s.quantity == "acceleration" and kind == "move" and abs(k * GRAVITY - 1) < 0.1:
            by_unit.setdefault(("1/g", "g"), []).append(s.name)
            continue
        j = _power_of_ten(k)
        if j is not None:
            unit = _UNITS[s.quantity].get(j, "") if kind == "move" else ""
            by_unit.setdefault((f"{10.0**j:g}", unit), []).append(s.name)
    parts = []
    for (factor, unit), names in by_unit.items():
        if kind == "floor":
            whose = "of the table sensors" if len(names) == len(sensors) else f"of {', '.join(names)}"
            parts.append(f"the H1 {whose} in {file} is about {factor} times the model's: its table and floor "
                         "columns in different units?")
            continue
        quantities = {s.quantity for s in sensors if s.name in names}
        noun = _PLURAL[quantities.pop()] if len(quantities) == 1 else "signals"
        whose = "" if len(names) == len(sensors) else f" ({', '.join(names)})"
        hint = f": {unit}?" if unit else ": another unit?"
        parts.append(f"the {noun} of {file}{whose} are about {factor} times the model's{hint}")
    if flipped:
        parts.append(f"{', '.join(flipped)} {'reads' if len(flipped) == 1 else 'read'} about -1 times the "
                     f"model's: {'its direction' if len(flipped) == 1 else 'their directions'} flipped?")
    return "; ".join(parts)


def misfit_message(failed: list[Goodness], accepted: bool = False) -> str:
    """One line naming each experiment that fails the test (worst first), its ratio and what it most likely
    means; ``accepted``: the fit is given anyway (``accept_misfit``)."""
    parts = []
    for g in sorted(failed, key=lambda g: g.ratio / g.limit, reverse=True):
        text = (f"experiment '{g.experiment}' ({g.file}): weighted residual variance {g.ratio:.3g} times the "
                f"noise's (at most {g.limit:.3g} for a fit within the noise); {g.worst} misfits most")
        parts.append(text + (f"; {g.diagnosis}" if g.diagnosis else ""))
    advice = ("check the records at the instants named (a bad sample is no model's to explain)"
              if all(g.jump is not None for g in failed) else
              "check the records' units and the sensors' directions, or fit more parameters")
    tail = f" (given anyway: {advice})" if accepted else f" ({advice}; --accept-misfit gives the fit anyway)"
    return "calibrate: the fit does not explain the records: " + "; ".join(parts) + tail
