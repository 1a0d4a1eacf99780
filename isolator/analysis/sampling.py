"""A continuous plant sampled as a digital controller runs it, and the sampled loop's state matrix.

Shared by the error budget's closed loop (:mod:`isolator.analysis.budget`) and the output-feedback designs
and checks of :mod:`controllers.feedback` (``SensorPlant.discrete``, the robustness check).
"""

from __future__ import annotations

import numbers

import numpy as np
from scipy.linalg import expm

from isolator.errors import ParameterError

__all__ = ["MAX_SAMPLE_RATE", "check_sample_rate", "closed_loop_matrix", "sample_held"]

#: the fastest rate [Hz] a digital controller may have, whichever command designs, reads or runs it: the
#: fastest grid a simulation steps a controller on
MAX_SAMPLE_RATE = 100e3


def check_sample_rate(rate: object, key: str = "sample_rate") -> float:
    """A controller's sample rate [Hz] as a float, by the one rule every command follows: a number > 0 and at
    most :data:`MAX_SAMPLE_RATE`; else one :class:`ParameterError` naming ``key``.

    Examples
    --------
    >>> check_sample_rate(2000)
    2000.0
    >>> check_sample_rate(1e300)
    Traceback (most recent call last):
    ...
    isolator.errors.ParameterError: sample_rate: must be a rate > 0 Hz and at most 100000 Hz (the fastest grid ...
    """
    if isinstance(rate, bool) or not isinstance(rate, numbers.Real) or not 0 < float(rate) <= MAX_SAMPLE_RATE:
        raise ParameterError(f"{key}: must be a rate > 0 Hz and at most {MAX_SAMPLE_RATE:g} Hz (the fastest grid "
                             f"a simulation steps a controller on), got {rate!r}")
    return float(rate)


def sample_held(matrices: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray], m: int, sample_rate: float,
                delay: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(A, B, C, D)`` of a continuous plant whose first ``m`` inputs are commands, sampled at ``sample_rate``.

    Every input is held over each sample (zero-order hold, exact for the held commands; other inputs are
    held too, a model only). With ``delay``, ``m`` extra states hold the command of the previous sample: the
    input ``u_k`` computed at ``t_k`` acts from ``t_{k+1}``. The readings at ``t_k`` are the left limit, as the
    simulation and a real sampler take them: a command that reaches a reading at once (an accelerometer with
    an actuator without lag) is seen there as the command applied just before ``t_k``, held in ``m`` more
    states.

    Parameters
    ----------
    matrices : tuple of ndarray
        ``(A, B, C, D)`` of the continuous plant [SI].
    m : int
        Number of command inputs (the first columns of ``B`` and ``D``).
    sample_rate : float
        [Hz], > 0.
    delay : bool
        One sample of computation delay.

    Returns
    -------
    tuple of ndarray
        The discrete ``(A, B, C, D)``: states the continuous plant's, then the delayed command (with
        ``delay``), then the command applied before the sample (with a direct feedthrough).
    """
    check_sample_rate(sample_rate)
    a, b, c, d = (np.asarray(x, dtype=float) for x in matrices)
    n, nu = a.shape[0], b.shape[1]
    block = np.zeros((n + nu, n + nu))
    block[:n, :n], block[:n, n:] = a, b
    phi = expm(block / sample_rate)
    ad, bd = phi[:n, :n], phi[:n, n:]
    p = c.shape[0]
    # z = (x, pending): x+ = Ad x + Bd_u applied + Bd_w w; applied = u (no delay) or the pending command
    hold = m if delay else 0
    az = np.zeros((n + hold, n + hold))
    bz = np.zeros((n + hold, nu))
    az[:n, :n], bz[:n, m:] = ad, bd[:, m:]
    if delay:
        az[:n, n:] = bd[:, :m]
        bz[n:, :m] = np.eye(m)
    else:
        bz[:n, :m] = bd[:, :m]
    cz = np.hstack([c, np.zeros((p, hold))])
    dz = np.hstack([np.zeros((p, m)), d[:, m:]])
    du = d[:, :m]
    if np.any(du != 0):  # the reading's left limit: the command applied over the previous sample
        k = n + hold
        applied_a = np.zeros((m, k))
        applied_b = np.zeros((m, nu))
        if delay:
            applied_a[:, n:] = np.eye(m)
        else:
            applied_b[:, :m] = np.eye(m)
        az = np.block([[az, np.zeros((k, m))], [applied_a, np.zeros((m, m))]])
        bz = np.vstack([bz, applied_b])
        cz = np.hstack([cz, du])
    return az, bz, cz, dz


def closed_loop_matrix(plant: tuple[np.ndarray, ...], controller: tuple[np.ndarray, ...]) -> np.ndarray:
    """State matrix of the sampled loop, states ``[x, xc]``.

    Parameters
    ----------
    plant : tuple of ndarray
        ``(Ap, Bp, Cp, Dp)``: the sampled plant from the commands [N] to the readings (Bp, Dp only the
        commands' columns).
    controller : tuple of ndarray
        ``(Ak, Bk, Ck, Dk)`` of the controller (``u = Ck xc + Dk y``).

    Returns
    -------
    ndarray
        The loop is stable when every eigenvalue is inside the unit circle.

    Raises
    ------
    ParameterError
        ``I - Dk Dp`` is singular (the loop has no solution for ``u``).
    """
    ap, bp, cp, dp = plant
    ak, bk, ck, dk = controller
    n, nk, m = ap.shape[0], ak.shape[0], bp.shape[1]
    try:
        right = np.linalg.solve(np.eye(m) - dk @ dp, np.hstack([dk @ cp, ck]))
    except np.linalg.LinAlgError:
        raise ParameterError("controller: I - D Dp is singular, the loop through the plant's feedthrough "
                             "has no solution") from None
    a = np.block([[ap, np.zeros((n, nk))], [bk @ cp, ak]])
    return a + np.vstack([bp, bk @ dp]) @ right
