"""The sampled law the time-varying simulation runs: a controller at its rate, its loops checked."""

from __future__ import annotations

import math

import numpy as np

from controllers.feedforward.path import QuasiStaticPath, quasi_static_path
from isolator.analysis.linear import linearise
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario

from .designs import Controller
from .loops import REFERENCE_INPUTS, ClosedLoop, check_stability, closed_loop

__all__ = ["DiscreteLaw", "feedback_law"]


class DiscreteLaw:
    """A controller as the time-varying simulation runs it.

    At each tick ``t_k = k / sample_rate`` it measures the table's deviation
    from its reference (the initial equilibrium, or a quasi-static path and
    its rate), updates the Tustin-discretised controller and returns the
    command, which the simulation holds until the next tick (adding any
    feedforward, then saturating and lagging as the actuators do).
    Build it with :func:`feedback_law`.

    Parameters
    ----------
    controller : Controller
        The design it runs.
    reference : QuasiStaticPath, optional
        What the controller regulates to (default: the initial equilibrium).
    end : ClosedLoop, optional
        The loop with the carriages at their final positions, for the
        closed-loop final value (default: the passive one).
    """

    def __init__(self, controller: Controller, reference: QuasiStaticPath | None = None,
                 end: ClosedLoop | None = None) -> None:
        self.controller = controller
        self.reference = reference
        self.end = end
        self.sample_rate = controller.sample_rate
        self.ad, self.bd, self.cd, self.dd = controller.discrete()
        self.state = np.zeros(self.ad.shape[0])

    def reset(self) -> None:
        self.state = np.zeros(self.ad.shape[0])

    def matrices(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The Tustin-discretised ``(A, B, C, D)`` from the 12 measured deviations to the commands [N]."""
        return self.ad, self.bd, self.cd, self.dd

    def references(self, t: np.ndarray) -> np.ndarray:
        """What the law regulates to at times ``t`` [s]: (len(t), 12), the quasi-static path and its rate
        (zero without one)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if self.reference is None:
            return np.zeros((t.size, 12))
        return np.hstack([self.reference(t), self.reference(t, None, 1)])

    def _reference(self, t: float) -> np.ndarray:
        return self.references(np.array([t]))[0]

    def __call__(self, t: float, measurement: np.ndarray) -> np.ndarray:
        """Command [N] per actuator at a tick from the measured state (12,) relative to the start."""
        m = np.asarray(measurement, dtype=float) - self._reference(t)
        u = self.cd @ self.state + self.dd @ m
        self.state = self.ad @ self.state + self.bd @ m
        return u

    def final(self, passive: np.ndarray) -> np.ndarray:
        """Closed-loop final value of the six signals from the passive one (linear, at the end)."""
        if self.end is None:
            return np.asarray(passive, dtype=float)
        r_end = self._reference(math.inf)[:6] if self.reference is not None else np.zeros(6)
        return passive + self.end.dc_gain(REFERENCE_INPUTS) @ (r_end - passive)


def feedback_law(
    scenario: Scenario, controller: Controller, reference: QuasiStaticPath | None = None, check: bool = True
) -> DiscreteLaw:
    """The controller ready to run in the simulation of ``scenario``, its loop checked.

    Parameters
    ----------
    reference : QuasiStaticPath, optional
        Regulate to this path (e.g. the feedforward's) instead of the initial
        equilibrium, so that feedback does not fight the quasi-static tilt.
        Default: the initial equilibrium, or ``quasi_static_path(scenario)``
        for a controller with ``follows_path`` (:func:`lqr`, :func:`hinf`).
    check : bool
        Raise :class:`UnstableClosedLoopError` when the sampled loop is unstable
        with the carriages at their start or their final positions.
    scenario : Scenario
        The scenario (or a bundled scenario's name, or a TOML file's path).
    controller : Controller
        The design (its sample rate is the law's).

    Returns
    -------
    DiscreteLaw
        The law :meth:`isolator.Simulator.run` takes as ``feedback``.
    """
    lin_start = linearise(scenario)
    finals = scenario.final_positions()
    lin_end = linearise(scenario, positions=finals) if finals is not None else lin_start
    if check:
        check_stability(lin_start, controller, "with the carriages at their start").raise_if_unstable()
        check_stability(lin_end, controller, "with the carriages at their final positions").raise_if_unstable()
    if reference is None and controller.follows_path:
        reference = quasi_static_path(scenario)
    return DiscreteLaw(controller, reference, closed_loop(lin_end, controller, check=False))


check_public(globals())
