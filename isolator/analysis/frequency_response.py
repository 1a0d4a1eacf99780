"""Frequency responses of named state-space systems, including those with conserved quantities."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from scipy.linalg import matrix_balance

from isolator.analysis.signal_names import labels
from isolator.errors import ParameterError
from isolator.scenario.files import check_memory

if TYPE_CHECKING:  # python-control takes most of a second to import: imported where used
    import control

__all__ = ["state_space_response"]


def _index(names: Sequence[str] | None, labels: list[str], what: str) -> list[int]:
    if names is None:
        return list(range(len(labels)))
    out = []
    for name in names:
        if name not in labels:
            raise ParameterError(f"{what}: no {what[:-1]} named '{name}' (have: {', '.join(labels)})")
        out.append(labels.index(name))
    return out


def state_space_response(
    system: control.StateSpace,
    frequency_hz: np.ndarray,
    inputs: Sequence[str] | None = None,
    outputs: Sequence[str] | None = None,
) -> np.ndarray:
    """Complex ``H(j 2 pi f)`` of a named state-space system, one batched solve.

    At 0 Hz a system with conserved quantities no input reaches (the air each
    leveling group of a pneumatic table holds) keeps them at zero: its static
    gain is the solution of ``A x = -B u`` on which they stay zero.

    Returns
    -------
    ndarray (nf, n_outputs, n_inputs)
    """
    try:
        f = np.asarray(frequency_hz, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"frequency_hz: must be numbers [Hz], got {type(frequency_hz).__name__}") from None
    if f.ndim > 1:
        raise ParameterError(f"frequency_hz: must be one frequency or a 1-D array of them, got shape {f.shape}")
    f = f.ravel()
    if f.size == 0 or not np.all(np.isfinite(f)) or np.any(f < 0):
        raise ParameterError("frequency_hz: must be finite frequencies >= 0 Hz")
    iu = _index(inputs, labels(system.input_labels), "inputs")
    iy = _index(outputs, labels(system.output_labels), "outputs")
    n_states = np.asarray(system.A).shape[0]  # each frequency's resolvent, states and response (complex)
    check_memory(16.0 * f.size * (2 * n_states * n_states + n_states * len(iu) + len(iy) * len(iu)),
                 f"frequency_hz: {f.size} frequencies", "ask for fewer frequencies")
    a, b = np.asarray(system.A), np.asarray(system.B)[:, iu]
    c, d = np.asarray(system.C)[iy], np.asarray(system.D)[np.ix_(iy, iu)]
    s = 2j * np.pi * f
    n = a.shape[0]
    still = f == 0
    x = np.empty((f.size, n, b.shape[1]), dtype=complex)
    resolvent = s[~still, None, None] * np.eye(n) - a[None]
    x[~still] = np.linalg.solve(resolvent, np.broadcast_to(b.astype(complex), (int((~still).sum()), *b.shape)))
    if still.any():
        x[still] = _static_states(np.asarray(system.A), np.asarray(system.B), b)
    return c[None] @ x + d[None]


def _static_states(a_full: np.ndarray, b_full: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``x`` with ``A x = -b``, holding at zero what ``[A, B]`` conserves (its left null space), in
    states balanced first (pressures [Pa] and displacements [m] differ by ten orders of magnitude)."""
    _, (scale, _) = matrix_balance(a_full, permute=False, separate=True)
    a_bal = a_full * scale[None, :] / scale[:, None]
    _, sv, vt = np.linalg.svd(np.hstack([a_bal, b_full / scale[:, None]]).T, full_matrices=True)
    rank = int(np.sum(sv > 1e-9 * max(float(sv.max(initial=0.0)), 1e-300)))
    conserved = vt[rank:]
    system = np.vstack([a_bal, conserved])
    rhs = np.vstack([-b / scale[:, None], np.zeros((conserved.shape[0], b.shape[1]))])
    return np.asarray(np.linalg.lstsq(system, rhs, rcond=None)[0] * scale[:, None])
