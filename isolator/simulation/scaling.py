"""Every isolator's stiffness and damping scaled at once, for sweeps and trade-off studies.

Spring-dampers: ``k -> s k`` and ``c -> c_s c`` on every axis.

Pneumatic isolators (a three-parameter element: the spring ``k_0`` in parallel
with the spring ``k_b`` in series with the orifice's dashpot ``c_b = k_b tau``,
``docs/scenario-format.md``): both chambers' volumes are divided by ``s`` (so
``k_0`` and ``k_inf`` scale by ``s`` at the same volume ratio) and the orifice's
conductance ``G ~ d^4`` by ``s c_s``, which scales the series dashpot
``c_b = A^2 V2^2 / (V1 (V1 + V2) G)`` by ``c_s``; the horizontal springs and
dampers scale as a spring-damper's. The rest pressures do not change (statics).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from isolator.errors import ParameterError
from isolator.model.parameters import ParameterLayout

__all__ = ["scaled_parameter_sets"]


def _scales(values: float | Sequence[float] | np.ndarray, key: str, positive: bool) -> np.ndarray:
    """Scale factors as an array, each finite and > 0 (``positive``) or >= 0; one clear error naming ``key``."""
    if isinstance(values, str | bytes | bool):
        raise ParameterError(f"{key}: scale must be a finite number or a sequence of them, got {values!r}")
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{key}: scale must be a finite number or a sequence of them, got {values!r}") from None
    flat = array.reshape(-1)
    bad = ~(np.isfinite(flat) & ((flat > 0) if positive else (flat >= 0)))
    if bad.any():
        i = int(np.argmax(bad))
        where = key if array.ndim == 0 else f"{key}[{i}]"
        raise ParameterError(f"{where}: scale must be a finite number {'>' if positive else '>='} 0, got {flat[i]}")
    return flat


def scaled_parameter_sets(
    layout: ParameterLayout,
    parameters: np.ndarray,
    stiffness: float | Sequence[float] | np.ndarray,
    damping: float | Sequence[float] | np.ndarray,
) -> np.ndarray:
    """Parameter vectors (runs, parameters) with every isolator's stiffness and damping scaled per run.

    Parameters
    ----------
    layout : ParameterLayout
    parameters : ndarray
        The scenario's parameter vector.
    stiffness, damping : float or sequence of float
        Scale factors [-], one per run (or one for all); damping may be 0 for
        spring-dampers, not for pneumatic isolators (their orifice would be infinite).

    Raises
    ------
    ParameterError
        A bad scale, named by its index (``stiffness[3]: ...``) when the scales are sequences.
    """
    pneumatic = layout.pneumatic is not None
    k = _scales(stiffness, "stiffness", positive=True)
    c = _scales(damping, "damping", positive=pneumatic)
    if k.size != c.size:
        raise ParameterError(f"damping: needs one scale per stiffness scale ({k.size}), got {c.size}")
    names = layout.names
    k, c = k[:, None], c[:, None]

    def where(*parts: str) -> np.ndarray:
        return np.array([any(part in n for part in parts) for n in names])[None, :]

    if pneumatic:
        scale = np.where(where(".volume", ".damping_volume"), 1.0 / k, 1.0)
        scale = np.where(where(".orifice.diameter"), (k * c) ** -0.25, scale)
        scale = np.where(where(".horizontal_stiffness."), k, scale)
        scale = np.where(where(".horizontal_damping."), c, scale)
    else:
        scale = np.where(where(".stiffness."), k, np.where(where(".damping."), c, 1.0))
    return np.asarray(parameters)[None, :] * scale
