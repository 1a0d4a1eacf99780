"""What a move costs: move time, settling time (in a stated band), cycle time, peak table motion.

Every profile method (the paper's, input shapers, time-optimal, optimised) is
judged the same way, by the true simulation: :func:`evaluate_move`. Model
variants (isolators stiffer or softer, more or less damped, a heavier or
lighter payload) test whether a gain survives an imperfect model.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

from isolator.errors import ParameterError
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Carriage, Isolator, Scenario
from isolator.scenario.pneumatic import PneumaticIsolator
from isolator.simulation.band import Band
from isolator.simulation.response import Response
from isolator.simulation.simulator import Simulator

from .move_design import MoveDesign, move_time

__all__ = [
    "ROBUSTNESS_VARIANTS",
    "ModelVariant",
    "MoveMetrics",
    "evaluate_move",
    "over_variants",
    "with_moves",
]


@dataclass(frozen=True)
class ModelVariant:
    """A model that is off: isolator stiffness, damping and payload mass scaled.

    Attributes
    ----------
    stiffness, damping : float
        Factors on every isolator's stiffness and damping.
    mass : float
        Factor on the table's mass and inertia (the isolated payload).
    """

    stiffness: float = 1.0
    damping: float = 1.0
    mass: float = 1.0

    def __post_init__(self) -> None:
        for name in ("stiffness", "damping", "mass"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ParameterError(f"variant.{name}: must be a finite factor > 0, got {value}")

    @property
    def label(self) -> str:
        """e.g. ``nominal``, ``k +15%``, ``c -15%, m +15%``."""
        parts = [f"{s} {100 * (v - 1):+.0f}%" for s, v in (("k", self.stiffness), ("c", self.damping),
                                                            ("m", self.mass)) if abs(v - 1) > 1e-12]
        return ", ".join(parts) or "nominal"

    def apply(self, scenario: Scenario) -> Scenario:
        """The scenario with this variant's isolators and table."""
        table = replace(scenario.table, mass=self.mass * scenario.table.mass,
                        inertia=_scaled(scenario.table.inertia, self.mass))
        springs = tuple(iso for iso in scenario.isolators if isinstance(iso, Isolator))
        if len(springs) == len(scenario.isolators):
            isolators: tuple[Isolator, ...] | tuple[PneumaticIsolator, ...] = tuple(
                replace(iso, stiffness=_scaled(iso.stiffness, self.stiffness),
                        damping=_scaled(iso.damping, self.damping))
                for iso in springs
            )
        else:  # pneumatic: volumes and orifice (PneumaticIsolator.scaled)
            isolators = tuple(iso.scaled(self.stiffness, self.damping) for iso in scenario.isolators
                              if isinstance(iso, PneumaticIsolator))
        return scenario.with_changes(isolators=isolators, table=table)



def _scaled(values: tuple[float, float, float], factor: float) -> tuple[float, float, float]:
    """Each of three values times ``factor``."""
    return (factor * values[0], factor * values[1], factor * values[2])


#: the variants a profile is checked against (and optimised over, when asked):
#: stiffness, damping and payload mass each 15 % off, one at a time
ROBUSTNESS_VARIANTS: tuple[ModelVariant, ...] = (
    ModelVariant(),
    ModelVariant(stiffness=0.85), ModelVariant(stiffness=1.15),
    ModelVariant(damping=0.85), ModelVariant(damping=1.15),
    ModelVariant(mass=0.85), ModelVariant(mass=1.15),
)


@dataclass(frozen=True)
class MoveMetrics:
    """One profile method's cost, from the true simulation.

    Attributes
    ----------
    label : str
    move_time : float
        From the move's command to the last carriage's stop [s].
    settling_time_max : float or None
        Largest 5 % settling time over the six signals [s] (None: the run is
        too short to show it); for pneumatic tables, of the motion about the
        slowly leveling table (``Response.dynamic_settling_time_max``).
    cycle_time : float or None
        Move plus settling [s].
    peak : dict
        Largest |signal| per table signal [m or rad].
    response : Response
    band : Band
        The band the settling time is measured in, resolved (six half-widths).
    """

    label: str
    move_time: float
    settling_time_max: float | None
    cycle_time: float | None
    peak: dict[str, float]
    response: Response = field(repr=False, compare=False)

    @property
    def band(self) -> Band:
        return self.response.band

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: label, move_time, settling_time_max, cycle_time, peak, band [s, m, rad]."""
        return {"label": self.label, "move_time": self.move_time, "settling_time_max": self.settling_time_max,
                "cycle_time": self.cycle_time, "peak": dict(self.peak), "band": self.band.to_dict()}


def with_moves(scenario: Scenario, profiles: Sequence[Any]) -> Scenario:
    """The scenario with each carriage's profile replaced (one profile or MoveDesign per carriage).

    Parameters
    ----------
    scenario : Scenario
        The scenario (or a bundled scenario's name, or a TOML file's path).
    profiles : sequence of Profile or MoveDesign
        One per carriage, in the scenario's order.

    Returns
    -------
    Scenario
        The scenario with those profiles.
    """
    if len(profiles) != len(scenario.carriages):
        raise ParameterError(f"profiles: need one per carriage ({len(scenario.carriages)}), got {len(profiles)}")
    carriages: list[Carriage] = []
    for carriage, prof in zip(scenario.carriages, profiles, strict=True):
        made = prof.profile() if isinstance(prof, MoveDesign) else prof
        carriages.append(replace(carriage, profile=made))
    return scenario.with_changes(carriages=tuple(carriages))


def evaluate_move(
    scenario: Scenario, label: str, command: float, variant: ModelVariant | None = None, duration: float | None = None,
    band: Band | None = None,
) -> MoveMetrics:
    """Simulate a scenario's move and measure it.

    Parameters
    ----------
    scenario : Scenario
        With the profiles to judge.
    label : str
        The method's name, in reports and figures.
    command : float
        When the move is commanded [s] (the move time counts from there).
    variant : ModelVariant, optional
        Judge it on a model that is off.
    duration : float, optional
        Simulated time [s] (default: the scenario's).
    band : Band, optional
        The settling band (default: the scenario's ``[settling]`` rule, each run's own 5 %); give one band
        to compare methods on it (``Band.of_baseline``).

    Returns
    -------
    MoveMetrics
        The run with its move time, 5 % settling time and cycle time [s], under ``label``.
    """
    run_scenario = variant.apply(scenario) if variant is not None else scenario
    if duration is not None:
        run_scenario = run_scenario.with_changes(simulation=replace(run_scenario.simulation, duration=duration))
    response = Simulator(run_scenario).run(band=band)
    moved = move_time(run_scenario, command)
    settle = response.dynamic_settling_time_max  # pneumatic: about the leveling table
    return MoveMetrics(
        label=label, move_time=moved, settling_time_max=settle,
        cycle_time=None if settle is None else moved + settle,
        peak={k: float(v) for k, v in response.peak.items()}, response=response,
    )


def over_variants(scenario: Scenario, label: str, command: float,
                  variants: Sequence[ModelVariant] = ROBUSTNESS_VARIANTS,
                  band: Band | None = None) -> list[MoveMetrics]:
    """The move measured on each model variant (labelled ``<label> (<variant>)``), in ``band``.

    Parameters
    ----------
    scenario : Scenario
        The scenario (or a bundled scenario's name, or a TOML file's path).
    label : str
        The method's name; each result is labelled ``<label> (<variant>)``.
    command : float
        When the move is commanded [s] (the move time counts from there).
    variants : sequence of ModelVariant
        Models that are off (isolator stiffness and damping, payload mass); default the three the profile
        study uses.
    band : Band, optional
        The settling band all variants are judged in; default each run's own.

    Returns
    -------
    list of MoveMetrics
        One per variant, in order.
    """
    return [evaluate_move(scenario, f"{label} ({v.label})", command, v, band=band) for v in variants]


check_public(globals())
