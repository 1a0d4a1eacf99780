"""A design judged on the bending top: where the sampled loop on the full plant (the top's elastic modes
included) is unstable or short of its disk margin, the commands are rolled off above the isolation band.

``docs/scenario-format.md``, "Controllers on a bending top": a design may be made on any model; it is judged
on the full one, by the loop every check closes (:func:`isolator.analysis.closed_loop.sampled_loop`). On a
scenario with ``[table.flexible]``, :func:`roll_off` closes each design's loop at the design positions and
the carriages' start; when one is unstable, or its multiloop disk margin at the actuators is below
:data:`MIN_DISK_MARGIN`, each actuator's command passes a second-order Butterworth low-pass (discrete, unit
gain at DC) with the highest corner that makes them all stable with that margin, tried from half the lowest
elastic mode down to :data:`BAND_FACTOR` times the highest rigid-body mode (the isolation band's top). The
choice is recorded in ``settings["rolloff"]``: the kind, the corner [Hz], the order, why, and the spectral
radius before. A rigid top's design is returned unchanged.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np
from scipy.signal import butter, tf2ss

from isolator.analysis.closed_loop import SampledLoop, sampled_loop
from isolator.analysis.linear import LinearModel
from isolator.analysis.modes import modes
from isolator.model.equilibrium import DOF_NAMES
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.simulation.discrete_controller import DiscreteController, ScheduleEntry

from .loop_margins import sampled_margins

__all__ = ["BAND_FACTOR", "MIN_DISK_MARGIN", "lowpass", "rigid_top", "roll_off", "with_lowpass"]

#: the smallest multiloop disk margin [-] at the actuators a design keeps on the full plant (gain x1.67 or
#: 0.6, phase 28 deg at once)
MIN_DISK_MARGIN = 0.5
#: the lowest corner tried: this many times the highest rigid-body mode [Hz] (the isolation band's top)
BAND_FACTOR = 5.0
#: corners tried, geometrically spaced from half the lowest elastic mode down to the lowest
_CORNERS = 10


def rigid_top(scenario: Scenario) -> Scenario:
    """``scenario`` with its top rigid: the reduced model a bending top's designs are made on.

    Parameters
    ----------
    scenario : Scenario
        Any scenario; the six rigid modes of a bending top's modal file are its ``[table]`` mass and inertia
        (checked when it was read).

    Returns
    -------
    Scenario
        The same scenario without ``[table.flexible]`` (a rigid top's scenario itself).
    """
    table = scenario.table
    if getattr(table, "flexible", None) is None:
        return scenario
    return replace(scenario, table=replace(table, flexible=None))


def lowpass(corner_hz: float, sample_rate: float, channels: int
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(A, B, C, D)`` of ``channels`` independent discrete second-order Butterworth low-passes (bilinear,
    the corner prewarped; unit gain at DC) at ``sample_rate`` [Hz]."""
    b, a = butter(2, corner_hz, fs=sample_rate)
    a1, b1, c1, d1 = (np.atleast_2d(np.asarray(x, dtype=float)) for x in tf2ss(b, a))
    eye = np.eye(channels)
    return np.kron(eye, a1), np.kron(eye, b1), np.kron(eye, c1), np.kron(eye, d1)


def _series(k: Sequence[np.ndarray], f: Sequence[np.ndarray]) -> tuple[np.ndarray, ...]:
    """The controller ``k`` followed by the filter ``f`` (states ``[x_k, x_f]``)."""
    ak, bk, ck, dk = (np.asarray(x, dtype=float) for x in k)
    af, bf, cf, df = f
    nk, nf = ak.shape[0], af.shape[0]
    a = np.block([[ak, np.zeros((nk, nf))], [bf @ ck, af]])
    return a, np.vstack([bk, bf @ dk]), np.hstack([df @ ck, cf]), df @ dk


def with_lowpass(controller: DiscreteController, corner_hz: float, record: dict[str, Any]) -> DiscreteController:
    """``controller`` with each command through :func:`lowpass` at ``corner_hz`` [Hz] (every design point of a
    schedule alike), ``record`` added to its settings as ``"rolloff"``."""
    f = lowpass(corner_hz, controller.sample_rate, len(controller.actuators))
    settings = {**controller.settings, "rolloff": record}
    if controller.schedule:
        entries = [ScheduleEntry(e.q, *_series((e.A, e.B, e.C, e.D), f)) for e in controller.schedule]
        return replace(controller, schedule=entries, settings=settings)
    a, b, c, d = _series(controller.matrices(), f)
    return replace(controller, A=a, B=b, C=c, D=d, settings=settings)


def _judged(loops: Sequence[SampledLoop]) -> tuple[float, float]:
    """The worst spectral radius and (when all are stable) the smallest multiloop disk margin."""
    radius = max(loop.spectral_radius for loop in loops)
    if radius >= 1.0:
        return radius, 0.0
    return radius, min(sampled_margins(loop).disk_margin for loop in loops)


def roll_off(controller: DiscreteController, lins: Sequence[LinearModel]) -> DiscreteController:
    """``controller`` judged on the full plant at each of ``lins`` (the design positions and the start), rolled
    off when unstable or short of :data:`MIN_DISK_MARGIN` there (see the module's description).

    Parameters
    ----------
    controller : DiscreteController
        The design, as made on its (possibly reduced) plant.
    lins : sequence of LinearModel
        The full plant, with the top's elastic modes, at the positions it is judged at.

    Returns
    -------
    DiscreteController
        Unchanged on a rigid top or when the full plant's loops are good; else low-passed with the highest
        corner that makes them good (``settings["rolloff"]``), or, when none does, the lowest corner tried,
        recorded as ``"insufficient"`` (the robustness check then refuses it, naming where).
    """
    if not lins or getattr(lins[0].scenario.table, "flexible", None) is None:
        return controller
    radius, margin = _judged([sampled_loop(lin, controller) for lin in lins])
    if radius < 1.0 and margin >= MIN_DISK_MARGIN:
        return controller
    table = modes(lins[0])
    rigid = [f for f, d in zip(table.frequencies_hz, table.dominant, strict=True) if d in DOF_NAMES]
    elastic = [f for f, d in zip(table.frequencies_hz, table.dominant, strict=True) if d not in DOF_NAMES]
    if not elastic:
        return controller
    top = 0.5 * min(min(elastic), 0.45 * controller.sample_rate)
    low = min(top, BAND_FACTOR * max(rigid, default=1.0))
    why = (f"the loop on the full plant is unstable (spectral radius {radius:.6g})" if radius >= 1.0 else
           f"the disk margin on the full plant is {margin:.3g} < {MIN_DISK_MARGIN}")
    candidate = controller
    for corner in np.geomspace(top, low, _CORNERS):
        record = {"kind": "low-pass", "order": 2, "corner_hz": float(corner), "reason": why,
                  "lowest_elastic_mode_hz": float(min(elastic)), "spectral_radius_before": radius}
        candidate = with_lowpass(controller, float(corner), record)
        r, mg = _judged([sampled_loop(lin, candidate) for lin in lins])
        if r < 1.0 and mg >= MIN_DISK_MARGIN:
            return candidate
    return with_lowpass(controller, float(low), {**candidate.settings["rolloff"], "insufficient": True})


check_public(globals())
