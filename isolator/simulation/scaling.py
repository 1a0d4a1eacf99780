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

__all__ = ["PNEUMATIC_SCALING", "SPRING_DAMPER_SCALING", "scale_columns", "scaled_parameter_sets"]

#: what the stiffness scale ``s`` and the damping scale ``c_s`` do to an isolator's parameters: (the
#: parameter's name under ``isolators[i].``, exponent of ``s``, exponent of ``c_s``); the one rule both
#: :func:`scaled_parameter_sets` and the sweep columns of :func:`scale_columns` follow
SPRING_DAMPER_SCALING: tuple[tuple[str, float, float], ...] = (("stiffness", 1.0, 0.0), ("damping", 0.0, 1.0))
PNEUMATIC_SCALING: tuple[tuple[str, float, float], ...] = (
    ("volume", -1.0, 0.0),
    ("damping_volume", -1.0, 0.0),
    ("orifice.diameter", -0.25, -0.25),
    ("horizontal_stiffness", 1.0, 0.0),
    ("horizontal_damping", 0.0, 1.0),
)


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
    scale = np.ones((k.size, layout.size))
    for name, ek, ec in _rule(layout):
        entries = [i for i, n in enumerate(layout.names) if _member(n, name)]
        scale[:, entries] = (k**ek * c**ec)[:, None]
    return np.asarray(parameters)[None, :] * scale


def scale_columns(layout: ParameterLayout, stiffness: np.ndarray, damping: np.ndarray) -> dict[str, np.ndarray]:
    """The same scaling as sweep ``scale`` columns [-], by name (``isolators[*].volume``, ...), one factor
    per design: a sweep with these zipped gives the parameter vectors of :func:`scaled_parameter_sets`.
    Parameters no isolator of the scenario has are left out."""
    k, c = np.asarray(stiffness, dtype=float), np.asarray(damping, dtype=float)
    return {f"isolators[*].{name}": k**ek * c**ec for name, ek, ec in _rule(layout)
            if any(_member(n, name) for n in layout.names)}


def _rule(layout: ParameterLayout) -> tuple[tuple[str, float, float], ...]:
    return PNEUMATIC_SCALING if layout.pneumatic is not None else SPRING_DAMPER_SCALING


def _member(entry: str, name: str) -> bool:
    """Whether the layout entry ``isolators[i].<name>`` or ``isolators[i].<name>.<axis>`` is one of ``name``'s."""
    head, _, rest = entry.partition("].")
    return head.startswith("isolators[") and (rest == name or rest.startswith(name + "."))
