"""One pneumatic isolator as a frequency-dependent spring and damper, to compare with spring-damper designs.

Linearising the contract's chamber equations (``docs/scenario-format.md``,
"Pneumatic isolators and leveling") about the rest pressure ``p0`` (absolute)
gives the vertical force per displacement of an air spring with a damping
chamber behind a capillary orifice, a three-parameter (relaxation, Zener)
element:

``k(i w) = n p0 A^2 (1 + i w tau) / ((V1r + V2) + i w tau V1r)``,
``tau = V2 / (n G p0)``, ``G = pi d^4 / (128 mu L)``.

At low frequency the two chambers act as one (``k_0 = n p0 A^2 / (V1r + V2)``),
at high frequency the orifice is shut (``k_inf = n p0 A^2 / V1r``); the loss is
largest at ``w tau = sqrt(1 + N)``, ``N = V2 / V1r``. Ruzicka and Derby's
relaxation isolator: a mass on it has the smallest resonance peak
``1 + 2 / N`` when its damping is optimal.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from isolator.errors import ParameterError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.scenario.pneumatic import Air, PneumaticIsolator
from isolator.scenario.validation import isolator_rest_pressures

__all__ = ["EquivalentSpringDamper", "equivalent_spring_damper", "optimal_relaxation_time", "relaxation_time"]


@dataclass(frozen=True)
class EquivalentSpringDamper:
    """An air spring's vertical dynamic stiffness as a spring and a damper at each frequency.

    Attributes
    ----------
    frequency_hz : ndarray
        [Hz].
    stiffness : ndarray
        Storage stiffness ``Re k(i w)`` [N/m].
    damping : ndarray
        ``Im k(i w) / w`` [N s/m] (the viscous damper that dissipates as much; 0 at 0 Hz).
    static_stiffness, high_frequency_stiffness : float
        ``k_0`` and ``k_inf`` [N/m].
    relaxation_time : float
        ``tau`` [s] (0 without a damping chamber).
    gauge_pressure : float
        The rest pressure it is linearised at, ``p0 - p_atm`` [Pa].
    """

    frequency_hz: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    static_stiffness: float
    high_frequency_stiffness: float
    relaxation_time: float
    gauge_pressure: float

    @property
    def loss_factor(self) -> np.ndarray:
        """``Im k / Re k`` [-]."""
        omega = 2 * np.pi * self.frequency_hz
        return np.asarray(self.damping * omega / self.stiffness)


def relaxation_time(isolator: PneumaticIsolator, gauge_pressure: float, air: Air) -> float:
    """``tau = V2 / (n G p0)`` [s] of an isolator at a rest gauge pressure [Pa] (0 without a damping chamber)."""
    if not isolator.has_damping_chamber or isolator.orifice is None:
        return 0.0
    p0 = gauge_pressure + air.atmosphere
    return isolator.damping_volume / (air.polytropic * isolator.orifice.conductance(air.viscosity) * p0)


def optimal_relaxation_time(isolator: PneumaticIsolator, frequency_hz: float) -> float:
    """The relaxation time [s] whose loss is largest at ``frequency_hz``: ``sqrt(1 + V2 / V1r) / w``."""
    return math.sqrt(1.0 + isolator.damping_volume / isolator.volume) / (2 * math.pi * frequency_hz)


def equivalent_spring_damper(
    target: Scenario | PneumaticIsolator,
    frequency_hz: float | np.ndarray,
    *,
    isolator: str | None = None,
    gauge_pressure: float | None = None,
    air: Air | None = None,
) -> EquivalentSpringDamper | dict[str, EquivalentSpringDamper]:
    """The frequency-dependent vertical stiffness and damping of pneumatic isolators.

    Parameters
    ----------
    target : Scenario or PneumaticIsolator
        A pneumatic scenario (each isolator at its group's rest pressure with the
        carriages at their start), or one isolator.
    frequency_hz : float or ndarray
        [Hz], >= 0.
    isolator : str, optional
        With a scenario: only this isolator (by name).
    gauge_pressure : float
        With an isolator: its rest gauge pressure [Pa] (required).
    air : Air, optional
        With an isolator: the air (default :class:`Air`).

    Returns
    -------
    EquivalentSpringDamper, or dict of isolator name to it (a scenario without ``isolator``)
        The dynamic stiffness [N/m] and damping [N s/m] at each frequency, with the static and high-
        frequency stiffness and the relaxation time [s].

    Notes
    -----
    One isolator on its own: a group's connecting line carries no flow when all
    its isolators move alike, as in heave.
    """
    f = np.atleast_1d(np.asarray(frequency_hz, dtype=float))
    if f.size == 0 or not np.all(np.isfinite(f)) or np.any(f < 0):
        raise ParameterError(f"frequency_hz: must be finite frequencies >= 0 Hz, got {frequency_hz!r}")
    if isinstance(target, Scenario):
        if not target.is_pneumatic or target.air is None:
            raise ParameterError("target: the scenario's isolators are not pneumatic")
        pressures = isolator_rest_pressures(target)
        out = {}
        for k, iso in enumerate(target.isolators):
            if isinstance(iso, PneumaticIsolator):
                out[iso.name] = _equivalent(iso, float(pressures[k]), target.air, f)
        if isolator is None:
            return out
        if isolator not in out:
            raise ParameterError(f"isolator: no pneumatic isolator named '{isolator}' (have: {', '.join(out)})")
        return out[isolator]
    if not isinstance(target, PneumaticIsolator):
        raise ParameterError(
            f"target: must be a pneumatic Scenario or a PneumaticIsolator, got {type(target).__name__}"
        )
    if gauge_pressure is None or not math.isfinite(gauge_pressure) or gauge_pressure <= 0:
        raise ParameterError(
            f"gauge_pressure: the isolator's rest gauge pressure (> 0 Pa) is needed, got {gauge_pressure}"
        )
    return _equivalent(target, float(gauge_pressure), air or Air(), f)


def _equivalent(iso: PneumaticIsolator, gauge: float, air: Air, f: np.ndarray) -> EquivalentSpringDamper:
    p0 = gauge + air.atmosphere
    scale = air.polytropic * p0 * iso.area**2
    tau = relaxation_time(iso, gauge, air)
    omega = 2 * np.pi * f
    k = scale * (1 + 1j * omega * tau) / ((iso.volume + iso.damping_volume) + 1j * omega * tau * iso.volume)
    if tau == 0.0:
        k = np.full_like(omega, scale / iso.volume, dtype=complex)
    with np.errstate(invalid="ignore", divide="ignore"):
        damping = np.where(omega > 0, k.imag / np.where(omega > 0, omega, 1.0), 0.0)
    k0 = scale / (iso.volume + (iso.damping_volume if tau > 0 else 0.0))
    return EquivalentSpringDamper(f, k.real, damping, k0, scale / iso.volume, tau, gauge)


check_public(globals(), ("EquivalentSpringDamper", "equivalent_spring_damper"))
