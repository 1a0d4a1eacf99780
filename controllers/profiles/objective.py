"""The profile optimisation's objective: the vibration left after the stop, in units of the band.

Smooth, in units of the 5 % band of each signal:

* ``R``: the residual vibration at the stop, ``z' P z`` with ``z`` the table's
  deviation from its final equilibrium (pneumatic tables: from the quasi-static pose of the air
  the table holds, so the slow re-leveling is not counted) (six signals and rates, each divided by
  its band) and ``P`` from the Lyapunov equation of the model linearised at the
  final configuration, so ``R`` is the integral of the squared normalised
  deviation of the free response, divided by the slowest decay time;
* ``H``: over a window after the stop (integrated with the full model), the
  mean of ``max(0, (e / band)^2 - margin^2)^2``: the band, with a margin.

Each signal's band is ``fraction`` times its peak over the move, a smooth
maximum (a ``PEAK_POWER``-norm over the RK4 steps, scaled to equal the true
maximum at the starting design: :func:`calibration`), so the objective sees
that a gentler move also narrows the band of a signal that only its
transients move.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import SIGNALS, Settling

from .transcription import PEAK_POWER, Nlp, Transcription, VariantData, advance

__all__ = ["calibration", "floors", "peak_floor", "residual"]


def floors(values: np.ndarray) -> np.ndarray:
    """Per signal, 1e-3 of the largest value of its kind (translations, rotations); 1e-12 when all are 0."""
    tops = np.repeat([np.max(values[:3]), np.max(values[3:])], 3)
    return np.where(tops > 0, 1e-3 * tops, 1e-12)


def peak_floor(peak: dict[str, float]) -> np.ndarray:
    """Each signal's peak [m, rad], floored at 1e-3 of the largest of its kind (a signal that
    symmetry keeps at zero must not dominate)."""
    values = np.array([peak[s] for s in SIGNALS], dtype=float)
    return np.maximum(values, floors(values))


def calibration(run: Transcription, theta: ca.MX, vd: VariantData, theta0: np.ndarray) -> np.ndarray:
    """Factors making the smooth peak equal the true one at the starting design ``theta0``."""
    _, power, hard, _ = run.trajectory(vd, None)
    fn = ca.Function("peaks", [theta], [power, hard])
    p, m = (np.asarray(v).ravel() for v in fn(theta0))
    smooth = p ** (1.0 / PEAK_POWER)
    return np.where(smooth > 0, m / np.where(smooth > 0, smooth, 1.0), 1.0)


def residual(run: Transcription, vd: VariantData, factors: np.ndarray, nlp: Nlp | None, settling: Settling,
             window: float, step: float, band_margin: float) -> ca.MX:
    """``R + H`` of one model variant: the window after the stop, in bands.

    Parameters
    ----------
    run : Transcription
    vd : VariantData
    factors : ndarray (6,)
        :func:`calibration` of the smooth peaks.
    nlp : Nlp or None
        With multiple shooting, the problem the run's nodes are added to.
    settling : Settling
        The scenario's band rule.
    window : float
        Length of the window after the stop [s].
    step : float
        Nominal RK4 step [s].
    band_margin : float
        ``H`` counts deviations beyond this fraction of the band.
    """
    x, power, _, _ = run.trajectory(vd, nlp)
    peak = ca.DM(run.peaks * factors) * power ** (1.0 / PEAK_POWER)
    floor = floors(run.peaks)
    band = ca.vertcat(*[settling.band(s, ca.fmax(peak[i], floor[i])) for i, s in enumerate(SIGNALS)])
    n = len(run.designs)
    n_window = max(4, math.ceil(window / step))
    rest = ca.vertcat(*[ca.horzcat(st[-1][0], 0, 0, 0) for st in run.states])
    xs = advance(run.step_fn, n_window, x, ca.DM.zeros(n, n_window), window / n_window, rest, vd.parameters)
    zs = run.sense.map(n_window)(xs, ca.repmat(ca.DM(vd.start_state), 1, n_window))
    e = (zs[:6, :] - vd.reference(xs)) / ca.repmat(band, 1, n_window)
    over = ca.fmax(0, e**2 - band_margin**2)
    return ca.sum1(ca.sum2(e**2 + over**2)) / n_window


check_public(globals())
