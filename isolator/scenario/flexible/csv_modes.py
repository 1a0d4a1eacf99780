"""A modal file in the contract's CSV: ``mode,frequency_hz,damping,x,y,z,ux,uy,uz`` (and ``rx,ry,rz``), one row per
mode and node, every mode with the same nodes in the same order, ``damping`` empty where not given."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from isolator.errors import ScenarioError
from isolator.scenario.flexible.raw import RawModes
from isolator.scenario.tables import LINE, read_csv_columns

__all__ = ["COLUMNS", "read_csv_modes"]

#: the columns of a modal CSV file: required, then optional
COLUMNS = (("mode", "frequency_hz", "x", "y", "z", "ux", "uy", "uz"), ("damping", "rx", "ry", "rz"))


def read_csv_modes(path: Path, key: str, where: str) -> RawModes:
    """The modes of a CSV modal file; every problem one :class:`ScenarioError` starting with ``where`` (the key
    and the file) and naming the line."""
    columns = read_csv_columns(path, key, COLUMNS[0], COLUMNS[1], min_rows=1, blank=("damping",), lines=True)
    line = columns[LINE]
    turning = sorted({"rx", "ry", "rz"} & set(columns))
    if turning and len(turning) < 3:
        raise ScenarioError(f"{where}: gives the rotations {', '.join(turning)} but not all of rx, ry, rz")
    mode = columns["mode"]
    whole = np.flatnonzero(mode != np.round(mode))
    if whole.size:
        raise ScenarioError(f"{where} line {line[whole[0]]}: mode {mode[whole[0]]:g} is not a whole number")
    starts = np.flatnonzero(np.r_[True, mode[1:] != mode[:-1]])
    seen: dict[float, int] = {}
    for s in starts:
        if mode[s] in seen:
            raise ScenarioError(f"{where} line {line[s]}: mode {mode[s]:g} again (first on line {seen[mode[s]]}); "
                                "each mode's rows come together, one per node")
        seen[mode[s]] = int(line[s])
    nodes_n = int(np.r_[starts, mode.size][1] - starts[0])
    for k, s in enumerate(starts):
        size = int((starts[k + 1] if k + 1 < starts.size else mode.size) - s)
        if size != nodes_n:
            raise ScenarioError(f"{where} line {line[s]}: mode {mode[s]:g} has {size} rows, mode {mode[0]:g} has "
                                f"{nodes_n} (every mode lists the same nodes in the same order)")
    shaped = {name: v.reshape(starts.size, nodes_n) for name, v in columns.items()}
    lines = shaped[LINE]
    xyz = np.stack([shaped[c] for c in "xyz"], axis=-1)
    scale = 1e-9 * (1.0 + float(np.abs(xyz[0]).max()))
    bad = np.argwhere(np.abs(xyz - xyz[0]).max(axis=-1) > scale)
    if bad.size:
        m, j = bad[0]
        shown = ", ".join(f"{v:.6g}" for v in xyz[m, j])
        first = ", ".join(f"{v:.6g}" for v in xyz[0, j])
        raise ScenarioError(f"{where} line {lines[m, j]}: node {j + 1} of mode {shaped['mode'][m, 0]:g} lies at "
                            f"({shown}) m, on line {lines[0, j]} (mode {shaped['mode'][0, 0]:g}) at ({first}) m "
                            "(every mode lists the same nodes in the same order)")
    for name, what in (("frequency_hz", "frequency"), ("damping", "damping")):
        if name not in shaped:
            continue
        values = shaped[name]
        differs = ~((values == values[:, :1]) | (np.isnan(values) & np.isnan(values[:, :1])))
        if differs.any():
            m, j = np.argwhere(differs)[0]
            raise ScenarioError(f"{where} line {lines[m, j]}: mode {shaped['mode'][m, 0]:g} has {name} "
                                f"{values[m, j]:g}, on line {lines[m, 0]} {values[m, 0]:g} (one {what} per mode)")
    rotations = np.stack([shaped[c] for c in ("rx", "ry", "rz")], axis=-1) if turning else None
    return RawModes(
        frequencies=shaped["frequency_hz"][:, 0].copy(),
        damping=shaped["damping"][:, 0].copy() if "damping" in shaped else np.full(starts.size, np.nan),
        nodes=xyz[0].copy(),
        translations=np.stack([shaped[c] for c in ("ux", "uy", "uz")], axis=-1),
        rotations=rotations,
        mode_names=[f"mode {shaped['mode'][m, 0]:g} (line {lines[m, 0]})" for m in range(starts.size)],
        node_names=[f"node {j + 1} (line {lines[0, j]})" for j in range(nodes_n)],
    )
