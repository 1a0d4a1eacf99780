"""The air in a pneumatic table's chambers, written again in plain numpy for the MuJoCo check.

The equations are the contract of ``docs/scenario-format.md`` ("Pneumatic
isolators and leveling"), transcribed independently of the toolkit's casadi
element so that the check shares nothing with the model but the scenario:

- spring chamber volume ``V1 = V1r + A s`` (``s``: world z displacement of
  the attachment point relative to its floor point, from the initial
  equilibrium);
- capillary mass flow from a to b ``G (pa - pb)(pa + pb) / (2 R T)``,
  ``G = pi d^4 / (128 mu L)`` (orifice between an isolator's chambers; a
  group's line between each consecutive pair of its spring chambers);
- ``dp1/dt = n / V1 (R T mdot_in1 - p1 dV1/dt)``, ``dp2/dt = n / V2 R T mdot_in2``;
- valve flow into a group ``clip(gain dz(-h), -max_flow, max_flow)`` with
  ``dz(e) = sign(e) max(|e| - deadband, 0)``, no filling while a spring
  chamber of the group is at or above ``p_atm + supply``, no exhausting while
  one is at or below ``p_atm``, split equally among the group's chambers.

Pressures are absolute [Pa]. The chamber vector holds every spring chamber
(isolator order), then the damping chamber of every isolator that has one.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from isolator.errors import ScenarioError
from isolator.scenario.definitions import Scenario
from isolator.scenario.pneumatic import PneumaticIsolator

__all__ = ["AirChambers"]


def _conductance(diameter: float, length: float, viscosity: float) -> float:
    """Hagen-Poiseuille conductance ``pi d^4 / (128 mu L)`` [m^3/(Pa s)] of a capillary."""
    return math.pi * diameter**4 / (128.0 * viscosity * length)


class AirChambers:
    """Chamber pressures of a pneumatic scenario: their rates and the forces they put on the table.

    Parameters
    ----------
    scenario : Scenario
        A pneumatic scenario (every isolator a :class:`PneumaticIsolator`).

    Attributes
    ----------
    isolators : tuple of PneumaticIsolator
    damped : ndarray of int
        Isolators with a damping chamber, in the order of their pressures in the chamber vector.
    n_chambers : int
        Spring chambers plus damping chambers.
    """

    def __init__(self, scenario: Scenario) -> None:
        if scenario.air is None:
            raise ScenarioError("isolators: not a pneumatic scenario")
        isolators = tuple(iso for iso in scenario.isolators if isinstance(iso, PneumaticIsolator))
        if len(isolators) != len(scenario.isolators):
            raise ScenarioError("isolators: a pneumatic scenario's isolators must all be pneumatic")
        air = scenario.air
        self.isolators = isolators
        self.groups = scenario.leveling
        self.p_atm = float(air.atmosphere)
        self.rt = float(air.gas_constant * air.temperature)
        self.n = float(air.polytropic)
        self.area = np.array([iso.area for iso in isolators], dtype=float)
        self.rest_volume = np.array([iso.volume for iso in isolators], dtype=float)
        self.damped = np.array([k for k, iso in enumerate(isolators) if iso.damping_volume > 0.0], dtype=int)
        self.damping_volume = np.array([isolators[k].damping_volume for k in self.damped], dtype=float)
        orifices = []
        for k in self.damped:
            orifice = isolators[k].orifice
            if orifice is None:
                raise ScenarioError(f"isolators: {isolators[k].name} has a damping chamber but no orifice")
            orifices.append(_conductance(orifice.diameter, orifice.length, air.viscosity))
        self.orifice = np.array(orifices, dtype=float)
        self.lines: list[tuple[int, int, float]] = []  # (from, to, conductance) between spring chambers
        for group in self.groups:
            if len(group.isolators) > 1 and group.line is not None:
                g = _conductance(group.line.diameter, group.line.length, air.viscosity)
                self.lines += [(a, b, g) for a, b in itertools.pairwise(group.isolators)]
        self.n_chambers = len(isolators) + self.damped.size

    def _flow(self, g: float | np.ndarray, pa: float | np.ndarray, pb: float | np.ndarray) -> np.ndarray:
        """Capillary mass flow from a to b [kg/s]."""
        return np.asarray(g * (pa - pb) * (pa + pb) / (2.0 * self.rt))

    def initial(self, group_gauge: np.ndarray) -> np.ndarray:
        """The chamber vector (absolute [Pa]) with each group at its gauge pressure ``group_gauge`` [Pa].

        Every spring chamber of a group at the group's pressure, every damping
        chamber at its spring chamber's.
        """
        p1 = np.empty(len(self.isolators))
        for j, group in enumerate(self.groups):
            p1[list(group.isolators)] = self.p_atm + float(group_gauge[j])
        return np.concatenate([p1, p1[self.damped]])

    def group_areas(self) -> np.ndarray:
        """(isolators, groups): the piston area [m^2] of each isolator in its group's column."""
        out = np.zeros((len(self.isolators), len(self.groups)))
        for j, group in enumerate(self.groups):
            out[list(group.isolators), j] = self.area[list(group.isolators)]
        return out

    def vertical_forces(self, p: np.ndarray) -> np.ndarray:
        """Force of each air spring on the table along world +z, ``(p1 - p_atm) A`` [N]."""
        return (p[: len(self.isolators)] - self.p_atm) * self.area

    def gauge(self, chambers: np.ndarray) -> np.ndarray:
        """Spring chamber gauge pressures (isolators, N) [Pa] from chamber vectors (N, n_chambers)."""
        return np.asarray(chambers[:, : len(self.isolators)] - self.p_atm).T

    def valve_flow(self, j: int, height: float, p1: np.ndarray) -> float:
        """Mass flow into group ``j`` through its valve [kg/s] (0 without a valve).

        Parameters
        ----------
        j : int
            Group index.
        height : float
            Its sensor's height from the initial equilibrium [m].
        p1 : ndarray
            All spring chamber pressures (absolute) [Pa].
        """
        group = self.groups[j]
        valve = group.valve
        if valve is None:
            return 0.0
        error = -height
        excess = max(abs(error) - valve.deadband, 0.0)
        flow = min(max(valve.gain * math.copysign(excess, error), -valve.max_flow), valve.max_flow)
        members = p1[list(group.isolators)]
        if flow > 0.0 and np.max(members) >= self.p_atm + group.supply:
            return 0.0
        if flow < 0.0 and np.min(members) <= self.p_atm:
            return 0.0
        return flow

    def rates(self, p: np.ndarray, stroke: np.ndarray, stroke_rate: np.ndarray, heights: np.ndarray) -> np.ndarray:
        """Pressure rates of the chamber vector [Pa/s].

        Parameters
        ----------
        p : ndarray (n_chambers,)
            Absolute pressures [Pa].
        stroke : ndarray (isolators,)
            ``s``: world z displacement of each attachment point relative to its floor point [m].
        stroke_rate : ndarray (isolators,)
            ``ds/dt`` [m/s].
        heights : ndarray (groups,)
            Each group's sensor height [m].
        """
        m = len(self.isolators)
        p1, p2 = p[:m], p[m:]
        inflow1 = np.zeros(m)
        orifice = self._flow(self.orifice, p2, p1[self.damped])  # damping -> spring chamber
        np.add.at(inflow1, self.damped, orifice)
        for a, b, g in self.lines:
            flow = float(self._flow(g, p1[a], p1[b]))
            inflow1[a] -= flow
            inflow1[b] += flow
        for j, group in enumerate(self.groups):
            flow = self.valve_flow(j, float(heights[j]), p1)
            inflow1[list(group.isolators)] += flow / len(group.isolators)
        volume = self.rest_volume + self.area * stroke
        rate1 = self.n / volume * (self.rt * inflow1 - p1 * self.area * stroke_rate)
        rate2 = self.n / self.damping_volume * self.rt * (-orifice)
        return np.concatenate([rate1, rate2])
