"""Random disturbances and noise (``docs/scenario-format.md``, "Error budget: random disturbances and noise at
the points"): one-sided power spectral densities, ``[[disturbances]]``, the ``noise_psd`` of sensors and
actuators, and the floor at the limit of a VC class (``[ground.spectrum] vc``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from isolator.errors import ScenarioError
from isolator.scenario.ground import FloorSpectrum
from isolator.scenario.keys import KeyReader, check_placement, number, table_of_tables
from isolator.scenario.names import check_name

__all__ = ["VC_CLASSES", "Disturbance", "SpectralDensity", "read_density", "read_disturbances", "vc_spectrum"]

#: VC class limits: one-third-octave RMS velocity [m/s] (VC-A 50 µm/s, halving per letter to VC-G)
VC_CLASSES: dict[str, float] = {f"VC-{c}": 50e-6 / 2**k for k, c in enumerate("ABCDEFG")}
#: the one-third-octave band numbers ``n`` (centres ``10^(n/10)`` Hz) of a ``vc`` floor: 1 to 79.4 Hz
VC_BANDS = range(20)


@dataclass(frozen=True)
class SpectralDensity:
    """A one-sided power spectral density [SI^2/Hz] of a random source.

    Flat (``frequency`` empty, one ``value``: the same at every frequency) or a table (``frequency``
    increasing, ``value`` > 0 at each), interpolated log-log between its points and zero outside them.

    Attributes
    ----------
    value : tuple of float
        [SI^2/Hz]: one value (flat) or one per frequency.
    frequency : tuple of float
        [Hz]; empty for a flat density.
    """

    value: tuple[float, ...]
    frequency: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        check_density(self.value, self.frequency, "psd")

    @classmethod
    def flat(cls, value: float) -> SpectralDensity:
        """The same density ``value`` [SI^2/Hz] at every frequency."""
        return cls((float(value),))

    @property
    def is_flat(self) -> bool:
        """Whether the density is one value at every frequency."""
        return not self.frequency

    @property
    def corners(self) -> np.ndarray:
        """Frequencies [Hz] where the density's slope changes or it starts and ends (empty when flat)."""
        return np.asarray(self.frequency, dtype=float)

    def __call__(self, frequency_hz: np.ndarray) -> np.ndarray:
        """The density [SI^2/Hz] at ``frequency_hz`` [Hz] (any shape)."""
        f = np.asarray(frequency_hz, dtype=float)
        if self.is_flat:
            return np.full(f.shape, self.value[0])
        fs, vs = np.log(self.corners), np.log(np.asarray(self.value, dtype=float))
        out = np.zeros(f.shape)
        inside = (f >= self.frequency[0]) & (f <= self.frequency[-1])
        out[inside] = np.exp(np.interp(np.log(f[inside]), fs, vs))
        return out

    def integral(self, high: float) -> float:
        """``int_0^high S(f) df`` [SI^2]: the variance of the source below ``high`` [Hz] (exact for the log-log
        interpolation: each segment a power law)."""
        if self.is_flat:
            return self.value[0] * high
        total = 0.0
        for f1, f2, s1, s2 in zip(self.frequency[:-1], self.frequency[1:], self.value[:-1], self.value[1:],
                                  strict=True):
            end = min(f2, high)
            if end <= f1:
                break
            slope = math.log(s2 / s1) / math.log(f2 / f1)
            if abs(slope + 1.0) < 1e-12:
                total += s1 * f1 * math.log(end / f1)
            else:
                total += s1 * f1 / (slope + 1.0) * ((end / f1) ** (slope + 1.0) - 1.0)
        return total

    def to_toml(self) -> float | dict[str, list[float]]:
        """The density as the scenario file writes it: a number, or ``{frequency, value}``."""
        if self.is_flat:
            return self.value[0]
        return {"frequency": list(self.frequency), "value": list(self.value)}


def check_density(values: tuple[float, ...], freqs: tuple[float, ...], key: str) -> None:
    """Refuse a density's values [SI^2/Hz] and frequencies [Hz] (one :class:`ScenarioError` naming ``key``)."""
    if not isinstance(values, tuple) or not isinstance(freqs, tuple):
        raise ScenarioError(f"{key}: value and frequency must be tuples of numbers")
    for i, v in enumerate(values):
        label = f"{key}" if not freqs else f"{key}.value[{i}]"
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise ScenarioError(f"{label}: must be a finite number [SI^2/Hz], got {v!r}")
        if v < 0 or (freqs and v == 0):
            raise ScenarioError(f"{label}: a power spectral density must be {'> 0' if freqs else '>= 0'} "
                                f"[SI^2/Hz], got {v:g}")
    if not freqs:
        if len(values) != 1:
            raise ScenarioError(f"{key}: a flat density has one value, got {len(values)}")
        return
    if len(freqs) < 2 or len(values) != len(freqs):
        raise ScenarioError(f"{key}: needs at least two frequencies and one value per frequency, got "
                            f"{len(freqs)} frequencies and {len(values)} values")
    for i, f in enumerate(freqs):
        if isinstance(f, bool) or not isinstance(f, int | float) or not math.isfinite(f) or f <= 0:
            raise ScenarioError(f"{key}.frequency[{i}]: must be a finite frequency > 0 [Hz], got {f!r}")
        if i and f <= freqs[i - 1]:
            raise ScenarioError(f"{key}.frequency[{i}]: frequencies must be strictly increasing, got {f:g} after "
                                f"{freqs[i - 1]:g}")


def read_density(value: Any, key: str) -> SpectralDensity:
    """A density from the file: a number (flat) or ``{frequency = [...], value = [...]}``.

    Raises
    ------
    ScenarioError
        Naming ``key`` (or its ``frequency``/``value``) and the reason.
    """
    if isinstance(value, Mapping):
        r = KeyReader(value, key)
        raw_f, raw_v = r.raw("frequency"), r.raw("value")
        r.finish()
        for name, raw in (("frequency", raw_f), ("value", raw_v)):
            if not isinstance(raw, list) or not raw:
                raise ScenarioError(f"{key}.{name}: must be a non-empty list of numbers")
        freqs = tuple(number(v, f"{key}.frequency[{i}]") for i, v in enumerate(raw_f))
        values = tuple(number(v, f"{key}.value[{i}]") for i, v in enumerate(raw_v))
        check_density(values, freqs, key)
        return SpectralDensity(values, freqs)
    return SpectralDensity.flat(number(value, key, nonnegative=True))


@dataclass(frozen=True)
class Disturbance:
    """A random force on the table (``[[disturbances]]``).

    Attributes
    ----------
    name : str
        Unique among the disturbances; its source is ``force:<name>``.
    position : tuple of float
        Where the force acts, table frame [m].
    direction : tuple of float
        Its line of action, world frame, unit vector.
    psd : SpectralDensity
        One-sided force PSD [N^2/Hz].
    """

    name: str
    position: tuple[float, float, float]
    direction: tuple[float, float, float]
    psd: SpectralDensity

    def __post_init__(self) -> None:
        check_disturbance(self, "disturbance")


def check_disturbance(disturbance: Disturbance, key: str) -> None:
    """Refuse a disturbance built with wrong values (one :class:`ScenarioError` naming ``key`` and the field)."""
    check_name(disturbance.name, f"{key}.name")
    check_placement(disturbance.position, disturbance.direction, key)
    if not isinstance(disturbance.psd, SpectralDensity):
        raise ScenarioError(f"{key}.psd: must be a SpectralDensity [N^2/Hz], got {type(disturbance.psd).__name__}")


def read_disturbances(top: KeyReader, data: Mapping[str, Any]) -> tuple[Disturbance, ...]:
    """The ``[[disturbances]]`` blocks (their names checked unique with every section's, by
    :func:`isolator.scenario.names.check_scenario_names`)."""
    top.used.add("disturbances")
    out: list[Disturbance] = []
    for i, item in enumerate(table_of_tables(data, "disturbances")):
        key = f"disturbances[{i}]"
        r = KeyReader(item, key)
        name = r.string("name")
        position = r.vector("position")
        direction = r.unit_vector("direction")
        psd = read_density(r.raw("psd"), r.key("psd"))
        r.finish()
        try:
            out.append(Disturbance(name, position, direction, psd))
        except ScenarioError as exc:
            raise ScenarioError(str(exc).replace("disturbance.", f"{key}.", 1)) from None
    return tuple(out)


def vc_spectrum(name: Any, key: str) -> FloorSpectrum:
    """The floor at the limit of a VC class: that class's one-third-octave RMS velocity in each of the 20 bands
    with centres ``10^(n/10)`` Hz, n = 0..19, on x, y and z.

    Raises
    ------
    ScenarioError
        An unknown class, naming ``key`` and the classes.
    """
    if not isinstance(name, str) or name.upper() not in VC_CLASSES:
        raise ScenarioError(f"{key}: unknown vibration criterion {name!r} (one of {', '.join(VC_CLASSES)})")
    level = VC_CLASSES[name.upper()]
    centres = 10.0 ** (np.array(VC_BANDS, dtype=float) / 10)
    return FloorSpectrum(kind="third-octave", frequency=centres,
                         values={a: np.full(centres.size, level) for a in "xyz"})

