"""What the steppers need of a model (the :class:`SteppedSystem` protocol) and which right-hand side they step."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import casadi as ca

__all__ = ["SteppedSystem", "Unstaged", "stepped_rhs"]


class SteppedSystem(Protocol):
    """What the steppers need of a model: its right-hand side, state count and a tag naming its structure."""

    @property
    def tag(self) -> str: ...

    @property
    def n_states(self) -> int: ...

    @property
    def rhs(self) -> ca.Function: ...

    @property
    def staged_rhs(self) -> ca.Function | None: ...


def stepped_rhs(model: SteppedSystem) -> ca.Function:
    """The right-hand side the DOP853 steps evaluate, ``(x, inputs, p) -> dx/dt``: the staged one
    (:attr:`SteppedSystem.staged_rhs`, its inputs from ``model.staged_inputs``) when the model has it."""
    return model.staged_rhs if model.staged_rhs is not None else model.rhs


@dataclass(frozen=True)
class Unstaged:
    """A model stepped through its whole right-hand side ``rhs (x, u, p)``, its staged form set aside: the
    inputs ``u`` do not depend on the parameters, so runs whose time-only part differs (masses, inertia,
    carriage axes and origins) can share them, lane by lane.

    Attributes
    ----------
    tag : str
        The model's, with ``_unstaged`` (compiled steppers are named by it).
    n_states : int
    rhs : casadi.Function
    """

    tag: str
    n_states: int
    rhs: ca.Function
    staged_rhs: ca.Function | None = None

    @classmethod
    def of(cls, model: SteppedSystem) -> Unstaged:
        """``model`` stepped through ``rhs``."""
        return cls(f"{model.tag}_unstaged", model.n_states, model.rhs)
