"""A modal file (CSV or UFF) read into :class:`ModalData`: the frequencies checked, the six rigid modes fitted,
the elastic modes chosen by ``count`` and ``max_frequency``, the nodes moved to the table frame."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from isolator.errors import ScenarioError
from isolator.scenario.flexible.csv_modes import read_csv_modes
from isolator.scenario.flexible.definitions import ModalData
from isolator.scenario.flexible.raw import RawModes
from isolator.scenario.flexible.rigid_check import FIT_TOLERANCE, RIGID_LIMIT, RigidCheck, fit_rigid, rigid_properties
from isolator.scenario.flexible.uff_modes import UFF_SUFFIXES, read_uff_modes
from isolator.scenario.names import escaped

__all__ = ["load_modal_data"]


def load_modal_data(
    path: str | Path,
    *,
    thickness: float | None = None,
    count: int | None = None,
    max_frequency: float | None = None,
    damping: float = 0.01,
    origin: Sequence[float] = (0.0, 0.0, 0.0),
    key: str = "table.flexible.modes",
) -> ModalData:
    """Read and check a modal file of the top's free-free modes.

    Parameters
    ----------
    path : str or Path
        A CSV file (``.csv``) or a universal file (``.unv``, ``.uff``; needs ``pyuff``), as the contract in
        ``docs/scenario-format.md`` ("A top that bends") describes them.
    thickness : float, optional
        The top's thickness (``[table] size`` z) [m]; needed for a single layer of nodes, default the nodes'
        height span.
    count : int, optional
        Keep the lowest ``count`` elastic modes (default every one).
    max_frequency : float, optional
        Keep only elastic modes up to this frequency [Hz].
    damping : float
        The damping ratio of a mode the file gives none.
    origin : sequence of 3 float
        Where the file's origin lies in the table frame [m].
    key : str
        The key named first in errors.

    Returns
    -------
    ModalData
        The kept elastic modes (at or above 1 Hz), with ``rigid`` from the six rigid modes if the file has them.

    Raises
    ------
    ScenarioError
        One line naming the key, the file and the row, node or dataset: see the contract's list.
    """
    path = Path(path)
    where = f"{key}: '{escaped(path, 120)}'"
    suffix = path.suffix.lower()
    if suffix == ".csv":
        raw = read_csv_modes(path, key, where)
    elif suffix in UFF_SUFFIXES:
        raw = read_uff_modes(path, key, where)
    else:
        raise ScenarioError(f"{where}: must be a .csv or a universal file (.unv, .uff), got '{escaped(suffix, 20)}'")
    shift = np.asarray(origin, dtype=float)
    raw.nodes = raw.nodes + shift
    rigid, elastic = _split(raw, where)
    chosen = _choose(raw, elastic, where, key, count, max_frequency)
    given = raw.damping[chosen]
    bad = np.flatnonzero(np.isfinite(given) & ((given < 0) | (given >= 1)))
    if bad.size:
        raise ScenarioError(f"{where}: {raw.mode_names[chosen[bad[0]]]} has the damping ratio {given[bad[0]]:g} "
                            "(must be >= 0 and < 1)")
    span = float(np.ptp(raw.nodes[:, 2]))
    try:
        return ModalData(
            path=str(path),
            frequencies=raw.frequencies[chosen],
            damping=np.where(np.isfinite(given), given, damping),
            nodes=raw.nodes,
            translations=raw.translations[chosen],
            rotations=None if raw.rotations is None else raw.rotations[chosen],
            thickness=float(thickness) if thickness is not None else span if span > 0 else math.nan,
            rigid=rigid,
            labels=tuple(raw.node_names),
        )
    except ScenarioError as exc:  # the faces' checks, naming the file
        raise ScenarioError(f"{key}: {exc}") from None


def _split(raw: RawModes, where: str) -> tuple[RigidCheck | None, np.ndarray]:
    """The rigid modes' check (None without rigid modes) and the indices of the elastic modes."""
    f = raw.frequencies
    name = raw.mode_names
    bad = np.flatnonzero(~np.isfinite(f))
    if bad.size:
        raise ScenarioError(f"{where}: {name[bad[0]]} has the frequency {f[bad[0]]} (must be finite)")
    floor = np.maximum(f, RIGID_LIMIT)  # the rigid modes' order is numerical noise; they come first
    down = np.flatnonzero(floor[1:] < floor[:-1])
    if down.size:
        i = int(down[0]) + 1
        raise ScenarioError(f"{where}: {name[i]} has the frequency {f[i]:.6g} Hz, below {f[i - 1]:.6g} Hz of "
                            f"{name[i - 1]} before it (the modes must come in increasing frequency)")
    rigid = np.flatnonzero(f < RIGID_LIMIT)
    if rigid.size not in (0, 6):
        listed = ", ".join(name[i] for i in rigid[:7])
        raise ScenarioError(f"{where}: {rigid.size} modes below 1 Hz ({listed}); a free-free top has six rigid "
                            "modes (give all six, to be checked against [table], or none)")
    elastic = np.flatnonzero(f >= RIGID_LIMIT)
    if not rigid.size:
        return None, elastic
    rotations = None if raw.rotations is None else raw.rotations[rigid]
    v, w, residual = fit_rigid(raw.nodes, raw.translations[rigid], rotations)
    worst = int(np.argmax(residual))
    if residual[worst] > FIT_TOLERANCE:
        raise ScenarioError(f"{where}: {name[rigid[worst]]} ({f[rigid[worst]]:.3g} Hz) is no rigid motion of the "
                            f"top (u = v + w x p misses its translations by {residual[worst]:.1%}); a mode below "
                            "1 Hz must be one of the six rigid modes")
    try:
        return rigid_properties(v, w), elastic
    except ScenarioError as exc:
        raise ScenarioError(f"{where}: {exc}") from None


def _choose(raw: RawModes, elastic: np.ndarray, where: str, key: str, count: int | None,
            max_frequency: float | None) -> np.ndarray:
    """The indices of the kept elastic modes: the lowest ``count``, up to ``max_frequency``."""
    table = key.rpartition(".")[0] or "table.flexible"
    if not elastic.size:
        raise ScenarioError(f"{where}: has no elastic mode (every mode is below 1 Hz)")
    if count is not None and count > elastic.size:
        raise ScenarioError(f"{table}.count: {count} elastic modes asked, but {where} has {elastic.size} "
                            f"(from {raw.frequencies[elastic[0]]:.4g} to {raw.frequencies[elastic[-1]]:.4g} Hz)")
    chosen = elastic[:count] if count is not None else elastic
    if max_frequency is not None:
        chosen = chosen[raw.frequencies[chosen] <= max_frequency]
        if not chosen.size:
            raise ScenarioError(f"{table}.max_frequency: {max_frequency:g} Hz leaves no elastic mode of {where} "
                                f"(its lowest is {raw.frequencies[elastic[0]]:.4g} Hz)")
    return chosen
