"""Each experiment as weighted residuals of the model against its record, with their Jacobian in the
logarithms of the fitted parameters.

- ``floor``: the multi-input H1 from the floor sensors' signals to the table sensors' signals
  (:func:`isolator.calibration.spectra.h1_estimate`) against the linearised model's response over the
  experiment's band (:class:`~isolator.calibration.floor_model.FloorModel`, exact derivatives) as the same
  estimator sees it (the model's response to the measured floor through the same segments, after the same
  warm-up: :mod:`isolator.calibration.estimator_view`), each bin's real and imaginary part divided by its random
  error (the coherence-based variance of the estimate).
- ``move``: the table sensors' records against the full time-varying model sample by sample
  (:class:`~isolator.calibration.move_model.MoveModel`), each channel divided by its noise, estimated from
  the record alone (the median absolute second difference, robust to the move's steps:
  ``sigma = 1.4826 median|d2y - median d2y| / sqrt(6)`` for white noise); the Jacobian by forward
  differences in the parameters' logarithms, the perturbed runs in one batch of SIMD lanes.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from isolator.analysis.linear import linearise, rest_positions
from isolator.analysis.modes import modes
from isolator.calibration.definition import Calibration, Experiment
from isolator.calibration.estimator_view import EstimatorView
from isolator.calibration.floor_model import FloorModel
from isolator.calibration.move_model import MoveModel
from isolator.calibration.records import Record
from isolator.calibration.spectra import FrfEstimate, h1_estimate
from isolator.errors import ParameterError, ScenarioError
from isolator.scenario.sensors import Sensor

__all__ = ["FloorExperiment", "MoveExperiment", "Residuals", "check_time_columns", "noise_estimate", "prepare"]

#: forward-difference step in a parameter's logarithm (move experiments)
LOG_STEP = 1e-6
#: the warm-up left out of a floor record's spectra, in decay times of the slowest mode
WARM_UP = 6.0
#: the Hann window's equivalent noise bandwidth [bins]: N sum w^2 / (sum w)^2
ENBW_HANN = 1.5
#: least random error of an H1 bin, relative to its magnitude (noise-free records)
FLOOR_ERROR = 1e-6


@dataclass(frozen=True)
class Residuals:
    """An experiment's weighted residuals at one parameter vector and their Jacobian.

    Attributes
    ----------
    r : ndarray (m,)
        (model - measured) / random error, dimensionless.
    J : ndarray (m, params) or None
        d r / d log(parameter).
    """

    r: np.ndarray
    J: np.ndarray | None


def noise_estimate(y: np.ndarray) -> float:
    """The RMS of white noise on a sampled signal [its unit], from its second differences (robust to steps
    and smooth motion); at least 1e-9 of the signal's largest magnitude (a noise-free record)."""
    d2 = np.diff(np.asarray(y, dtype=float), 2)
    sigma = 1.4826 * float(np.median(np.abs(d2 - np.median(d2)))) / np.sqrt(6.0)
    return max(sigma, 1e-9 * float(np.max(np.abs(y))), 1e-300)


def _split(sensors: tuple[Sensor, ...], record: Record) -> tuple[tuple[Sensor, ...], tuple[Sensor, ...]]:
    """The table sensors and the floor sensors the record holds, in the scenario's order."""
    held = [s for s in sensors if s.name in record.channels]
    return tuple(s for s in held if s.on == "table"), tuple(s for s in held if s.on == "floor")


class FloorExperiment:
    """A floor experiment: H1 from the floor's sensors to the table's, against the linear model."""

    kind = "floor"

    def __init__(self, calibration: Calibration, experiment: Experiment, record: Record) -> None:
        key, scenario = experiment.key, calibration.scenario
        self.name = experiment.name
        table, floor = _split(scenario.sensors, record)
        if not floor:
            raise ScenarioError(f"{key}: a floor experiment needs the floor's motion: its record ({record.path}) "
                                "holds no floor sensor")
        if not table:
            raise ScenarioError(f"{key}: its record ({record.path}) holds no table sensor")
        directions = np.array([s.direction for s in floor], dtype=float)
        if np.linalg.matrix_rank(directions, tol=1e-6) < len(floor):
            raise ScenarioError(f"{key}: the floor sensors {', '.join(s.name for s in floor)} do not measure "
                                "independent directions (keep one per direction)")
        try:
            positions = rest_positions(scenario, dict(experiment.positions))
        except ParameterError as exc:
            raise ScenarioError(f"{key}.{exc}") from None
        self.table, self.floor = table, floor
        self.model = FloorModel(calibration.layout, positions, table)
        lowest = modes(linearise(scenario, positions))
        f1 = float(lowest.frequencies_hz[0])
        zeta = float(np.clip(np.min(lowest.damping_ratios), 1e-3, 1.0))
        duration = float(record.t[-1] - record.t[0])
        # the slowest decay's time constant sets the warm-up (6 of them, at most a quarter of the record) and the
        # default segment (four bins per half-power bandwidth of the lowest mode, at least 4 of its periods, at
        # most an eighth of what is left)
        decay = np.clip(lowest.damping_ratios, 1e-3, 1.0) * 2 * np.pi * lowest.frequencies_hz
        tau = 1.0 / float(np.min(decay))  # the slowest mode's decay time [s]
        self.warm = float(min(WARM_UP * tau, duration / 4.0))
        used = duration - self.warm
        self.segment = experiment.segment or float(min(max(4.0 / (2 * zeta * f1), 4.0 / f1), used / 8.0))
        start = round(self.warm * record.rate)
        x = np.array([record.channels[s.name] for s in floor])
        y = np.array([record.channels[s.name] for s in table])
        # the record's channels in their noise's sigma (where a misfit's bad sample is looked for)
        self.t, self.samples = record.t, np.array([v / noise_estimate(v) for v in (*y, *x)])
        try:
            estimate = h1_estimate(x[:, start:], y[:, start:], record.rate, self.segment)
        except ParameterError as exc:
            raise ScenarioError(f"{key} ({record.path.name}): {exc}") from None
        low, high = experiment.frequency
        band = (estimate.f >= low) & (estimate.f <= high) & (estimate.f > 0) & np.all(
            np.isfinite(estimate.H), axis=(0, 1)) & np.all(np.isfinite(estimate.variance), axis=(0, 1))
        if band.sum() < 2:
            raise ScenarioError(f"{key}.frequency: [{low:g}, {high:g}] Hz holds {int(band.sum())} frequency bins of "
                                f"the {self.segment:.4g} s segments (resolution {estimate.f[1]:.4g} Hz); widen it or "
                                "lengthen the segment")
        self.estimate = estimate
        self.f = estimate.f[band]
        self.H1 = estimate.H[:, :, band]
        self.coherence = estimate.coherence[:, band]
        _warn_input_noise(key, floor, x[:, start:], record.rate, estimate, band)
        # each part's random error; neighbouring bins are correlated through the window (Hann: its equivalent
        # noise bandwidth is 1.5 bins), so a bin carries 1 / ENBW of an independent bin's information
        sigma = np.sqrt(np.asarray(estimate.variance[:, :, band], dtype=float) / 2.0 * ENBW_HANN)
        self.sigma = np.maximum(sigma, FLOOR_ERROR * np.abs(self.H1) + 1e-300)
        nperseg = round(estimate.segment * record.rate)
        self.view = EstimatorView.of(x, record.rate, nperseg, start, np.flatnonzero(band), estimate.f,
                                     pad=2 * start + nperseg)
        # floor translation (3) per floor-sensor signal: g = pinv(N) x, a signal of order k is (jw)^k times it
        jw = 2j * np.pi * self.view.lines
        orders = np.array([s.order for s in floor])
        self.to_signals = np.linalg.pinv(directions)[None, :, :] * (jw[:, None, None] ** -orders[None, None, :])

    def predict(self, p: np.ndarray, tangents: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray | None]:
        """The model's H1 as the estimator sees it (table sensors, floor sensors, nf), and its derivatives
        (params, ...) along ``tangents`` (:class:`~isolator.calibration.estimator_view.EstimatorView`)."""
        response = self.model.response(p, self.view.lines, tangents)
        h = self.view.seen(np.einsum("skf,fkm->smf", response.H, self.to_signals))
        dh = None if response.dH is None else self.view.seen(
            np.einsum("jskf,fkm->jsmf", response.dH, self.to_signals))
        return h, dh

    def residuals(self, p: np.ndarray, tangents: np.ndarray | None = None) -> Residuals:
        h, dh = self.predict(p, tangents)
        r = np.concatenate([((h - self.H1).real / self.sigma).ravel(), ((h - self.H1).imag / self.sigma).ravel()])
        if dh is None:
            return Residuals(r, None)
        jac = np.concatenate([(dh.real / self.sigma).reshape(dh.shape[0], -1),
                              (dh.imag / self.sigma).reshape(dh.shape[0], -1)], axis=1).T
        return Residuals(r, jac)


class MoveExperiment:
    """A move experiment: the table sensors' records against the time-varying model, sample by sample."""

    kind = "move"

    def __init__(self, calibration: Calibration, experiment: Experiment, record: Record) -> None:
        self.name = experiment.name
        table, _ = _split(calibration.scenario.sensors, record)
        if not table:
            raise ScenarioError(f"{experiment.key}: its record ({record.path}) holds no table sensor")
        self.table = table
        self.model = MoveModel(calibration.scenario, record.t, table, experiment.key)
        self.t = self.model.t
        self.y = np.array([record.channels[s.name] for s in table])
        self.sigma = np.array([noise_estimate(v) for v in self.y])

    def residuals(self, p: np.ndarray, tangents: np.ndarray | None = None) -> Residuals:
        runs = [p] if tangents is None else [p] + [p * np.exp(LOG_STEP * (t != 0)) for t in tangents]
        signals = self.model.signals(np.array(runs))
        r = ((signals[0] - self.y) / self.sigma[:, None]).ravel()
        if tangents is None:
            return Residuals(r, None)
        jac = ((signals[1:] - signals[0]) / (LOG_STEP * self.sigma[None, :, None])).reshape(len(tangents), -1).T
        return Residuals(r, jac)

    def predict(self, p: np.ndarray) -> np.ndarray:
        """The model's sensor signals (table sensors, N) [SI]."""
        return self.model.signals(p[None, :])[0]


def _warn_input_noise(key: str, floor: tuple[Sensor, ...], x: np.ndarray, rate: float, estimate: FrfEstimate,
                      band: np.ndarray) -> None:
    """Warn when a floor sensor's declared ``noise`` biases the H1 by more than half its random error: noise on
    an input lowers any H1 by the noise's share of that input's spectrum (``Gnn / Gxx``), which the fit's
    intervals do not include."""
    nperseg = round(estimate.segment * rate)
    from scipy import signal  # imported where used: scipy.signal takes a quarter of a second

    welch_f, pxx = signal.welch(x, fs=rate, window="hann", nperseg=nperseg, noverlap=nperseg // 2)
    relative = np.sqrt(estimate.variance[:, :, band]) / np.maximum(np.abs(estimate.H[:, :, band]), 1e-300)
    frequency = welch_f[band]
    for k, sensor in enumerate(floor):
        density = sensor.noise_density(rate)
        if density is None:
            continue
        share = float(np.max(density(frequency) / np.maximum(pxx[k, band], 1e-300)))
        error = float(np.median(relative[:, k, :]))
        if share > 0.5 * error:
            above = " (its declared noise exceeds the measured floor signal somewhere in the band)" if share > 1 else ""
            warnings.warn(f"{key}: the floor sensor '{sensor.name}' (noise {sensor.noise_rms(rate):.3g} {sensor.unit} "
                          "RMS per sample) "
                          f"biases the H1 low by up to {min(share, 1.0):.2%} in the band{above}, against a random "
                          f"error of {error:.2%}; the intervals do not include it (a quieter sensor or a stronger "
                          "floor excitation removes it)", stacklevel=3)


def check_time_columns(calibration: Calibration, records: dict[str, Record]) -> None:
    """Refuse, before any spectrum or simulation, a record sampled too slowly for its experiment: a floor
    experiment's band, a move's table modes (the highest at rest) need a rate above twice their frequency. A
    record whose rate would do a thousand times faster most likely has its ``t`` in milliseconds: said so.

    Raises
    ------
    ScenarioError
        Naming the experiment, its file, its rate and what it needs.
    """
    highest: float | None = None
    for e in calibration.experiments:
        record = records[e.name]
        if e.kind == "floor":
            need, what = e.frequency[1], f"its band's top, {e.frequency[1]:.4g} Hz"
        else:
            if highest is None:
                highest = float(np.max(modes(linearise(calibration.scenario)).frequencies_hz))
            need, what = highest, f"the table's highest mode, {highest:.4g} Hz"
        rate = record.rate
        if rate > 2.0 * need:
            continue
        unit = ("; is its t column in milliseconds? (t is in seconds)" if rate * 1e3 > 2.0 * need else "")
        raise ScenarioError(f"{e.key}: the record {record.path.name} is sampled at {rate:.4g} Hz (samples "
                            f"{1.0 / rate:.4g} s apart), too slow for {what}: it needs more than "
                            f"{2.0 * need:.4g} Hz{unit}")


def prepare(calibration: Calibration, records: dict[str, Record]) -> list[FloorExperiment | MoveExperiment]:
    """Each experiment with its record (by experiment name), the records' time columns checked first
    (:func:`check_time_columns`)."""
    check_time_columns(calibration, records)
    out: list[FloorExperiment | MoveExperiment] = []
    for e in calibration.experiments:
        kind = FloorExperiment if e.kind == "floor" else MoveExperiment
        out.append(kind(calibration, e, records[e.name]))
    return out
