"""What the steppers need of a model (the :class:`SteppedSystem` protocol) and which right-hand side they step."""

from __future__ import annotations

from typing import Protocol

import casadi as ca

__all__ = ["SteppedSystem", "stepped_rhs"]


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
