"""Stability and margins of a sampled output-feedback loop, broken at the plant's input.

The plant is discrete (``x+ = Ap x + Bp u``, ``y = Cp x + Dp u``: commands ``u`` [N] to readings ``y``),
the controller too (``xc+ = Ak xc + Bk y``, ``u = Ck xc + Dk y``): the controller's output *is* the
command, so the loop is ``u = K(z) P(z) u`` and ``M(z) = K(z) P(z)`` is its return at the plant's input in
the positive-feedback sense (``L = -M`` in the usual negative-feedback convention; the critical point is
``M = +1``).

* Stability: the spectral radius of the closed loop's state matrix (disturbance-free form), stable
  below 1.
* Loop-at-a-time margins at each actuator ``i`` (loop ``i`` broken at the plant's input, the others
  closed): the return ``l_i = 1 - 1 / S_ii`` with ``S = (I - M)^-1`` (a Schur complement), so closing
  loop ``i`` through a gain ``g`` is singular on the unit circle exactly where ``g l_i = 1``. Critical
  gains are ``1 / l_i`` where ``l_i`` is real (``0``, the Nyquist frequency, and every crossing of the
  real axis, refined by bisection on the exact response); the gain margins are the nearest above
  and below 1 (``inf`` and ``0`` when there is none; negative gains are not considered). The phase margin
  is ``min |arg l_i|`` where ``|l_i| = 1`` (refined likewise; ``inf`` without a crossover). The disk
  margin (balanced, skew 0) of loop ``i`` is ``1 / max |S_ii - 1/2|``.
* The multiloop disk margin at the plant's input (simultaneous independent complex perturbations of all
  actuators, skew 0): ``1 / max mu(S - I/2)`` as :func:`control.disk_margins` defines it. That function
  calls SLICOT's ``ab13md`` at every frequency (about 20 ms each for 12 loops, too slow for a check over
  many cases), so ``mu(X)``, ``X = S - I/2``, is bounded here by ``sigma_max(D X D^-1)`` with the
  diagonal ``D`` of Osborne's scaling (the standard upper bound of ``mu``, at one ``D`` rather than the
  best): the disk margin given is a lower bound (conservative), within a few per cent of
  :func:`control.disk_margins`'s in the tests.

The frequency grid: 0, 400 points logarithmically spaced from ``1e-5`` of the sample rate to the Nyquist
frequency, and the frequency of each closed-loop pole and its half-power edges (where the narrow peaks
are); the multiloop disk margin's peak is refined between its grid neighbours.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from isolator.analysis.closed_loop import SampledLoop
from isolator.analysis.sampling import closed_loop_matrix
from isolator.scenario.arguments import check_public

__all__ = ["LoopMargins", "closed_loop_matrix", "loop_margins", "sampled_margins"]

_POINTS = 400
#: bisections of a grid interval where a margin is reached
_BISECTIONS = 10


@dataclass(frozen=True)
class LoopMargins:
    """Margins of a stable sampled loop at the plant's input (see the module's description).

    Attributes
    ----------
    gain_margin, gain_margin_low : ndarray (actuators,)
        Loop-at-a-time: the gain factors [-] above and below 1 that make the loop unstable (``inf``, ``0``
        when none does).
    gain_frequency : ndarray (actuators,)
        [Hz] where the nearer of the two gain margins (in dB) is reached.
    phase_margin : ndarray (actuators,)
        Loop-at-a-time phase margins [deg] (``inf`` when ``|l_i|`` never crosses 1).
    phase_frequency : ndarray (actuators,)
        [Hz] of each phase margin (NaN without a crossover).
    loop_disk_margin : ndarray (actuators,)
        Loop-at-a-time disk margins [-] (balanced).
    disk_margin : float
        The multiloop disk margin at the plant's input [-] (balanced; a lower bound, see the module).
    disk_frequency : float
        [Hz] where it is reached.
    """

    gain_margin: np.ndarray
    gain_margin_low: np.ndarray
    gain_frequency: np.ndarray
    phase_margin: np.ndarray
    phase_frequency: np.ndarray
    loop_disk_margin: np.ndarray
    disk_margin: float
    disk_frequency: float

    @property
    def disk_gain_margin(self) -> float:
        """The gain factor [-] all actuators may take at once by the multiloop disk margin ``a``:
        ``(1 + a/2) / (1 - a/2)``."""
        a = self.disk_margin
        return math.inf if a >= 2.0 else (1.0 + a / 2.0) / (1.0 - a / 2.0)

    @property
    def disk_phase_margin(self) -> float:
        """The phase [deg] every actuator may take at once by the multiloop disk margin: ``2 atan(a / 2)``."""
        return math.degrees(2.0 * math.atan(self.disk_margin / 2.0))


class DiscreteResponse:
    """``C (zI - A)^-1 B + D`` of one system at any ``z``: by ``A``'s eigenvectors when they are well
    conditioned (``C V diag(1 / (z - lambda)) V^-1 B``), else by solving at each ``z``."""

    def __init__(self, a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray) -> None:
        self.a, self.b, self.c, self.d = a, b.astype(complex), c, d
        self.modal: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        if a.shape[0]:
            lam, v = np.linalg.eig(a)
            if np.linalg.cond(v) < 1e8:
                self.modal = (lam, c @ v, np.linalg.solve(v, b))

    def __call__(self, z: np.ndarray) -> np.ndarray:
        n = self.a.shape[0]
        if n == 0:
            return np.broadcast_to(self.d.astype(complex), (z.size, *self.d.shape))
        if self.modal is not None:
            lam, cv, vb = self.modal
            with np.errstate(divide="ignore", invalid="ignore"):
                return (cv[None, :, :] / (z[:, None] - lam[None, :])[:, None, :]) @ vb + self.d
        x = np.linalg.solve(z[:, None, None] * np.eye(n) - self.a, np.broadcast_to(self.b, (z.size, *self.b.shape)))
        return self.c @ x + self.d


class _Loop:
    """The return ``M(z) = K(z) P(z)`` and ``S = (I - M)^-1`` at any points of the unit circle."""

    def __init__(self, plant: tuple[np.ndarray, ...], controller: tuple[np.ndarray, ...], rate: float) -> None:
        self.plant, self.controller, self.rate = DiscreteResponse(*plant), DiscreteResponse(*controller), rate
        self.m = plant[1].shape[1]

    def sensitivity(self, f: np.ndarray) -> np.ndarray:
        z = np.exp(2j * math.pi * np.asarray(f, dtype=float) / self.rate)
        mm = self.controller(z) @ self.plant(z)
        return np.linalg.inv(np.eye(self.m) - mm)

    def returns(self, f: np.ndarray) -> np.ndarray:
        """Each loop's ``l_i`` (nf, m)."""
        s = self.sensitivity(f)
        with np.errstate(divide="ignore", invalid="ignore"):
            return 1.0 - 1.0 / np.diagonal(s, axis1=1, axis2=2)


def _crossings(values: np.ndarray) -> np.ndarray:
    """Indices ``k`` with a sign change of ``values`` between ``k`` and ``k + 1``."""
    return np.flatnonzero((values[:-1] == 0) | (np.sign(values[:-1]) * np.sign(values[1:]) < 0))


def _measure(ret: np.ndarray, kind: np.ndarray) -> np.ndarray:
    """``Im l`` (kinds 0, 1: gain margins) or ``|l| - 1`` (kind 2: phase margin), elementwise."""
    return np.where(kind < 2, ret.imag, np.abs(ret) - 1.0)


def _refine(loop: _Loop, f: np.ndarray, ret: np.ndarray, jobs: list[tuple[int, int, int]]
            ) -> tuple[np.ndarray, np.ndarray]:
    """Where ``Im l_i`` (kinds 0, 1) or ``|l_i| - 1`` (kind 2) changes sign in ``f[k] .. f[k + 1]``, for every
    job ``(i, k, kind)`` at once: :data:`_BISECTIONS` bisections of the exact response, then linear
    interpolation. Returns the frequencies [Hz] and ``l_i`` there."""
    if not jobs:
        return np.zeros(0), np.zeros(0, dtype=complex)
    i, k, kind = (np.array(c) for c in zip(*jobs, strict=True))
    rows = np.arange(len(jobs))
    lo, hi = f[k].astype(float), f[k + 1].astype(float)
    g_lo, g_hi = _measure(ret[k, i], kind), _measure(ret[k + 1, i], kind)
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi)
        g = _measure(loop.returns(mid)[rows, i], kind)
        left = np.sign(g) == np.sign(g_lo)
        lo, g_lo = np.where(left, mid, lo), np.where(left, g, g_lo)
        hi, g_hi = np.where(left, hi, mid), np.where(left, g_hi, g)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.nan_to_num(np.clip(g_lo / (g_lo - g_hi), 0.0, 1.0))
    where = lo + t * (hi - lo)
    return where, loop.returns(where)[rows, i]


def _gain_candidates(f: np.ndarray, ret: np.ndarray) -> list[tuple[float, float, int]]:
    """The upper and lower critical gain factors of one loop's ``l`` on the grid: ``(g, frequency [Hz],
    grid interval to refine in or -1)``, ``(inf, nan, -1)`` and ``(0, nan, -1)`` when there is none."""
    # both ends (where l is real) and every crossing of the real axis
    cands = [(float(f[0]), float(ret[0].real), -1), (float(f[-1]), float(ret[-1].real), -1)]
    for k in _crossings(ret.imag):
        a, b = ret[k], ret[k + 1]
        t = a.imag / (a.imag - b.imag) if a.imag != b.imag else 0.0
        cands.append((float(f[k] + t * (f[k + 1] - f[k])), float(a.real + t * (b.real - a.real)), int(k)))
    up, low = (math.inf, math.nan, -1), (0.0, math.nan, -1)
    for freq, r, k in cands:
        if not (math.isfinite(r) and r != 0.0):
            continue
        if 1.0 < 1.0 / r < up[0]:
            up = (1.0 / r, freq, k)
        elif low[0] < 1.0 / r < 1.0:
            low = (1.0 / r, freq, k)
    return [up, low]


def _phase_candidate(f: np.ndarray, ret: np.ndarray) -> tuple[float, float, int]:
    """One loop's smallest ``|arg l|`` [deg] where ``|l|`` crosses 1 on the grid, its frequency and interval
    (``(inf, nan, -1)`` without a crossover)."""
    mag = np.abs(ret) - 1.0
    best = (math.inf, math.nan, -1)
    for k in _crossings(mag):
        t = mag[k] / (mag[k] - mag[k + 1]) if mag[k] != mag[k + 1] else 0.0
        pm = math.degrees(abs(np.angle(ret[k] + t * (ret[k + 1] - ret[k]))))
        if pm < best[0]:
            best = (pm, float(f[k] + t * (f[k + 1] - f[k])), int(k))
    return best


def _grid(sample_rate: float, poles: np.ndarray) -> np.ndarray:
    """0, :data:`_POINTS` frequencies [Hz] logarithmically spaced from ``1e-5`` of the sample rate to the
    Nyquist frequency, and each pole's frequency and its half-power edges (where narrow peaks are)."""
    nyquist = sample_rate / 2.0
    z = poles[np.abs(poles) > 0.5]
    centre = np.abs(np.angle(z)) * sample_rate / (2 * math.pi)
    width = np.abs(np.log(np.abs(z))) * sample_rate / (2 * math.pi)
    f = np.unique(np.concatenate([np.logspace(math.log10(sample_rate * 1e-5), math.log10(nyquist), _POINTS),
                                  centre, centre - width, centre + width]))
    return np.concatenate([[0.0], f[(f > sample_rate * 1e-5) & (f < nyquist)], [nyquist]])


def _osborne(x: np.ndarray) -> np.ndarray:
    """``D x D^-1`` with Osborne's diagonal scaling ``D`` of each ``x`` (nf, m, m): the rows' and columns'
    off-diagonal magnitudes balanced (a few sweeps)."""
    m = x.shape[1]
    off = np.abs(x) * (1.0 - np.eye(m))
    off += 1e-14 * np.max(off, axis=(1, 2), keepdims=True) + 1e-300
    d = np.ones((x.shape[0], m))
    for _ in range(5):
        scaled = off * d[:, :, None] / d[:, None, :]
        d = d * np.sqrt(scaled.sum(axis=1) / scaled.sum(axis=2))
        d /= d.max(axis=1, keepdims=True)
    return x * d[:, :, None] / d[:, None, :]


def _sigma_max(y: np.ndarray) -> np.ndarray:
    """The largest singular value of each ``y`` (nf, m, m)."""
    return np.sqrt(np.maximum(np.linalg.eigvalsh(np.conj(np.swapaxes(y, 1, 2)) @ y)[:, -1], 0.0))


def _mu_peak(x: np.ndarray) -> tuple[float, int]:
    """The largest over the grid of an upper bound of ``mu`` (diagonal complex scalar blocks) of ``x``
    (nf, m, m), ``sigma_max`` of Osborne's scaling of ``x``, and its index.

    It is computed in decreasing order of a cheaper bound of it (the root of the largest row sum times the
    largest column sum of the magnitudes) until that falls below the largest found; frequencies where the
    cheaper bound is below ``max |x_ii|`` (a lower bound of ``mu`` anywhere) are never reached."""
    y = _osborne(x)
    a = np.abs(y)
    cheap = np.sqrt(a.sum(axis=1).max(axis=1) * a.sum(axis=2).max(axis=1))
    floor = float(np.abs(np.diagonal(x, axis1=1, axis2=2)).max())
    order = np.argsort(-cheap)
    order = order[cheap[order] >= floor * (1.0 - 1e-12)]
    peak, k = -math.inf, int(np.argmax(cheap))
    for start in range(0, order.size, 64):
        chunk = order[start:start + 64]
        if cheap[chunk[0]] <= peak:
            break
        sigma = _sigma_max(y[chunk])
        if sigma.max() > peak:
            peak, k = float(sigma.max()), int(chunk[np.argmax(sigma)])
    return peak, k


def loop_margins(plant: tuple[np.ndarray, ...], controller: tuple[np.ndarray, ...], sample_rate: float,
                 poles: np.ndarray | None = None, skip_dc: bool = False) -> LoopMargins:
    """The margins of a stable sampled loop at the plant's input (see the module's description).

    Parameters
    ----------
    plant, controller : tuple of ndarray
        As :func:`closed_loop_matrix` takes them.
    sample_rate : float
        [Hz] of both.
    poles : ndarray, optional
        The closed loop's eigenvalues: the grid gets their frequencies and half-power edges.
    skip_dc : bool
        Leave out the frequency 0 (a pole at ``z = 1`` the loop does not reach, such as a pneumatic
        table's neutral air); it is left out anyway when ``z = 1`` is a pole of the plant or controller.
    """
    f = _grid(sample_rate, np.zeros(0) if poles is None else np.asarray(poles))
    loop = _Loop(plant, controller, sample_rate)
    with np.errstate(all="ignore"):
        try:
            s = loop.sensitivity(f[1:] if skip_dc else f)
        except np.linalg.LinAlgError:
            s = np.full((1, 1, 1), np.nan)
        f = f[1:] if skip_dc else f
        if not np.all(np.isfinite(s[:1])):  # a pole at z = 1
            f = f[1:]
            s = loop.sensitivity(f)
    diag = np.diagonal(s, axis1=1, axis2=2)
    with np.errstate(divide="ignore", invalid="ignore"):
        ret = 1.0 - 1.0 / diag
    m = loop.m
    gains = [_gain_candidates(f, ret[:, i]) for i in range(m)]
    phases = [_phase_candidate(f, ret[:, i]) for i in range(m)]
    jobs = [(i, c[2], j) for i in range(m) for j, c in enumerate(gains[i]) if c[2] >= 0]
    jobs += [(i, phases[i][2], 2) for i in range(m) if phases[i][2] >= 0]
    where, values = _refine(loop, f, ret, jobs)
    for (i, k, kind), freq, value in zip(jobs, where, values, strict=True):
        if kind == 2:
            phases[i] = (math.degrees(abs(np.angle(value))), float(freq), k)
        elif value.real != 0.0:
            gains[i][kind] = (1.0 / value.real, float(freq), k)
    gain_up = np.array([g[0][0] for g in gains])
    gain_low = np.array([g[1][0] for g in gains])
    with np.errstate(divide="ignore"):
        nearer = np.abs(np.log(gain_up)) <= np.abs(np.log(gain_low))
    peak, k = _mu_peak(s - 0.5 * np.eye(m))
    local = np.linspace(f[max(k - 1, 0)], f[min(k + 1, f.size - 1)], 17)  # the peak between its neighbours
    near, j = _mu_peak(loop.sensitivity(local) - 0.5 * np.eye(m))
    peak, at = (peak, float(f[k])) if peak >= near else (near, float(local[j]))
    return LoopMargins(
        gain_margin=gain_up, gain_margin_low=gain_low,
        gain_frequency=np.array([g[0][1] if near else g[1][1] for g, near in zip(gains, nearer, strict=True)]),
        phase_margin=np.array([p[0] for p in phases]), phase_frequency=np.array([p[1] for p in phases]),
        loop_disk_margin=1.0 / np.max(np.abs(diag - 0.5), axis=0), disk_margin=1.0 / peak, disk_frequency=at)


def sampled_margins(loop: SampledLoop) -> LoopMargins:
    """The margins at the actuators of a stable :class:`~isolator.analysis.closed_loop.SampledLoop` (the
    held air's poles at ``z = 1`` left out): what the robustness check and ``isolator check-controller``
    report."""
    return loop_margins(loop.plant, loop.controller, loop.sample_rate, poles=loop.poles, skip_dc=loop.held > 0)


check_public(globals())
