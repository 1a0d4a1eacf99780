"""Errors the toolkit raises for bad input and numerical trouble.

Which one: a bad function argument or command-line option (including a value
that does not fit the scenario, such as a carriage name, a forces file or a
controller designed for another plant) is a :class:`ParameterError` naming the
argument; only a scenario whose own content makes the request impossible (no
``[[actuators]]`` to control with, moves that never stop, an undamped table) is
a :class:`ScenarioError` naming the scenario key; an optimiser or synthesis
that finds no answer is an :class:`OptimisationError`; an executor that can no
longer run a sweep's chunks (its cluster gone) is an :class:`ExecutorError`
naming ``resume=True`` (``--resume`` on the command line).
"""

from __future__ import annotations

__all__ = [
    "ExecutorError",
    "IsolatorError",
    "MisfitError",
    "OptimisationError",
    "ParameterError",
    "ScenarioError",
    "SimulationError",
    "UnidentifiableError",
    "UnstableClosedLoopError",
    "UnstableTableError",
]


class IsolatorError(Exception):
    """Base class of every error the toolkit reports to a user."""


class ScenarioError(IsolatorError, ValueError):
    """A scenario's content is invalid; the message names the key path (``carriages[1].mass: ...``)."""


class ParameterError(IsolatorError, ValueError):
    """An argument of a public function or a command-line option is invalid; the message names it."""


class UnstableTableError(IsolatorError):
    """The table has no stable static equilibrium (it would tip or drift away)."""


class SimulationError(IsolatorError):
    """A run diverged or produced non-finite values."""


class UnstableClosedLoopError(IsolatorError):
    """A feedback loop is unstable (in continuous time or at its sample rate)."""


class OptimisationError(IsolatorError):
    """An optimiser stopped without a usable answer; the message says why and what is kept."""


class UnidentifiableError(IsolatorError):
    """The records of a calibration cannot tell some fitted parameters apart; the message names them.

    Attributes
    ----------
    groups : list of list of str
        The parameters of each direction the records cannot resolve.
    """

    def __init__(self, message: str, groups: list[list[str]] | None = None) -> None:
        super().__init__(message)
        self.groups = groups or []


class MisfitError(IsolatorError):
    """A calibration's fit does not explain its records (its weighted residuals are beyond their chi-square
    distribution); the message names each experiment, its ratio and what it most likely means.

    Attributes
    ----------
    result : object
        The :class:`~isolator.calibration.CalibrationResult` that was refused (``fit_ok`` False).
    """

    def __init__(self, message: str, result: object = None) -> None:
        super().__init__(message)
        self.result = result


class ExecutorError(IsolatorError):
    """The executor running a sweep's chunks can no longer run them (a Dask scheduler that is gone, a broken
    pool the sweep cannot renew); the rows written are kept and the message names ``resume=True`` (``isolator
    sweep`` names ``--resume``)."""
