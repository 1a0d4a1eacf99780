"""Input shapers (ZV, ZVD, EI) on the carriages' moves, tuned to the modes each move excites.

A shaper is a short train of impulses ``(A_i, t_i)``; convolving a move with it
cancels the residual vibration of one mode (ZV), also its first derivative in
frequency (ZVD), or keeps it below 5 % over a wide band (EI, Singhose et al.,
"Vibration reduction using multi-hump input shapers", 1997: the damped
extra-insensitive shaper's curve-fitted amplitudes and times). Each carriage
is shaped for the mode its move excites most in the table's settling signals
(:func:`dominant_modes`), at the configuration where the move ends.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from controllers.feedforward.wrench import carriage_inertia_wrench
from isolator.analysis.linear import linearise
from isolator.analysis.signal_names import labels
from isolator.errors import ScenarioError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.scenario.profile_shapes import shaped
from isolator.scenario.profiles import PiecewisePolynomialProfile
from isolator.scenario.shapers import EI_TOLERANCE, SHAPERS, Shaper, convolved, residual_vibration, shaper

from .move_metrics import with_moves

__all__ = [
    "EI_TOLERANCE",
    "SHAPERS",
    "ExcitedMode",
    "Shaper",
    "dominant_modes",
    "residual_vibration",
    "shaped_scenario",
    "shaper",
]

@dataclass(frozen=True)
class ExcitedMode:
    """A mode of the table and how much one carriage's move excites it.

    Attributes
    ----------
    frequency : float
        Undamped natural frequency [Hz].
    damping : float
        Damping ratio.
    weight : float
        Largest step response of the six signals to the carriage's
        acceleration, each over its peak in the reference run [1 / (m/s^2)].
    """

    frequency: float
    damping: float
    weight: float


def dominant_modes(scenario: Scenario, carriage: int, peaks: Sequence[float] | None = None) -> list[ExcitedMode]:
    """The table's modes ranked by how much the carriage's acceleration excites them where the move ends.

    Parameters
    ----------
    scenario : Scenario
        The scenario (or a bundled scenario's name, or a TOML file's path).
    carriage : int
        Index of the carriage.
    peaks : sequence of float, optional
        Each signal's scale [m, rad] (e.g. its peak in the baseline run, which
        sets its settling band); default 1 for all.

    Returns
    -------
    list of ExcitedMode
        Each mode's frequency [Hz], damping ratio and weight (its largest amplitude over the signals, in
        units of ``peaks``), most excited first.

    Notes
    -----
    Accelerating carriage ``c`` along its axis ``e`` (world axes) at ``a``
    pushes the table with ``-a m e`` at every mass ``m`` that rides along (the
    carriage and the ones it carries): a wrench at the table's mass centre.
    For each mode ``i`` of the linearised table, the step response of signal
    ``s`` to that wrench has the amplitude ``|C_s v_i w_i' B u| / |lambda_i|``.
    """
    finals = scenario.final_positions()
    if finals is None:
        raise ScenarioError("carriages: a move that never stops has no residual vibration to shape")
    lin = linearise(scenario, positions=finals)
    sys = lin.system
    a, b, c = np.asarray(sys.A), np.asarray(sys.B), np.asarray(sys.C)[:6]
    wrench_cols = [labels(sys.input_labels).index(n) for n in ("force:x", "force:y", "force:z",
                                                            "torque:x", "torque:y", "torque:z")]
    unit = np.zeros((finals.size, 1))
    unit[carriage] = 1.0
    u = -carriage_inertia_wrench(scenario, finals[:, None], unit)[0]  # the push on the table
    scale = np.ones(6) if peaks is None else np.maximum(np.asarray(peaks, dtype=float), 1e-300)
    lam, v = np.linalg.eig(a)
    w = np.linalg.inv(v)
    excitation = w @ (b[:, wrench_cols] @ u)
    modes = []
    for i in np.flatnonzero(lam.imag > 1e-9):
        response = np.abs(c @ v[:, i] * excitation[i]) / abs(lam[i]) * 2  # the pair's two halves
        omega = abs(lam[i])
        modes.append(ExcitedMode(omega / (2 * math.pi), -lam[i].real / omega, float(np.max(response / scale))))
    return sorted(modes, key=lambda m: -m.weight)


def shaped_scenario(scenario: Scenario, kind: str, peaks: Sequence[float] | None = None, modes: int = 1) -> Scenario:
    """The scenario with every carriage's move convolved with a shaper.

    Parameters
    ----------
    scenario : Scenario
        The scenario (or a bundled scenario's name, or a TOML file's path).
    kind : {"zv", "zvd", "ei"}
    peaks : sequence of float, optional
        Signal scales for ranking the modes (see :func:`dominant_modes`).
    modes : int
        Shape for this many of each carriage's most excited modes (the
        shapers convolved; each adds its own duration).

    Returns
    -------
    Scenario
        The scenario with each carriage's profile shaped (a piecewise polynomial), longer by the shapers'
        durations.

    Examples
    --------
    >>> from isolator import load_scenario, simulate
    >>> from controllers.profiles import shaped_scenario
    >>> zvd = shaped_scenario(load_scenario("paper-table-3-2"), "zvd")
    >>> round(simulate(zvd).settling_time_max, 2)  # the paper's profile: 2.31 s
    0.37
    """
    profiles = []
    for i, carriage in enumerate(scenario.carriages):
        profile = carriage.profile
        if not isinstance(profile, PiecewisePolynomialProfile) or math.isinf(profile.stop_time):
            raise ScenarioError(f"carriages[{i}].profile: input shaping needs a rest-to-rest move")
        excited = dominant_modes(scenario, i, peaks)[:modes]
        amps, times = convolved([shaper(kind, m.frequency, m.damping) for m in excited])
        profiles.append(shaped(profile, amps, times, kind=f"{kind}-shaped"))
    return with_moves(scenario, profiles)


check_public(globals())
