"""What the table does after a run ends: the free motion about the final rest, from the linear model.

A settling time read from a finite run stands only if no signal leaves its band after the run's end.
That is decided from the physics, not by waiting: from the run's last state ``x(T)`` the carriages are
parked and nothing forces the table, so to first order the state moves as

``x(t) - x* = exp(A (t - T)) (x(T) - x*)``

about the final rest ``x*``, ``A`` the model's Jacobian there, and each signal's deviation from its final
value is ``C (x(t) - x*)`` with ``C`` the signals' Jacobian at ``x*``. With ``A = V diag(lambda) V^-1``
(the exact eigen-decomposition) signal ``i`` deviates by

``o_i + Re sum_k w_ik exp(lambda_k (t - T))``:

``o`` from the modes at ``lambda = 0`` is what the motion keeps for good (a pneumatic group's air, its
valve shut inside its dead band; the quaternion's norm, which no signal sees), and
``sum_k |w_ik| exp(Re lambda_k (t - T))`` bounds the rest. A signal whose ``|o_i|`` plus that bound is
inside its band at ``T`` stays inside; otherwise its deviation is evaluated every
:data:`STEP_ANGLE` radians of its fastest mode that matters, up to the time from which the bound keeps it
inside (the modes that cannot move it by :data:`NEGLIGIBLE` of its band are left to the bound).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from isolator.model.signals import signal_jacobian
from isolator.model.variants import Model
from isolator.numerics.native import PLAIN_FLAGS, MappedFunction
from isolator.scenario.definitions import SIGNALS

__all__ = ["NEGLIGIBLE", "STEP_ANGLE", "FreeMotions", "FreeTail", "RestModes", "TailVerdict", "free_tail", "free_tails",
           "micro"]

#: points per radian of the fastest mode that matters: the deviation is read every 0.2 rad of it
STEP_ANGLE = 0.2
#: a mode moving a signal by less than this fraction of its band is left to the bound
NEGLIGIBLE = 1e-4
#: most points a signal's free motion is read at (longer horizons are read more coarsely)
MAX_POINTS = 200_000
#: points the largest excursion is read at between its neighbours on the coarse grid
REFINE = 41
#: eigenvalues below this fraction of the largest are conserved quantities (lambda = 0)
ZERO = 1e-9
#: margin of :meth:`FreeMotions.inside` for the rounding of its sums (their order differs from
#: :meth:`FreeTail.judge`'s), relative to the sum of every mode's weight
MARGIN = 1e-9


def micro(name: str, value: float) -> str:
    """A signal's value [m or rad] in µm or µrad, 3 significant digits."""
    return f"{value * 1e6:.3g} {'µm' if name in ('x', 'y', 'z') else 'µrad'}"


@dataclass(frozen=True)
class TailVerdict:
    """Per signal (``SIGNALS`` order), what the free motion after the run's end does in its band.

    Attributes
    ----------
    end : float
        The run's end [s].
    leaves : ndarray of bool (6,)
        Outside the band at some time after the end.
    excess : ndarray (6,)
        The largest ``|deviation| - band`` after the end [m or rad] (<= 0: inside throughout).
    when : ndarray (6,)
        When that largest excess happens [s].
    enters : ndarray (6,)
        From when the signal stays inside its band [s] (the end when it never leaves; inf when it comes to
        rest outside).
    offset : ndarray (6,)
        Where the free motion comes to rest, from the final value [m or rad].
    band : ndarray (6,)
        The half-widths judged against [m or rad].
    """

    end: float
    leaves: np.ndarray
    excess: np.ndarray
    when: np.ndarray
    enters: np.ndarray
    offset: np.ndarray
    band: np.ndarray

    def needed(self, i: int) -> float:
        """A duration [s] (tenths, rounded up) whose run shows row ``i`` settled."""
        needed = math.ceil(10 * float(self.enters[i]) * (1 + 1e-12)) / 10
        return needed + 0.1 if needed <= self.enters[i] else needed

    def reason(self, i: int, outside_at_end: bool, rest_note: str = "") -> str:
        """Why signal ``i`` shows no settling time, in one true sentence (``rest_note``: what keeps the
        table off its final rest, said when the signal comes to rest outside its band)."""
        name = SIGNALS[i]
        over = f"{micro(name, float(self.excess[i]))} ({100 * self.excess[i] / self.band[i]:.3g} % of its band)"
        if not math.isfinite(self.enters[i]):
            why = f": {rest_note}" if rest_note else ""
            return (f"{name} comes to rest {micro(name, abs(float(self.offset[i])))} from its final value, outside its "
                    f"band ±{micro(name, float(self.band[i]))}{why}; a longer run cannot help")
        needed = self.needed(i)
        if outside_at_end:
            return (f"{name} is still outside its band when the run ends at {self.end:.4g} s, by up to {over} "
                    f"after it (at {self.when[i]:.4g} s), and stays inside from {self.enters[i]:.4g} s by the linear "
                    f"model about the final rest; lengthen simulation.duration to {needed:g} s or more")
        return (f"{name} leaves its band again after the run ends at {self.end:.4g} s, by {over} at "
                f"{self.when[i]:.4g} s, and stays inside from {self.enters[i]:.4g} s by the linear model about the "
                f"final rest; lengthen simulation.duration to {needed:g} s or more")


@dataclass(frozen=True)
class FreeTail:
    """The six signals' free motion after a run's end (see the module's description).

    Attributes
    ----------
    end : float
        The run's end ``T`` [s].
    rates : ndarray (m,) complex
        The eigenvalues ``lambda`` of the modes that move [1/s].
    weights : ndarray (6, m) complex
        Each mode's ``w_ik`` [m or rad].
    offset : ndarray (6,)
        ``o``: where the free motion comes to rest, from the final values [m or rad].
    rest : ndarray (n_states,)
        The state the free motion comes to rest in (``x*`` moved by the conserved modes).
    modes : ndarray (n_states, m) complex
        Each moving mode's part of the state's deviation from ``x*`` at the end (its eigenvector times its
        amplitude).
    shift : ndarray (n_states,)
        ``rest - x*``.
    """

    end: float
    rates: np.ndarray
    weights: np.ndarray
    offset: np.ndarray
    rest: np.ndarray
    modes: np.ndarray
    shift: np.ndarray

    def outputs(self, matrix: np.ndarray) -> FreeTail:
        """The free motion of other outputs linear in the state, ``matrix`` (k, n_states) their Jacobian at
        the final rest (a point's displacement on some axes, for its window)."""
        matrix = np.asarray(matrix, dtype=float)
        return FreeTail(self.end, self.rates, matrix @ self.modes, matrix @ self.shift, self.rest, self.modes,
                        self.shift)

    def deviation(self, i: int, t: np.ndarray, modes: np.ndarray | None = None) -> np.ndarray:
        """Signal ``i``'s deviation from its final value at times ``t`` [s] (>= ``end``), by ``modes``
        (indices; all by default) [m or rad]."""
        k = np.arange(self.rates.size) if modes is None else modes
        phase = np.exp(np.outer(np.asarray(t, dtype=float) - self.end, self.rates[k]))
        return self.offset[i] + (phase @ self.weights[i, k]).real

    def judge(self, band: np.ndarray) -> TailVerdict:
        """What the free motion does in the band of half-widths ``band`` (one per output row) [m or rad]."""
        band = np.asarray(band, dtype=float)
        rows = self.weights.shape[0]
        leaves, excess = np.zeros(rows, dtype=bool), np.zeros(rows)
        when, enters = np.full(rows, self.end), np.full(rows, self.end)
        for i in range(rows):
            leaves[i], excess[i], when[i], enters[i] = self._signal(i, float(band[i]))
        return TailVerdict(self.end, leaves, excess, when, enters, self.offset.copy(), band)

    def _signal(self, i: int, band: float) -> tuple[bool, float, float, float]:
        """(leaves, largest excess, its time, from when inside) of signal ``i`` in ``band``."""
        size = np.abs(self.weights[i])
        offset = abs(float(self.offset[i]))
        start = offset + float(size.sum())
        if start <= band:
            return False, start - band, self.end, self.end
        if offset >= band:  # at rest outside: from when the motion stays on the far side is beside the point
            return True, offset - band, math.inf, math.inf
        keep = size > NEGLIGIBLE * band
        slack = float(size[~keep].sum())
        if not keep.any():  # only modes too small to read, about an offset at the band's edge: the bound decides
            return (True, start - band, math.inf, math.inf) if start > band else (False, start - band, self.end,
                                                                                  self.end)
        rates, sizes = self.rates[keep], size[keep]
        room = band - offset - slack
        decay = float(np.max(rates.real))
        if room <= 0.0 or decay >= 0.0:  # no time from which the bound keeps it inside: read a long way
            horizon = 50.0 / max(-decay, 1e-3)
        else:
            horizon = max(0.0, math.log(max(float(sizes.sum()) / room, 1.0)) / -decay)
        fastest = float(np.max(np.abs(rates)))
        count = int(min(MAX_POINTS, max(2, math.ceil(horizon * fastest / STEP_ANGLE) + 1)))
        t = self.end + np.linspace(0.0, horizon, count)
        modes = np.flatnonzero(keep)
        gap = np.abs(self.deviation(i, t, modes)) - band
        top = int(np.argmax(gap))
        fine = np.linspace(t[max(top - 1, 0)], t[min(top + 1, count - 1)], REFINE)  # the largest, closely
        fine_gap = np.abs(self.deviation(i, fine, modes)) - band
        best = int(np.argmax(fine_gap))
        outside = np.flatnonzero(gap > 0.0)
        if not outside.size:
            return False, float(fine_gap[best]), float(fine[best]), self.end
        last = int(outside[-1])
        enters = float(t[min(last + 1, count - 1)])
        return True, float(fine_gap[best]), float(fine[best]), enters


@lru_cache(maxsize=16)
def _jacobians(model: Model) -> tuple[MappedFunction, MappedFunction]:
    """The model's state Jacobian and the signals' Jacobian for many runs at once, compiled to compute as
    casadi's evaluator does (:data:`~isolator.numerics.native.PLAIN_FLAGS`: the same numbers, bit for bit)."""
    signals = signal_jacobian(model.variant, model.n_states)
    return (MappedFunction(model.state_jacobian, f"isolator_tail_a_{model.tag}", block=16, flags=PLAIN_FLAGS),
            MappedFunction(signals, f"isolator_tail_c_{model.tag}", block=16, flags=PLAIN_FLAGS))


def free_tail(model: Model, p: np.ndarray, final_state: np.ndarray, positions: np.ndarray,
              reference: np.ndarray, last: np.ndarray, end: float) -> FreeTail:
    """The free motion after a run's end.

    Parameters
    ----------
    model : Model
    p : ndarray
        Parameter vector.
    final_state : ndarray (n_states,)
        The final rest ``x*`` (the final equilibrium's state).
    positions : ndarray
        The carriages' final coordinates [m].
    reference : ndarray (n_states,)
        The state the signals are measured from (the initial equilibrium's).
    last : ndarray (n_states,)
        The run's state at its end.
    end : float
        The run's end [s].
    """
    p, final_state, positions, reference, last = (np.asarray(a, dtype=float)[None] for a in (
        p, final_state, positions, reference, last))
    return free_tails(model, p, final_state, positions, reference, last, end)[0]


def free_tails(model: Model, p: np.ndarray, final_state: np.ndarray, positions: np.ndarray,
               reference: np.ndarray, last: np.ndarray, end: float, modes: RestModes | None = None
               ) -> list[FreeTail]:
    """:func:`free_tail` of several runs at once, each argument but ``end`` stacked (runs, ...); ``modes``: their
    :class:`RestModes`, when the caller has them already."""
    motions = FreeMotions.of(model, p, final_state, positions, reference, last, end, modes)
    return [motions.tail(k) for k in range(motions.count)]


@dataclass(frozen=True)
class RestModes:
    """The linear model about several final rests, decomposed side by side (one mapped Jacobian call, one
    stacked eigen-decomposition): what the free motion after a run's end needs of the rest, whatever the run
    (a simulator keeps it with its rests, so that runs of the same table decompose it once).

    Attributes
    ----------
    rates, vectors : ndarray (runs, n_states) and (runs, n_states, n_states) complex
        Eigenvalues [1/s] and eigenvectors of the state Jacobians at the final rests.
    signals : ndarray (runs, 6, n_states)
        The signals' Jacobians there.
    """

    rates: np.ndarray
    vectors: np.ndarray
    signals: np.ndarray

    @classmethod
    def of(cls, model: Model, p: np.ndarray, final_state: np.ndarray, positions: np.ndarray,
           reference: np.ndarray) -> RestModes:
        """The decompositions (arguments stacked (runs, ...) as :func:`free_tails` takes them)."""
        state_jacobian, signal_jacobian = _jacobians(model)
        inputs = np.array([model.layout.rest_inputs(q) for q in positions])
        a = state_jacobian(final_state, inputs, np.asarray(p, dtype=float))[0]
        c = signal_jacobian(final_state, np.asarray(reference, dtype=float))[0]
        rates, vectors = np.linalg.eig(a)
        return cls(rates, vectors, c)


@dataclass(frozen=True)
class FreeMotions:
    """The free motions of several runs after their end, decomposed side by side (one mapped Jacobian call,
    one stacked eigen-decomposition), each run's :class:`FreeTail` built only when asked for: a batch asks for
    those of runs whose signals :meth:`inside` cannot keep in their bands.

    Attributes
    ----------
    end : float
        The runs' end [s].
    rates, vectors : ndarray (runs, n_states) and (runs, n_states, n_states) complex
        Eigenvalues [1/s] and eigenvectors of the state Jacobians at the final rests.
    signals : ndarray (runs, 6, n_states)
        The signals' Jacobians there.
    deviation : ndarray (runs, n_states)
        The runs' end states from their final rests.
    final_state : ndarray (runs, n_states)
        The final rests ``x*``.
    """

    end: float
    rates: np.ndarray
    vectors: np.ndarray
    signals: np.ndarray
    deviation: np.ndarray
    final_state: np.ndarray

    @classmethod
    def of(cls, model: Model, p: np.ndarray, final_state: np.ndarray, positions: np.ndarray, reference: np.ndarray,
           last: np.ndarray, end: float, modes: RestModes | None = None) -> FreeMotions:
        """The decompositions (arguments as :func:`free_tails` takes them; ``modes`` theirs, when known)."""
        if modes is None:
            modes = RestModes.of(model, p, final_state, positions, reference)
        return cls(float(end), modes.rates, modes.vectors, modes.signals, np.asarray(last, dtype=float) - final_state,
                   final_state)

    @property
    def count(self) -> int:
        """Runs."""
        return int(self.rates.shape[0])

    def tail(self, k: int) -> FreeTail:
        """Run ``k``'s free motion."""
        vectors, deviation, rates = self.vectors[k], self.deviation[k], self.rates[k]
        try:
            amplitude = np.linalg.solve(vectors, deviation)
        except np.linalg.LinAlgError:
            amplitude = np.linalg.lstsq(vectors, deviation, rcond=None)[0]
        zero = np.abs(rates) <= ZERO * max(float(np.max(np.abs(rates), initial=0.0)), 1.0)
        modes = vectors * amplitude[None, :]
        weights, shift = self.signals[k] @ modes, modes[:, zero].sum(axis=1).real
        return FreeTail(self.end, rates[~zero], weights[:, ~zero], weights[:, zero].sum(axis=1).real,
                        self.final_state[k] + shift, modes[:, ~zero], shift)

    def inside(self, band: np.ndarray) -> np.ndarray:
        """Which signals (runs, 6) provably stay inside their bands ``band`` (runs, 6) [m or rad] after the
        end: where ``|o_i| + sum_k |w_ik|`` (:meth:`FreeTail.judge`'s first test) is inside with a margin
        of :data:`MARGIN` for rounding (the runs' :meth:`tail` then need not be built: they would be judged
        inside; the margin is relative to every mode's weight, so a conserved part that cancels is covered).
        False where that is not shown, or a run's eigenvectors are singular."""
        try:
            amplitude = np.linalg.solve(self.vectors, self.deviation[..., None].astype(complex))[..., 0]
        except np.linalg.LinAlgError:
            return np.zeros((self.count, 6), dtype=bool)
        scale = np.max(np.abs(self.rates), axis=1, initial=0.0)
        zero = np.abs(self.rates) <= ZERO * np.maximum(scale, 1.0)[:, None]  # (runs, modes)
        weights = self.signals @ (self.vectors * amplitude[:, None, :])  # (runs, 6, modes)
        offset = np.abs(np.sum(np.where(zero[:, None, :], weights, 0.0), axis=2).real)
        size = np.abs(weights)
        bound = offset + np.sum(np.where(zero[:, None, :], 0.0, size), axis=2)
        return bound + MARGIN * np.sum(size, axis=2) <= np.asarray(band, dtype=float)
