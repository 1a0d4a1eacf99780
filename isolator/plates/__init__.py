"""A starting point for a top that bends without a finite-element model of one: the free-free modes of a
homogeneous (or honeycomb) rectangular top, written as the scenario contract's modal CSV
(``isolator plate-modes``), and the figure of a top's mode shapes.

Needs scikit-fem for the modes (``pip install 'isolator[plate]'``); the figure takes plain arrays, so any
modal data (a finite-element code's file as the scenario reader holds it) can be drawn.

The bundled ``isolator/data/scenarios/paper-table-3-2-top-modes.csv`` (the paper's table 3.2 top, a granite
block taken as E = 50 GPa, nu = 0.25) is ``isolator plate-modes paper-table-3-2-top-modes.csv --size 2,1,0.3
--mass 4400 --young 50e9 --poisson 0.25 --model solid`` (a test regenerates it and compares).
"""

from isolator.plates.figure import plot_mode_shapes
from isolator.plates.modes import CSV_HEADER, PlateModes, check_plate_arguments, plate_modes, rigid_modes

__all__ = ["CSV_HEADER", "PlateModes", "check_plate_arguments", "plate_modes", "plot_mode_shapes", "rigid_modes"]
