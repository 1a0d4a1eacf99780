"""Sensors (``[[sensors]]``): what a real table measures, in scenario files and calibration files.

A table sensor measures the motion of a point fixed to the table along a fixed world direction (its
displacement from the initial equilibrium [m], its velocity [m/s] or its acceleration [m/s^2]; no gravity or
tilt term); a floor sensor measures the floor's translation along its direction (``position`` is recorded
only). The contract is in ``docs/scenario-format.md`` ("Calibration from measured records", "Sensors in the
scenario").
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from isolator.errors import ScenarioError
from isolator.scenario.keys import KeyReader, check_placement, number, table_of_tables
from isolator.scenario.names import check_name
from isolator.scenario.random_sources import SpectralDensity, read_density

__all__ = ["QUANTITIES", "SENSOR_SITES", "UFF_DIRECTIONS", "Sensor", "read_sensors", "sensor_from_dict"]

#: what a sensor measures, with its SI unit
QUANTITIES = {"displacement": "m", "velocity": "m/s", "acceleration": "m/s^2"}
#: where a sensor sits
SENSOR_SITES = ("table", "floor")
#: a UFF channel's direction as a sensor names it
UFF_DIRECTIONS = ("+X", "-X", "+Y", "-Y", "+Z", "-Z")
#: names a record's columns already use
_RESERVED = ("t",)


@dataclass(frozen=True)
class Sensor:
    """One sensor of the table or the floor.

    Attributes
    ----------
    name : str
        Unique; the column ``s:<name>`` of simulation results and the column of a record.
    on : {"table", "floor"}
    position : tuple of float
        [m]; table frame at rest (a table sensor), world frame (a floor sensor: recorded only).
    direction : tuple of float
        World frame, unit vector.
    quantity : {"displacement", "velocity", "acceleration"}
        Signal [m], [m/s] or [m/s^2].
    noise : float
        RMS of the white noise added to each sample [SI units of the quantity] (default 0).
    uff : tuple of (int, str) or None
        The UFF58 channel (node, direction "+X" ... "-Z") that holds this sensor in a UFF record.
    noise_psd : SpectralDensity or None
        One-sided PSD of the sensor's noise [SI^2/Hz] (instead of ``noise``): the noise is a sequence of
        samples at the controller's rate whose PSD below half that rate is this.
    """

    name: str
    on: str
    position: tuple[float, float, float]
    direction: tuple[float, float, float]
    quantity: str
    noise: float = 0.0
    uff: tuple[int, str] | None = None
    noise_psd: SpectralDensity | None = None

    def __post_init__(self) -> None:
        check_sensor(self, "sensor")

    @property
    def unit(self) -> str:
        """The SI unit of the quantity."""
        return QUANTITIES[self.quantity]

    def noise_density(self, sample_rate: float) -> SpectralDensity | None:
        """The noise's one-sided PSD [SI^2/Hz] when sampled at ``sample_rate`` [Hz]: ``noise_psd``, or the flat
        ``2 noise^2 / sample_rate`` of white noise of ``noise`` RMS per sample; None for a noiseless sensor."""
        if self.noise_psd is not None:
            return self.noise_psd
        return SpectralDensity.flat(2.0 * self.noise**2 / sample_rate) if self.noise > 0 else None

    def noise_rms(self, sample_rate: float) -> float:
        """RMS per sample [SI units] of the noise sampled at ``sample_rate`` [Hz]: ``noise``, or the root of
        ``noise_psd`` integrated up to half the rate (what a design that models the noise as white per sample
        assumes)."""
        if self.noise_psd is None:
            return self.noise
        return math.sqrt(self.noise_psd.integral(sample_rate / 2.0))

    @property
    def order(self) -> int:
        """Time derivatives of displacement the quantity is: 0, 1 or 2."""
        return tuple(QUANTITIES).index(self.quantity)


def check_sensor(sensor: Sensor, key: str) -> None:
    """Refuse a sensor built with wrong values (:class:`ScenarioError` naming ``key`` and the field)."""
    check_name(sensor.name, f"{key}.name")
    if sensor.name in _RESERVED:
        raise ScenarioError(f"{key}.name: '{sensor.name}' is the records' time column; choose another name")
    if sensor.on not in SENSOR_SITES:
        raise ScenarioError(f"{key}.on: must be \"table\" or \"floor\", got {sensor.on!r}")
    if sensor.quantity not in QUANTITIES:
        raise ScenarioError(f"{key}.quantity: must be one of {', '.join(QUANTITIES)}, got {sensor.quantity!r}")
    check_placement(sensor.position, sensor.direction, key)
    number(sensor.noise, f"{key}.noise", nonnegative=True)
    if sensor.noise_psd is not None:
        if not isinstance(sensor.noise_psd, SpectralDensity):
            raise ScenarioError(f"{key}.noise_psd: must be a SpectralDensity [SI^2/Hz], got "
                                f"{type(sensor.noise_psd).__name__}")
        if sensor.noise > 0:
            raise ScenarioError(f"{key}.noise_psd: give noise (white, RMS per sample) or noise_psd (a spectrum), "
                                "not both")
    if sensor.uff is not None:
        node, direction = sensor.uff
        if isinstance(node, bool) or not isinstance(node, int) or node < 0:
            raise ScenarioError(f"{key}.uff.node: must be a whole number >= 0, got {node!r}")
        if direction not in UFF_DIRECTIONS:
            raise ScenarioError(f"{key}.uff.direction: must be one of {', '.join(UFF_DIRECTIONS)}, got {direction!r}")


def sensor_from_dict(item: Any, key: str) -> Sensor:
    """One ``[[sensors]]`` block read key by key (every problem a :class:`ScenarioError` naming the key)."""
    r = KeyReader(item, key)
    name = r.string("name")
    on = r.string("on")
    quantity = r.string("quantity")
    position = r.vector("position")
    direction = r.unit_vector("direction")
    noise = r.number("noise", 0.0, nonnegative=True)
    uff = _read_uff(r.raw("uff", None), r.key("uff"))
    psd = read_density(r.raw("noise_psd"), r.key("noise_psd")) if r.has("noise_psd") else None
    r.used.add("noise_psd")
    r.finish()
    return _build(name, on, position, direction, quantity, noise, uff, key, psd)


def _build(name: str, on: str, position: tuple[float, float, float], direction: tuple[float, float, float],
           quantity: str, noise: float, uff: tuple[int, str] | None, key: str,
           noise_psd: SpectralDensity | None = None) -> Sensor:
    """The sensor, its own checks naming the file's key (``sensors[2].quantity``)."""
    try:
        return Sensor(name, on, position, direction, quantity, noise, uff, noise_psd)
    except ScenarioError as exc:
        raise ScenarioError(str(exc).replace("sensor.", f"{key}.", 1)) from None


def _read_uff(value: Any, key: str) -> tuple[int, str] | None:
    if value is None:
        return None
    r = KeyReader(value, key)
    node = r.raw("node")  # checked with the rest by the Sensor
    direction = r.string("direction")
    spelled = direction if direction.startswith(("+", "-")) else f"+{direction}"
    if spelled.upper() not in UFF_DIRECTIONS:
        raise ScenarioError(f"{r.key('direction')}: must be one of {', '.join(UFF_DIRECTIONS)}, got {direction!r}")
    r.finish()
    return node, spelled.upper()


def read_sensors(top: KeyReader, data: Mapping[str, Any], section: str = "sensors",
                 others: Sequence[Sensor] = ()) -> tuple[Sensor, ...]:
    """The ``[[sensors]]`` blocks of a file, their names unique (also against ``others``, the sensors a
    calibration file adds to its scenario's)."""
    top.used.add(section)
    sensors = tuple(sensor_from_dict(item, f"{section}[{i}]") for i, item in enumerate(table_of_tables(data, section)))
    taken = {s.name for s in others}
    for i, s in enumerate(sensors):
        if s.name in taken or s.name in {o.name for o in sensors[:i]}:
            where = "the scenario's [[sensors]]" if s.name in taken else f"{section} above"
            raise ScenarioError(f"{section}[{i}].name: '{s.name}' is used twice (also in {where})")
    return sensors
