"""Names as python-control takes them, and back: a ``.`` in a name is legal in a scenario, not in python-control.

python-control reads ``sys.signal`` as a subsystem's signal, so it refuses a ``.`` in a system or signal name
(``invalid signal name``). The name rule (:func:`isolator.scenario.names.check_name`) allows it
(``probe.1``, ``act.x``), so every name goes to python-control through :func:`to_control` (each ``.`` as
:data:`DOT`, a character no name may hold: it is not printable) and every label read back goes through
:func:`from_control` before anyone sees or compares it. Only these two functions know the mapping.
"""

from __future__ import annotations

from collections.abc import Iterable

__all__ = ["DOT", "from_control", "labels", "signals", "to_control"]

#: what a ``.`` is in python-control's names: a private-use character, which no name holds (not printable)
DOT = "\ue000"


def to_control(name: str) -> str:
    """``name`` as python-control takes it (each ``.`` as :data:`DOT`).

    Examples
    --------
    >>> from_control(to_control("s:probe.1")) == "s:probe.1"
    True
    >>> "." in to_control("s:probe.1")
    False
    """
    return name.replace(".", DOT)


def from_control(label: str) -> str:
    """A python-control label as the name it came from (:func:`to_control` undone)."""
    return label.replace(DOT, ".")


def labels(names: Iterable[str]) -> list[str]:
    """:func:`from_control` of each python-control label (a system's ``input_labels``, ``output_labels``)."""
    return [from_control(n) for n in names]


def signals(names: Iterable[str]) -> list[str]:
    """:func:`to_control` of each name."""
    return [to_control(n) for n in names]
