"""A linear model's state-space matrices with its signals' names: what the python-control system is built from,
and all that the sampled loops and the budget need of it (python-control, a second to import, only on demand)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from isolator.analysis.signal_names import signals, to_control

if TYPE_CHECKING:
    import control

__all__ = ["Realisation"]


@dataclass(frozen=True)
class Realisation:
    """A linear model's state-space matrices and its signals' names, from which the python-control system is
    built (:meth:`state_space`).

    Attributes
    ----------
    a, b, c, d : ndarray
        ``x' = A x + B u``, ``y = C x + D u`` (SI units).
    inputs, outputs, states : tuple of str
        The signals' names (as :class:`LinearModel` documents them).
    name : str
        The scenario's.
    """

    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    d: np.ndarray
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    states: tuple[str, ...]
    name: str

    def state_space(self) -> control.StateSpace:
        """The ``control.StateSpace``, its names made python-control's (:mod:`isolator.analysis.signal_names`)."""
        import control  # python-control takes most of a second to import: only when needed

        return control.ss(self.a, self.b, self.c, self.d, inputs=signals(self.inputs),
                          outputs=signals(self.outputs), states=signals(self.states), name=to_control(self.name))
