"""Axes and units of the error budget's results and figures."""

from __future__ import annotations

__all__ = ["AXES", "QUANTITY_UNITS", "display_unit"]

#: the world axes of a point's motion
AXES = ("x", "y", "z")
#: SI unit of each quantity
QUANTITY_UNITS = {"displacement": "m", "velocity": "m/s", "acceleration": "m/s^2"}


def display_unit(quantity: str) -> tuple[float, str]:
    """The factor and unit figures and summaries show a quantity in: nm, µm/s, mm/s^2."""
    return {"displacement": (1e9, "nm"), "velocity": (1e6, "µm/s"), "acceleration": (1e3, "mm/s²")}[quantity]
