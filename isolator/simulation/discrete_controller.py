"""The discrete controller the simulation runs and ``controller.json`` holds: sensors in, forces out.

The contract is ``docs/scenario-format.md``, section "Sensors in the scenario, output feedback and
exported controllers". At each sample ``t_k = k / sample_rate`` the controller receives every sensor's
reading minus its reading at the initial equilibrium (``y``, SI units) and the carriages' raw positions
(``q``, m) and returns the actuators' force commands (``u``, N)::

    u_k     = C x_k + D y_k        (from the readings at t_k; held until t_{k+1})
    x_{k+1} = A x_k + B y_k

Gain scheduling: a schedule holds design points, each with the carriages' positions ``q`` and its
``(A, B, C, D)`` (the same state dimension, in corresponding state coordinates). One carriage
(``schedule_carriage``) schedules: with ``q_i <= q < q_{i+1}`` its positions at two neighbouring points and
``w = (q - q_i) / (q_{i+1} - q_i)``, every matrix is ``(1 - w) M_i + w M_{i+1}`` entry by entry, and that
interpolated ``(A, B, C, D)`` is applied as above. Below the first point (or a NaN position) the first
point's matrices apply, above the last the last's (clamped). The other carriages' positions are recorded
in the points but not used.

:meth:`DiscreteController.step` is the reference the generated C (:func:`controllers.feedback.export.write_c`)
equals to rounding.
"""

from __future__ import annotations

import itertools
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from isolator.analysis.sampling import check_sample_rate
from isolator.errors import ParameterError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.scenario.files import parse_json, read_input_text
from isolator.scenario.names import escaped
from isolator.scenario.output_files import write_output_text
from isolator.simulation.controller_schema import check_controller_data, check_states, warn_if_unstable

__all__ = ["DiscreteController", "ScheduleEntry"]
_MATRICES = ("A", "B", "C", "D")


def _matrix(value: object, shape: tuple[int, int], what: str, dims: str) -> np.ndarray:
    """``value`` as a read-only float matrix of ``shape``, or a ParameterError naming ``what``."""
    try:
        m = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{what}: must be a matrix of numbers, got {type(value).__name__}") from None
    m = m.reshape(shape) if m.size == 0 and 0 in shape else m
    if m.shape != shape:
        raise ParameterError(f"{what}: must be {shape[0]} x {shape[1]} ({dims}), got shape {m.shape}")
    if not np.all(np.isfinite(m)):
        raise ParameterError(f"{what}: every entry must be finite")
    m.setflags(write=False)
    return m


@dataclass(frozen=True, eq=False)
class ScheduleEntry:
    """One design point of a scheduled controller.

    Attributes
    ----------
    q : tuple of float
        Every carriage's position along its axis at this design [m], carriages in file order.
    A, B, C, D : numpy.ndarray
        The discrete state-space matrices designed there (see :class:`DiscreteController`).
    """

    q: Sequence[float]
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray


@dataclass(frozen=True, eq=False)
class DiscreteController:
    """A discrete-time controller from the sensors' readings to the actuators' force commands.

    Attributes
    ----------
    sample_rate : float
        [Hz] at which :meth:`step` is called (``> 0``).
    sensors, actuators, carriages : tuple of str
        Names in file order: the inputs ``y`` (sensor units: m, m/s or m/s^2), the outputs ``u`` [N], and
        the positions ``q`` [m]. At least one sensor and one actuator.
    method : str
        The design's name (e.g. ``"lqg"``).
    A, B, C, D : numpy.ndarray, optional
        ``x+ = A x + B y``, ``u = C x + D y``: shapes ``n x n``, ``n x sensors``, ``actuators x n``,
        ``actuators x sensors`` (``n`` may be 0: a static gain ``D``). Not given with a schedule.
    schedule : tuple of ScheduleEntry
        Design points instead of ``A .. D`` (see the module's description), ``schedule_carriage``'s
        positions strictly increasing.
    schedule_carriage : int
        Index of the carriage that schedules (file order).
    settings : dict
        The design's settings (JSON values), recorded as given.
    delay : bool
        Whether the design includes one sample of computation delay: :meth:`step` (and the C code) still
        returns ``u_k`` at ``t_k``, and the simulation applies it from ``t_{k+1}`` to ``t_{k+2}`` (the latency
        the design assumed).
    """

    sample_rate: float
    sensors: Sequence[str]
    actuators: Sequence[str]
    carriages: Sequence[str] = ()
    method: str = "custom"
    A: np.ndarray | None = None
    B: np.ndarray | None = None
    C: np.ndarray | None = None
    D: np.ndarray | None = None
    schedule: Sequence[ScheduleEntry] = ()
    schedule_carriage: int = 0
    settings: Mapping[str, Any] = field(default_factory=dict)
    delay: bool = False

    def __post_init__(self) -> None:
        put = lambda name, value: object.__setattr__(self, name, value)  # noqa: E731
        put("sample_rate", check_sample_rate(self.sample_rate))
        for key in ("sensors", "actuators", "carriages"):
            names = getattr(self, key)
            if isinstance(names, str) or not all(isinstance(n, str) for n in names):
                raise ParameterError(f"{key}: must be a sequence of names (strings)")
            put(key, tuple(names))
            if key != "carriages" and not names:
                raise ParameterError(f"{key}: at least one is needed")
        try:
            put("settings", json.loads(json.dumps(dict(self.settings), allow_nan=False)))
        except (TypeError, ValueError) as error:
            raise ParameterError(f"settings: must hold JSON values ({error})") from None
        p, m = len(self.sensors), len(self.actuators)
        given = [k for k in _MATRICES if getattr(self, k) is not None]
        if self.schedule:
            if given:
                raise ParameterError(f"{given[0]}: give either the matrices or a schedule, not both")
            put("schedule", self._check_schedule(p, m))
            return
        if missing := [k for k in _MATRICES if getattr(self, k) is None]:
            raise ParameterError(f"{missing[0]}: missing (the matrices A, B, C, D, or a schedule)")
        for k, v in zip(_MATRICES, self._check_matrices(self.A, self.B, self.C, self.D, p, m, ""), strict=True):
            put(k, v)

    @staticmethod
    def _check_matrices(A: Any, B: Any, C: Any, D: Any, p: int, m: int, where: str
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        shape = np.shape(A)
        n = shape[0] if len(shape) == 2 else (0 if np.size(A) == 0 else -1)
        if n < 0:
            raise ParameterError(f"{where}A: must be a square matrix (states x states), got shape {shape}")
        check_states(n, f"{where}A")
        return (_matrix(A, (n, n), where + "A", "states x states"),
                _matrix(B, (n, p), where + "B", "states x sensors"),
                _matrix(C, (m, n), where + "C", "actuators x states"),
                _matrix(D, (m, p), where + "D", "actuators x sensors"))

    def _check_schedule(self, p: int, m: int) -> tuple[ScheduleEntry, ...]:
        nc = len(self.carriages)
        if not (isinstance(self.schedule_carriage, int) and 0 <= self.schedule_carriage < nc):
            raise ParameterError(f"schedule_carriage: must index one of the {nc} carriages (a schedule needs "
                                 f"one), got {self.schedule_carriage!r}")
        entries: list[ScheduleEntry] = []
        for i, e in enumerate(self.schedule):
            where = f"schedule[{i}]."
            if not isinstance(e, ScheduleEntry):
                raise ParameterError(f"schedule[{i}]: must be a ScheduleEntry, got {type(e).__name__}")
            q = np.array(e.q, dtype=float).ravel()
            if q.shape != (nc,) or not np.all(np.isfinite(q)):
                raise ParameterError(f"{where}q: must be {nc} finite positions (one per carriage), got {e.q!r}")
            mats = self._check_matrices(e.A, e.B, e.C, e.D, p, m, where)
            if entries and mats[0].shape != entries[0].A.shape:
                raise ParameterError(f"{where}A: must have the first point's {entries[0].A.shape[0]} states, "
                                     f"got {mats[0].shape[0]}")
            entries.append(ScheduleEntry(tuple(float(v) for v in q), *mats))
        qs = [e.q[self.schedule_carriage] for e in entries]
        if any(b <= a for a, b in itertools.pairwise(qs)):
            raise ParameterError(f"schedule: q of carriage {self.schedule_carriage} must increase strictly "
                                 f"from point to point, got {qs}")
        return tuple(entries)

    @property
    def states(self) -> int:
        """Number of controller states ``n``."""
        return int(self.schedule[0].A.shape[0] if self.schedule else self.A.shape[0])  # type: ignore[union-attr]

    def matrices(self, q: Sequence[float] | np.ndarray | None = None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(A, B, C, D)`` at the carriages' positions ``q`` [m] (interpolated and clamped when scheduled)."""
        if not self.schedule:
            return self.A, self.B, self.C, self.D  # type: ignore[return-value]
        q_row = np.full(max(len(self.carriages), 1), math.nan) if q is None else np.asarray(q, dtype=float).ravel()
        w = self.schedule_weights(q_row[None, :])[0]
        return tuple(sum(wj * getattr(e, k) for wj, e in zip(w, self.schedule, strict=True))
                     for k in _MATRICES)

    def check_names(self, scenario: Scenario) -> None:
        """Refuse a controller for another table: its sensors, actuators and carriages must be the scenario's
        ``[[sensors]]``, ``[[actuators]]`` and ``[[carriages]]`` names in file order (one
        :class:`ParameterError` naming the first that differs)."""
        for key, ours in (("sensors", scenario.sensors), ("actuators", scenario.actuators),
                          ("carriages", scenario.carriages)):
            names, theirs = tuple(x.name for x in ours), tuple(getattr(self, key))
            for i in range(max(len(names), len(theirs))):
                mine = names[i] if i < len(names) else None
                other = theirs[i] if i < len(theirs) else None
                if mine == other:
                    continue
                if other is None or mine is None:  # one list ends first: count them, no "has None"
                    extra = f"its {key}[{i}] is {other!r}" if mine is None else f"[[{key}]][{i}] is {mine!r}"
                    raise ParameterError(f"controller.{key}: the controller has {len(theirs)} where the scenario's "
                                         f"[[{key}]] has {len(names)} ({extra}; in file order)")
                raise ParameterError(
                    f"controller.{key}[{i}]: {other!r} where the scenario's [[{key}]] has {mine!r} "
                    f"({len(theirs)} against {len(names)}, in file order)")

    def schedule_weights(self, q: np.ndarray) -> np.ndarray:
        """Each design point's weight (N, points) at the carriages' positions ``q`` (N, carriages) [m]:
        :meth:`matrices` at ``q[i]`` is ``sum_j w[i, j] M_j`` (ones (N, 1) without a schedule)."""
        q = np.asarray(q, dtype=float).reshape(-1, max(len(self.carriages), 1))
        if len(self.schedule) < 2:
            return np.ones((q.shape[0], 1))
        c = self.schedule_carriage
        points = np.array([e.q[c] for e in self.schedule])
        qs = q[:, c]
        k = np.clip(np.searchsorted(points, qs, side="right") - 1, 0, points.size - 2)
        w = (qs - points[k]) / (points[k + 1] - points[k])
        above = qs >= points[-1]
        k, w = np.where(above, points.size - 2, k), np.where(above, 1.0, w)
        below = ~(qs > points[0])  # below the range, or NaN: the first point
        k, w = np.where(below, 0, k), np.where(below, 0.0, w)
        out = np.zeros((qs.size, points.size))
        rows = np.arange(qs.size)
        out[rows, k] = 1.0 - w
        out[rows, k + 1] += w
        return out

    def reset(self) -> np.ndarray:
        """The state at rest: zeros (``n``,)."""
        return np.zeros(self.states)

    def step(self, x: np.ndarray, y: np.ndarray, q: Sequence[float] | np.ndarray | None = None
             ) -> tuple[np.ndarray, np.ndarray]:
        """One sample: ``(x_next, u)`` from the state ``x``, the readings ``y`` and positions ``q`` [m] at ``t_k``.

        ``u = C x + D y`` [N] is the command from ``t_k``; ``x_next = A x + B y``.
        """
        if q is not None and self.schedule and np.size(q) != len(self.carriages):  # read only when scheduled
            raise ParameterError(f"q: must hold one position per carriage ({len(self.carriages)}), got {np.size(q)}")
        A, B, C, D = self.matrices(q)
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        for name, value, size, what in (("x", x, self.states, "states"), ("y", y, len(self.sensors), "sensors")):
            if value.shape != (size,):
                raise ParameterError(f"{name}: must be ({size},), one value per {what[:-1]}, got shape {value.shape}")
        return A @ x + B @ y, C @ x + D @ y

    def to_dict(self) -> dict[str, Any]:
        """The JSON data of ``controller.json``."""
        out: dict[str, Any] = {"sample_rate": self.sample_rate, "sensors": list(self.sensors),
                               "actuators": list(self.actuators), "carriages": list(self.carriages),
                               "method": self.method, "delay": bool(self.delay), "settings": self.settings}
        if self.schedule:
            mid = self.schedule[(len(self.schedule) - 1) // 2]  # nominal design, for readers of A .. D only
            out.update({k: getattr(mid, k).tolist() for k in _MATRICES})
            out["schedule_carriage"] = self.schedule_carriage
            out["schedule"] = [{"q": list(e.q), **{k: getattr(e, k).tolist() for k in _MATRICES}}
                               for e in self.schedule]
        else:
            out.update({k: getattr(self, k).tolist() for k in _MATRICES})
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> DiscreteController:
        """The controller of :meth:`to_dict`'s data (with a ``schedule``, its top-level ``A .. D`` are ignored),
        checked against the schema first (:func:`~isolator.simulation.controller_schema.check_controller_data`:
        strict types, unknown keys warned about; one :class:`ParameterError` naming ``controller.<key>``)."""
        checked = check_controller_data(data)
        schedule = checked.pop("schedule", None)
        if schedule:
            checked["schedule"] = [ScheduleEntry(e["q"], *(e[k] for k in _MATRICES)) for e in schedule]
        return cls(**checked)

    def to_json(self, path: str | Path) -> Path:
        """Write ``controller.json`` (``path`` a file, or a folder to write it in); returns the file."""
        target = Path(path) / "controller.json" if Path(path).is_dir() else Path(path)
        write_output_text(target, json.dumps(self.to_dict(), indent=1, allow_nan=False) + "\n")
        return target

    @classmethod
    def from_json(cls, path: str | Path) -> DiscreteController:
        """Read ``controller.json`` (``path`` the file or its folder)."""
        source = Path(path) / "controller.json" if Path(path).is_dir() else Path(path)
        text = read_input_text(source, "", error=ParameterError, bom=False)  # errors start with the path
        where = escaped(source, 120)
        data = parse_json(text, where)  # a key given twice, NaN, bad syntax: one line naming the file
        controller = cls.from_dict(data)  # type: ignore[arg-type]  # not a mapping: the schema says so
        points = controller.schedule or (controller,)
        warn_if_unstable([e.A for e in points], f"controller '{where}'")  # type: ignore[misc]
        return controller


check_public(globals())
