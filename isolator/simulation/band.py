"""The settling band as an object: how it was chosen, and the six half-widths it resolves to.

A settling time means nothing without its band. Three kinds:

- ``own``: a fraction of each signal's own peak in the run (the default: the
  scenario's ``[settling] fraction``, the paper's 5 %);
- ``baseline``: a fraction of the peaks of a named baseline run (studies that
  compare designs against one reference judge every design in the same band);
- ``absolute``: six fixed half-widths (the scenario's ``[settling] tolerance``,
  or ``isolator simulate --band``).

Every kind resolves, for one run, to six per-signal absolute half-widths
[m for x, y, z; rad for rx, ry, rz] (:meth:`Band.resolve`). A resolved band
(:meth:`Band.resolved`) carries them, so a study's band written out
(:meth:`Band.to_dict`) can be given back to ``isolator simulate --band`` or
``--band-json`` to reproduce its number exactly.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from isolator.errors import ParameterError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import SIGNALS, Settling

__all__ = ["BAND_KINDS", "MOTION_FLOOR", "READ_BACK", "Band", "as_band", "format_half_widths", "parse_half_widths"]

#: peaks below this are numerical noise: such a signal does not move [m or rad]
MOTION_FLOOR = 1e-13

BAND_KINDS = ("own", "baseline", "absolute")

_UNITS = {"x": "µm", "y": "µm", "z": "µm", "rx": "µrad", "ry": "µrad", "rz": "µrad"}


def _fraction(value: float, key: str) -> float:
    value = float(value)
    if not (math.isfinite(value) and 0.0 < value < 1.0):
        raise ParameterError(f"{key}: must be a fraction between 0 and 1, got {value:g}")
    return value


def _widths(values: Mapping[str, float] | Sequence[float] | np.ndarray, key: str) -> tuple[float, ...]:
    """Six half-widths from a mapping by signal name or a sequence in ``SIGNALS`` order, checked."""
    if isinstance(values, Mapping):
        unknown = sorted(set(values) - set(SIGNALS))
        missing = [k for k in SIGNALS if k not in values]
        if unknown or missing:
            what = f"unknown {', '.join(unknown)}" if unknown else f"missing {', '.join(missing)}"
            raise ParameterError(f"{key}: needs the six signals {', '.join(SIGNALS)}; {what}")
        seq = [values[k] for k in SIGNALS]
    else:
        seq = list(np.asarray(values, dtype=float).reshape(-1))
        if len(seq) != len(SIGNALS):
            raise ParameterError(f"{key}: needs six half-widths ({', '.join(SIGNALS)}), got {len(seq)}")
    out = []
    for name, v in zip(SIGNALS, seq, strict=True):
        try:
            f = float(v)
        except (TypeError, ValueError):
            raise ParameterError(f"{key}: {name} must be a number, got {v!r}") from None
        if not (math.isfinite(f) and f > 0.0):
            raise ParameterError(f"{key}: {name} must be a finite half-width > 0 [m or rad], got {v!r}")
        out.append(f)
    return tuple(out)


#: the baseline of an own band read back (``from_dict``): resolved on the run it was written from
READ_BACK = "written-from"


@dataclass(frozen=True)
class Band:
    """How a settling band is chosen, and (once resolved) its six half-widths.

    Build one with :meth:`own`, :meth:`of_baseline`, :meth:`absolute` or
    :meth:`from_settling`, not with the constructor.

    Attributes
    ----------
    kind : {"own", "baseline", "absolute"}
    fraction : float or None
        Of the peaks (own, baseline); None for an absolute band.
    baseline : str or None
        The baseline run's name (kind ``baseline``).
    half_widths : tuple of six floats or None
        Per signal (``SIGNALS`` order) [m or rad]; None for an own band not yet
        resolved on a run.
    """

    kind: str = "own"
    fraction: float | None = 0.05
    baseline: str | None = None
    half_widths: tuple[float, ...] | None = None

    # -- building ----------------------------------------------------------------
    @classmethod
    def own(cls, fraction: float = 0.05) -> Band:
        """``fraction`` of each signal's own peak in the run."""
        return cls("own", _fraction(fraction, "band.fraction"))

    @classmethod
    def of_baseline(cls, name: str, peaks: Mapping[str, float] | Sequence[float] | np.ndarray,
                    fraction: float = 0.05) -> Band:
        """``fraction`` of the baseline run ``name``'s peaks (by signal name or in ``SIGNALS`` order)
        [m or rad]; a signal the baseline does not move gets ``fraction`` x ``MOTION_FLOOR``."""
        fraction = _fraction(fraction, "band.fraction")
        raw = [peaks[k] for k in SIGNALS] if isinstance(peaks, Mapping) else list(np.ravel(peaks))
        if len(raw) != len(SIGNALS) or not all(math.isfinite(float(p)) for p in raw):
            raise ParameterError(f"band.baseline: needs six finite peaks of the run '{name}'")
        widths = tuple(fraction * max(float(p), MOTION_FLOOR) for p in raw)
        return cls("baseline", fraction, str(name), widths)

    @classmethod
    def absolute(cls, half_widths: Mapping[str, float] | Sequence[float] | np.ndarray, key: str = "band") -> Band:
        """Six fixed half-widths [m or rad], by signal name or in ``SIGNALS`` order."""
        return cls("absolute", None, None, _widths(half_widths, key))

    @classmethod
    def from_settling(cls, settling: Settling) -> Band:
        """The scenario's ``[settling]`` rule: an absolute band from ``tolerance``, else ``fraction`` of the
        own peaks."""
        if settling.tolerance is not None:
            return cls.absolute([settling.band(name, 0.0) for name in SIGNALS], "settling.tolerance")
        return cls("own", float(settling.fraction))  # type: ignore[arg-type]

    @classmethod
    def from_dict(cls, data: Any, key: str = "band") -> Band:
        """A band object as :meth:`to_dict` writes it (a study's ``band``), or a bare mapping of the six
        half-widths; resolved bands keep their kind, fraction and baseline."""
        if not isinstance(data, Mapping):
            raise ParameterError(f"{key}: expected an object with 'half_widths' (or the six signals), "
                                 f"got {type(data).__name__}")
        if "half_widths" not in data:
            return cls.absolute(data, key)
        widths = _widths(data["half_widths"] if data["half_widths"] is not None else {}, f"{key}.half_widths")
        kind = data.get("kind", "absolute")
        if kind not in BAND_KINDS:
            raise ParameterError(f"{key}.kind: must be one of {', '.join(BAND_KINDS)}, got {kind!r}")
        fraction = data.get("fraction")
        if kind == "absolute" or fraction is None:
            return cls("absolute", None, None, widths)
        baseline = data.get("baseline")
        if kind == "own" and widths is not None:  # resolved on the run it was written from: that run's peaks,
            kind, baseline = "baseline", baseline or READ_BACK  # not the peaks of the run it is given to
        return cls(kind, _fraction(fraction, f"{key}.fraction"), None if baseline is None else str(baseline), widths)

    # -- using -------------------------------------------------------------------
    @property
    def is_resolved(self) -> bool:
        return self.half_widths is not None

    def resolve(self, peaks: np.ndarray) -> np.ndarray:
        """Half-widths (..., 6) [m or rad] for runs with these own peaks (..., 6): the band's own half-widths
        once it has them (a band read back from a study keeps those of the run it was resolved on)."""
        peaks = np.asarray(peaks, dtype=float)
        if self.half_widths is None:
            return float(self.fraction) * peaks  # type: ignore[arg-type]
        return np.broadcast_to(np.asarray(self.half_widths, dtype=float), peaks.shape).copy()

    def resolved(self, peaks: np.ndarray | Sequence[float]) -> Band:
        """The band with its half-widths for a run with these own peaks (6,) (the same band when fixed)."""
        if self.half_widths is not None:
            return self
        return Band(self.kind, self.fraction, self.baseline, tuple(float(v) for v in self.resolve(np.asarray(peaks))))

    def still(self, peaks: np.ndarray) -> np.ndarray:
        """Signals that do not move (own peak at numerical noise): settled at 0 whatever the band."""
        return np.asarray(peaks, dtype=float) <= MOTION_FLOOR

    @property
    def widths(self) -> dict[str, float]:
        """The half-widths by signal name [m or rad] (resolved bands)."""
        if self.half_widths is None:
            raise ValueError("band: an own-peak band has half-widths only once resolved on a run")
        return dict(zip(SIGNALS, self.half_widths, strict=True))

    def how(self) -> str:
        """How the band was chosen, in words."""
        if self.kind == "own":
            return f"{100 * float(self.fraction):g} % of each signal's own peak"  # type: ignore[arg-type]
        if self.kind == "baseline" and self.baseline == READ_BACK:
            return f"{100 * float(self.fraction):g} % of the peaks of the run it was written from"  # type: ignore[arg-type]
        if self.kind == "baseline":
            return f"{100 * float(self.fraction):g} % of the {self.baseline} run's peaks"  # type: ignore[arg-type]
        return "absolute half-widths"

    def describe(self) -> str:
        """One line: how it was chosen and, when resolved, the six half-widths in µm / µrad."""
        if self.half_widths is None:
            return f"settling band: {self.how()}"
        return f"settling band: {self.how()}: ±(" + format_half_widths(self, micro=True) + ")"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``kind``, ``fraction``, ``baseline`` (or null), ``half_widths`` by signal [m, rad]."""
        return {"kind": self.kind, "fraction": self.fraction, "baseline": self.baseline,
                "half_widths": None if self.half_widths is None else self.widths}

    def option(self) -> str:
        """The half-widths as ``isolator simulate --band`` takes them (``x=...,y=...,...,rz=...``)."""
        return format_half_widths(self)


def format_half_widths(band: Band, micro: bool = False) -> str:
    """``x=1.2e-06,...`` [m, rad] (or ``x 1.2 µm, ...`` with ``micro``) of a resolved band."""
    if micro:
        return ", ".join(f"{k} {v * 1e6:.4g} {_UNITS[k]}" for k, v in band.widths.items())
    return ",".join(f"{k}={v:.17g}" for k, v in band.widths.items())


def parse_half_widths(text: str, key: str = "--band") -> Band:
    """An absolute band from ``x=1e-6,y=1e-6,z=1e-6,rx=1e-6,ry=1e-6,rz=1e-6`` [m, rad]."""
    values: dict[str, float] = {}
    for item in text.split(","):
        name, sep, value = item.strip().partition("=")
        name = name.strip()
        if not sep or name not in SIGNALS:
            raise ParameterError(f"{key}: expected {','.join(f'{k}=VALUE' for k in SIGNALS)} [m, rad], got '{item}'")
        if name in values:
            raise ParameterError(f"{key}: {name} given twice")
        try:
            values[name] = float(value)
        except ValueError:
            raise ParameterError(f"{key}: {name} must be a number [m or rad], got '{value.strip()}'") from None
    return Band.absolute(values, key)


def as_band(rule: Band | Settling) -> Band:
    """A band from either a :class:`Band` or a scenario's ``[settling]`` rule."""
    return rule if isinstance(rule, Band) else Band.from_settling(rule)


check_public(globals(), ("Band"))
