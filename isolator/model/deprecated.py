"""Names that left the public API, kept for one release with a :class:`DeprecationWarning`.

``isolator.static_equilibrium`` left ``isolator.__all__`` in 0.1.0 (issue 26) without a deprecation; it stays
reachable as ``isolator.static_equilibrium`` until the next release, its arguments checked as a public
function's are. The equilibrium of a scenario is ``isolator.linearise(scenario, positions).equilibrium``.
"""

from __future__ import annotations

import warnings

import numpy as np

from isolator.errors import ParameterError
from isolator.model.equilibrium import Equilibrium, static_equilibrium
from isolator.model.variants import Model

__all__ = ["DEPRECATED", "deprecated_static_equilibrium"]


def deprecated_static_equilibrium(model: Model, p: np.ndarray, positions: np.ndarray, where: str = "at rest",
                                  check: bool = True) -> Equilibrium:
    """Deprecated: :func:`isolator.model.equilibrium.static_equilibrium` with its arguments checked (use
    ``isolator.linearise(scenario, positions).equilibrium``).

    Parameters
    ----------
    model : Model
        From :func:`isolator.get_model` or :func:`isolator.build_model`.
    p : ndarray (parameters,)
        The parameter vector (``model.layout.pack(scenario)``).
    positions : ndarray (carriages,)
        Carriage coordinates [m].
    where : str
        Words for messages.
    check : bool
        Raise when the equilibrium is unstable.

    Returns
    -------
    Equilibrium

    Raises
    ------
    ParameterError
        An argument of the wrong kind or size, named.
    UnstableTableError
        No stable equilibrium.
    """
    if not isinstance(model, Model):
        raise ParameterError(f"model: must be an isolator Model (isolator.get_model), got {type(model).__name__}")
    layout = model.layout
    vector = _vector(p, "p", layout.size)
    q = _vector(positions, "positions", layout.n_carriages)
    if not isinstance(where, str):
        raise ParameterError(f"where: must be text, got {type(where).__name__}")
    return static_equilibrium(model, vector, q, where, bool(check))


def _vector(value: object, name: str, size: int) -> np.ndarray:
    try:
        out = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ParameterError(f"{name}: must be {size} numbers, got {type(value).__name__}") from None
    if out.size != size or not np.all(np.isfinite(out)):
        raise ParameterError(f"{name}: must be {size} finite numbers, got {out.size}"
                             + ("" if np.all(np.isfinite(out)) else " with non-finite values"))
    return out


#: each deprecated public name: (the function, what replaces it)
DEPRECATED = {"static_equilibrium": (deprecated_static_equilibrium,
                                     "isolator.linearise(scenario, positions).equilibrium")}


def deprecated(name: str) -> object:
    """The deprecated public name ``name`` with its warning, or AttributeError."""
    if name not in DEPRECATED:
        raise AttributeError(f"module 'isolator' has no attribute {name!r}")
    function, replacement = DEPRECATED[name]
    warnings.warn(f"isolator.{name} is deprecated and leaves in the next release; use {replacement}",
                  DeprecationWarning, stacklevel=3)
    return function
