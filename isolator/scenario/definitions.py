"""The scenario: a table on isolators carrying carriages, as frozen dataclasses.

Read one with :func:`isolator.load_scenario`; the file format is described in
``docs/scenario-format.md``. All quantities are SI (m, kg, s, N, rad).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from isolator.scenario.actuators import Actuator, Point, Vector3
from isolator.scenario.arguments import check_public
from isolator.scenario.flexible import FlexibleTop, ModalData
from isolator.scenario.flexible.reader import Feet, tupled_feet
from isolator.scenario.ground import SIGNALS, FloorSpectrum, Ground
from isolator.scenario.pneumatic import Air, LevelingGroup, PneumaticIsolator
from isolator.scenario.profiles import Profile
from isolator.scenario.random_sources import Disturbance
from isolator.scenario.sensors import Sensor
from isolator.scenario.sequence import StepSequence
from isolator.scenario.windows import Window

__all__ = [
    "SIGNALS",
    "Actuator",
    "Carriage",
    "FloorSpectrum",
    "Ground",
    "Isolator",
    "MotionLimits",
    "Point",
    "Scenario",
    "Settling",
    "SimulationSettings",
    "Table",
]


@dataclass(frozen=True)
class Table:
    """The table: a rigid body, or a top that bends.

    Attributes
    ----------
    mass : float
        [kg]
    inertia : tuple of float
        Principal moments about the mass centre along the table axes [kg m^2].
    size : tuple of float or None
        Box length, width, thickness [m], if given.
    flexible : FlexibleTop or None
        The top's elastic modes (``[table.flexible]``); None: a rigid top.
    """

    mass: float
    inertia: Vector3
    size: Vector3 | None = None
    flexible: FlexibleTop | None = None


@dataclass(frozen=True)
class Isolator:
    """A spring-damper between ground and table, acting along the world axes.

    Attributes
    ----------
    position : tuple of float
        Attachment point in the table frame [m].
    stiffness : tuple of float
        Along world x, y, z [N/m].
    damping : tuple of float
        Along world x, y, z [N s/m].
    name : str
    """

    position: Vector3
    stiffness: Vector3
    damping: Vector3
    name: str = ""


@dataclass(frozen=True)
class MotionLimits:
    """What a carriage's drive can do, for profile design (None: not given).

    Attributes
    ----------
    velocity : float or None
        Largest speed [m/s].
    acceleration : float or None
        Largest acceleration and deceleration [m/s^2].
    jerk : float or None
        Largest jerk [m/s^3].
    """

    velocity: float | None = None
    acceleration: float | None = None
    jerk: float | None = None


@dataclass(frozen=True)
class Carriage:
    """A point mass translating along an axis of its parent.

    Attributes
    ----------
    name : str
    mass : float
        [kg]
    parent : str
        "table" or another carriage's name.
    axis : tuple of float
        Unit direction of travel in the table frame.
    origin : tuple of float
        Position of the mass at q = 0 relative to the parent's point [m].
    profile : Profile
        q(t) [m].
    limits : MotionLimits
        The drive's speed, acceleration and jerk limits, for profile design.
    feet : tuple of (float, float) or None
        Where a carriage on a bending top rides it: (x, y) offsets from its position [m] (its rails); None:
        one foot at its position.
    """

    name: str
    mass: float
    parent: str
    axis: Vector3
    origin: Vector3
    profile: Profile
    limits: MotionLimits = MotionLimits()
    feet: Feet | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "feet", tupled_feet(self.feet))


@dataclass(frozen=True)
class Settling:
    """The settling band: a fraction of each signal's peak, or absolute tolerances.

    Attributes
    ----------
    fraction : float or None
        Band as a fraction of the signal's peak (0.05: the paper's criterion).
    tolerance : tuple of float or None
        Absolute band: (translation [m], rotation [rad]).
    """

    fraction: float | None = 0.05
    tolerance: tuple[float, float] | None = None

    def band(self, signal: str, peak: float) -> float:
        """Half-width of the band for ``signal`` whose peak is ``peak``."""
        if self.tolerance is not None:
            return self.tolerance[1] if signal.startswith("r") else self.tolerance[0]
        return float(self.fraction) * peak  # type: ignore[arg-type]


@dataclass(frozen=True)
class SimulationSettings:
    """Time span and output sampling.

    Attributes
    ----------
    duration : float
        Simulated time from t = 0 [s].
    sample_rate : float
        Output samples per second [Hz].
    """

    duration: float = 10.0
    sample_rate: float = 1000.0

    def sample_times(self) -> np.ndarray:
        """Output sample times ``k / sample_rate`` from 0 up to ``duration`` [s]."""
        n = int(np.floor(self.duration * self.sample_rate * (1 + 1e-12))) + 1
        return np.arange(n) / self.sample_rate


@dataclass(frozen=True)
class Scenario:
    """A validated, immutable scenario. Build one with :func:`isolator.load_scenario`.

    Its isolators are all spring-dampers (:class:`Isolator`) or all pneumatic
    (:class:`PneumaticIsolator`, with ``air`` and the ``leveling`` groups). With a ``sequence``
    (``[sequence]``, :func:`isolator.run_sequence`) the carriages' profiles hold them at the sequence's
    initial positions.

    Attributes
    ----------
    name : str
        The scenario's name (results and files are named after it).
    table : Table
        The rigid table: mass [kg], inertia [kg m^2], size [m].
    isolators : tuple of Isolator or tuple of PneumaticIsolator
        Three or more, all spring-dampers or all pneumatic.
    carriages : tuple of Carriage
        The moving masses, a chain or tree on the table, each with its profile.
    actuators : tuple of Actuator
        Force actuators between floor and table (``[[actuators]]``).
    simulation : SimulationSettings
        Duration [s] and output sample rate [Hz] of a run.
    settling : Settling
        The settling rule: band fraction (5 %) and tolerance.
    gravity : float
        [m/s^2].
    ground : Ground or None
        Prescribed floor motion and the floor's spectrum (``[ground]``).
    points : tuple of Point
        Named table points whose motion runs report (``[[points]]``).
    air : Air or None
        The air's properties; set for pneumatic isolators only.
    leveling : tuple of LevelingGroup
        The pneumatic isolators' leveling groups and valves.
    windows : tuple of Window
        Absolute windows at points, for window settling (``[[windows]]``).
    sequence : StepSequence or None
        Step-and-settle steps (``[sequence]``).
    sensors : tuple of Sensor
        Table or floor sensors (``[[sensors]]``).
    disturbances : tuple of Disturbance
        Random forces on the table (``[[disturbances]]``), sources of the error budget.
    """

    name: str
    table: Table
    isolators: tuple[Isolator, ...] | tuple[PneumaticIsolator, ...]
    carriages: tuple[Carriage, ...] = ()
    actuators: tuple[Actuator, ...] = ()
    simulation: SimulationSettings = SimulationSettings()
    settling: Settling = Settling()
    gravity: float = 9.81
    ground: Ground | None = None
    points: tuple[Point, ...] = ()
    air: Air | None = None
    leveling: tuple[LevelingGroup, ...] = ()
    windows: tuple[Window, ...] = ()
    sequence: StepSequence | None = None
    sensors: tuple[Sensor, ...] = ()
    disturbances: tuple[Disturbance, ...] = ()

    # -- derived quantities -------------------------------------------------
    @property
    def total_mass(self) -> float:
        """Table plus carriages [kg]."""
        return self.table.mass + sum(c.mass for c in self.carriages)

    @property
    def modal_data(self) -> ModalData | None:
        """The bending top's kept elastic modes (``[table.flexible]``), None for a rigid top."""
        return None if self.table.flexible is None else self.table.flexible.data

    @property
    def is_pneumatic(self) -> bool:
        """Whether the isolators are pneumatic (air springs with leveling groups)."""
        return self.air is not None

    @property
    def stop_time(self) -> float:
        """Latest time any carriage stops [s]; inf when one never stops; 0 with none."""
        return max((c.profile.stop_time for c in self.carriages), default=0.0)

    @property
    def breakpoints(self) -> tuple[float, ...]:
        """Sorted times [s] where some carriage's or the floor's acceleration may jump."""
        floor = self.ground.breakpoints if self.ground is not None else ()
        return tuple(sorted({b for c in self.carriages for b in c.profile.breakpoints} | set(floor)))

    @property
    def has_ground_motion(self) -> bool:
        """Whether the floor moves (a ``[ground]`` section with motion)."""
        return self.ground is not None and bool(self.ground.motion)

    def parent_indices(self) -> tuple[int, ...]:
        """Index of each carriage's parent carriage, -1 for the table."""
        index = {c.name: i for i, c in enumerate(self.carriages)}
        return tuple(-1 if c.parent == "table" else index[c.parent] for c in self.carriages)

    def carriage_order(self) -> tuple[int, ...]:
        """Carriage indices ordered so that every parent comes before its children."""
        parents = self.parent_indices()
        order: list[int] = []
        placed: set[int] = set()
        while len(order) < len(parents):
            for i, p in enumerate(parents):
                if i not in placed and (p == -1 or p in placed):
                    order.append(i)
                    placed.add(i)
        return tuple(order)

    def carriage_positions(self, q: np.ndarray) -> np.ndarray:
        """Mass positions of all carriages in the table frame [m].

        Parameters
        ----------
        q : ndarray, shape (n_carriages, ...)
            Carriage coordinates [m].

        Returns
        -------
        ndarray, shape (n_carriages, 3, ...)
        """
        q = np.asarray(q, dtype=float)
        parents = self.parent_indices()
        out = np.zeros((len(self.carriages), 3, *q.shape[1:]))
        for i in self.carriage_order():
            c = self.carriages[i]
            base = out[parents[i]] if parents[i] >= 0 else 0.0
            axis = np.asarray(c.axis).reshape((3,) + (1,) * (q.ndim - 1))
            origin = np.asarray(c.origin).reshape(axis.shape)
            out[i] = base + origin + axis * q[i]
        return out

    def outside_footprint(self, q: np.ndarray) -> tuple[int, int, int, float] | None:
        """The first carriage whose mass leaves the table's footprint, if any.

        Parameters
        ----------
        q : ndarray, shape (n_carriages,) or (n_carriages, N)
            Carriage coordinates [m], one column per configuration.

        Returns
        -------
        tuple or None
            ``(carriage index, axis (0: x, 1: y), column of its farthest reach,
            that coordinate [m])``; None when all stay within ``|x| <= length/2``,
            ``|y| <= width/2`` (or the table has no size).
        """
        if self.table.size is None or not self.carriages:
            return None
        pos = self.carriage_positions(np.asarray(q, dtype=float).reshape(len(self.carriages), -1))
        half = np.array(self.table.size[:2]) / 2.0
        for i in range(len(self.carriages)):
            for axis in (0, 1):
                reach = np.abs(pos[i, axis])
                k = int(np.argmax(reach))
                if reach[k] > half[axis] * (1 + 1e-9):
                    return i, axis, k, float(pos[i, axis, k])
        return None

    def travel(self) -> np.ndarray:
        """Each carriage's travel [m], (carriages, 2): the least and greatest position its profile reaches over
        the run (to its stop, when that is later), or with a ``[sequence]`` those of its start and targets."""
        if self.sequence is not None:
            q = self.sequence.configurations([c.name for c in self.carriages])
            return np.column_stack([q.min(axis=0), q.max(axis=0)]).reshape(-1, 2)
        stop = self.stop_time
        t_end = max(self.simulation.duration, stop if stop < float("inf") else 0.0)
        return np.array([c.profile.position_range(t_end) for c in self.carriages], dtype=float).reshape(-1, 2)

    def initial_positions(self) -> np.ndarray:
        """Carriage coordinates at t = 0 [m]."""
        return np.array([c.profile.position(0.0) for c in self.carriages])

    def final_positions(self) -> np.ndarray | None:
        """Carriage coordinates once all have stopped [m], None if one never stops."""
        finals = [c.profile.final_position for c in self.carriages]
        if any(f is None for f in finals):
            return None
        return np.array(finals, dtype=float)

    def isolator_preloads(self) -> np.ndarray:
        """Vertical static force of each isolator at the reference pose [N].

        All isolators have the same free height, so together they carry the
        whole weight: ``k_z * g * total_mass / sum(k_z)`` (zeros for pneumatic isolators, whose load is
        their chamber pressure) (``docs/scenario-format.md``;
        :func:`isolator.model.elements.spring_damper.isolator_preloads` is the symbolic form).
        """
        kz = np.array([iso.stiffness[2] if isinstance(iso, Isolator) else 0.0 for iso in self.isolators])
        total = kz.sum()
        return kz * (self.gravity * self.total_mass / total) if total > 0 else np.zeros_like(kz)

    def with_changes(self, **changes: object) -> Scenario:
        """A copy with top-level fields replaced (see :func:`dataclasses.replace`)."""
        return replace(self, **changes)  # type: ignore[arg-type]


check_public(globals(), ("Actuator", "Carriage", "Isolator", "MotionLimits", "Point", "Scenario", "Settling",
                         "SimulationSettings", "Table"))
