"""A discrete controller from sensors to actuators as C99 code (:func:`write_c`), and from python-control.

The contract is ``docs/scenario-format.md``, section "Sensors in the scenario, output feedback and
exported controllers"; what the controller computes, and how a schedule interpolates, is
:mod:`isolator.simulation.discrete_controller`.

:meth:`DiscreteController.step` is the reference the generated C equals (to rounding). Names enter the C
only as string literals (and comments showing those literals), escaped by
:func:`isolator.numerics.rendering.escape_name`: every byte outside letters, digits, space and
``-_.:,;+=()[]<>{}!#$%&'@^|~`` is written as a three-digit octal escape, so ``*/``, ``/*``, quotes,
backslashes, ``??`` trigraphs, newlines and non-ASCII names cannot end a comment or a literal, and the
literal holds the name's UTF-8 bytes exactly. The C comes from template files (``templates/``) rendered by
:func:`isolator.numerics.rendering.render`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import control
import numpy as np

from isolator.analysis.sampling import check_sample_rate
from isolator.errors import ParameterError
from isolator.numerics.rendering import escape_name, render
from isolator.scenario.arguments import check_public
from isolator.scenario.output_files import write_output_text
from isolator.simulation.discrete_controller import DiscreteController, ScheduleEntry

__all__ = ["DiscreteController", "ScheduleEntry", "c_sources", "from_statespace", "write_c"]

_MATRICES = ("A", "B", "C", "D")


def c_literal(name: str) -> str:
    """``name`` as a C string literal holding its UTF-8 bytes; safe inside a comment as well."""
    return escape_name(name, "c")


def write_c(controller: DiscreteController, folder: str | Path) -> tuple[Path, Path]:
    """Write ``controller.h`` and ``controller.c`` of ``controller`` into ``folder`` (created).

    Both are rendered from the templates ``templates/controller.h.j2`` and ``templates/controller.c.j2``
    shipped with this package.

    Parameters
    ----------
    controller : DiscreteController
        The controller.
    folder : str or Path
        The folder to write into (created if missing).

    Returns
    -------
    header, source : Path
        The two files written, ``controller.h`` and ``controller.c``.
    """
    if not isinstance(controller, DiscreteController):
        raise ParameterError(f"controller: must be a DiscreteController, got {type(controller).__name__}")
    out = Path(folder)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ParameterError(f"folder: cannot make '{out}' ({exc.strerror or type(exc).__name__})") from None
    header, source = out / "controller.h", out / "controller.c"
    texts = c_sources(controller)
    write_output_text(header, texts["controller.h"])
    write_output_text(source, texts["controller.c"])
    return header, source


def c_sources(controller: DiscreteController) -> dict[str, str]:
    """The texts of ``controller.h`` and ``controller.c`` by file name (what :func:`write_c` writes)."""
    return {"controller.h": render(__package__, "templates/controller.h.j2", ctrl=controller),
            "controller.c": render(__package__, "templates/controller.c.j2", **_source_values(controller))}


def _source_values(ctrl: DiscreteController) -> dict[str, Any]:
    """What ``controller.c.j2`` needs besides the controller: its design points' matrices row by row (those
    without values left out) and the scheduling carriage's positions at the points."""
    points = ctrl.schedule or (ScheduleEntry((), ctrl.A, ctrl.B, ctrl.C, ctrl.D),)  # type: ignore[arg-type]
    matrices = {k.lower(): [float(v) for e in points for v in np.asarray(getattr(e, k)).ravel()] for k in _MATRICES}
    c = ctrl.schedule_carriage
    q = [float(e.q[c]) for e in points] if len(points) > 1 else []
    return {"ctrl": ctrl, "points": len(points), "matrices": {k: v for k, v in matrices.items() if v}, "q": q,
            "carriage": c}


def from_statespace(system: control.StateSpace, sample_rate: float, sensors: Sequence[str],
                    actuators: Sequence[str], carriages: Sequence[str] = (), method: str = "custom",
                    discretisation: str = "tustin", settings: Mapping[str, Any] | None = None,
                    delay: bool = False) -> DiscreteController:
    """A python-control design from the sensors to the actuators as a :class:`DiscreteController`.

    Parameters
    ----------
    system : control.StateSpace
        Inputs: the sensors' readings (SI); outputs: the actuators' commands [N]. Continuous (``dt`` 0)
        systems are discretised by ``control.c2d`` at ``1 / sample_rate`` s; a discrete one must have
        that sampling time (or ``dt=True``: unspecified) and is taken as it is.
    sample_rate : float
        [Hz].
    discretisation : str
        ``"tustin"`` (bilinear; keeps stability, warps frequencies near Nyquist) or ``"zoh"`` (exact for
        inputs held over each sample).
    settings, delay, method, carriages
        Recorded in the controller (see :class:`DiscreteController`).
    sensors : sequence of str
        The sensors' names, the system's inputs in order (the scenario's ``[[sensors]]``).
    actuators : sequence of str
        The actuators' names, its outputs in order (the scenario's ``[[actuators]]``).

    Returns
    -------
    DiscreteController
        The controller as data, which :func:`write_c` writes and the simulation runs.

    Examples
    --------
    >>> import control
    >>> import numpy as np
    >>> from controllers.feedback import from_statespace
    >>> gain = control.ss([], [], [], -2.0e4 * np.eye(2))     # u = -c v, c = 2e4 N s/m
    >>> ctrl = from_statespace(gain, 1000.0, ["v1", "v2"], ["f1", "f2"])
    >>> x, u = ctrl.step(ctrl.reset(), np.array([1e-6, 0.0]))  # 1 um/s on the first sensor
    >>> u.tolist()
    [-0.02, 0.0]
    """
    if not isinstance(system, control.StateSpace):
        raise ParameterError(f"system: must be a control.StateSpace, got {type(system).__name__}")
    check_sample_rate(sample_rate)
    if discretisation not in ("tustin", "zoh"):
        raise ParameterError(f"discretisation: must be 'tustin' or 'zoh', got {discretisation!r}")
    if (system.ninputs, system.noutputs) != (len(sensors), len(actuators)):
        raise ParameterError(f"system: must have {len(sensors)} inputs (sensors) and {len(actuators)} outputs "
                             f"(actuators), got {system.ninputs} and {system.noutputs}")
    dt = system.dt
    if dt is None or dt is False or dt == 0:
        system = control.c2d(system, 1.0 / sample_rate, method=discretisation)
    elif dt is not True and not math.isclose(float(dt), 1.0 / sample_rate, rel_tol=1e-9):
        raise ParameterError(f"system: sampled every {dt} s, not at the sample rate {sample_rate} Hz")
    return DiscreteController(sample_rate, sensors, actuators, carriages, method, system.A, system.B, system.C,
                              system.D, settings={"discretisation": discretisation, **(settings or {})}, delay=delay)


check_public(globals())
