"""Modal files written: the contract's CSV and a universal file (datasets 164, 2411, 55 with pyuff), and
``[table.flexible]`` as TOML keys."""

from __future__ import annotations

import csv
import os
from pathlib import Path
from typing import Any

import numpy as np

from isolator.scenario.flexible.definitions import FlexibleTop
from isolator.scenario.flexible.uff_modes import pyuff_module

__all__ = ["flexible_toml", "write_modal_csv", "write_modal_uff"]


def _arrays(frequencies: Any, nodes: Any, translations: Any, rotations: Any, damping: Any
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None, np.ndarray]:
    f = np.asarray(frequencies, dtype=float).reshape(-1)
    p = np.asarray(nodes, dtype=float).reshape(-1, 3)
    u = np.asarray(translations, dtype=float).reshape(f.size, len(p), 3)
    r = None if rotations is None else np.asarray(rotations, dtype=float).reshape(f.size, len(p), 3)
    z = np.full(f.size, np.nan) if damping is None else np.asarray(damping, dtype=float).reshape(f.size)
    return f, p, u, r, z


def write_modal_csv(path: str | Path, frequencies: Any, nodes: Any, translations: Any, rotations: Any = None,
                    damping: Any = None) -> Path:
    """Write modes as the contract's CSV (``mode,frequency_hz,damping,x,y,z,ux,uy,uz[,rx,ry,rz]``).

    Parameters
    ----------
    path : str or Path
    frequencies : array_like, shape (M,)
        [Hz], ascending (rigid modes below 1 Hz first).
    nodes : array_like, shape (N, 3)
        [m]
    translations : array_like, shape (M, N, 3)
        Mass-normalised [m/sqrt(kg)].
    rotations : array_like, shape (M, N, 3), optional
        [rad/sqrt(kg)]
    damping : array_like, shape (M,), optional
        Damping ratios; NaN (or None for all): left empty.

    Returns
    -------
    Path
    """
    f, p, u, r, z = _arrays(frequencies, nodes, translations, rotations, damping)
    target = Path(path)
    with open(target, "w", newline="", encoding="utf-8") as handle:
        out = csv.writer(handle)
        out.writerow(["mode", "frequency_hz", "damping", "x", "y", "z", "ux", "uy", "uz"]
                     + ([] if r is None else ["rx", "ry", "rz"]))
        for m in range(f.size):
            zeta = "" if not np.isfinite(z[m]) else repr(float(z[m]))
            for j in range(len(p)):
                row = [m + 1, repr(float(f[m])), zeta, *(repr(float(v)) for v in p[j]),
                       *(repr(float(v)) for v in u[m, j])]
                out.writerow(row + ([] if r is None else [repr(float(v)) for v in r[m, j]]))
    return target


def write_modal_uff(path: str | Path, frequencies: Any, nodes: Any, translations: Any, rotations: Any = None,
                    damping: Any = None, *, length: float = 1.0, force: float = 1.0, modal_mass: Any = None) -> Path:
    """Write modes as a universal file: a dataset 164 (``length``, ``force``: file units per SI unit), the
    nodes as a dataset 2411, one dataset 55 per mode (normal modes; 6 values per node with ``rotations``).

    The values are converted from SI to the file's units; ``modal_mass`` (M,) (in the file's mass unit)
    writes each shape scaled by ``sqrt(modal mass)`` with that modal mass. Damping NaN or None is written
    as 0. Needs ``pyuff``.

    Returns
    -------
    Path
    """
    pyuff = pyuff_module(str(path))
    f, p, u, r, z = _arrays(frequencies, nodes, translations, rotations, damping)
    mass_unit = length / force  # kg per file mass unit
    masses = np.zeros(f.size) if modal_mass is None else np.asarray(modal_mass, dtype=float).reshape(f.size)
    labels = np.arange(1, len(p) + 1)
    target = Path(path)
    if target.exists():
        os.remove(target)
    sets = [pyuff.prepare_164(units_code=9, units_description="isolator", temp_mode=1, length=float(length),
                              force=float(force), temp=1.0, temp_offset=0.0),
            pyuff.prepare_2411(node_nums=labels, def_cs=np.zeros(len(p), int), disp_cs=np.zeros(len(p), int),
                               color=np.ones(len(p), int), x=p[:, 0] * length, y=p[:, 1] * length,
                               z=p[:, 2] * length)]
    for m in range(f.size):
        scale = np.sqrt(mass_unit) * (np.sqrt(masses[m]) if masses[m] > 0 else 1.0)
        values = {f"r{k + 1}": u[m, :, k] * length * scale for k in range(3)}
        if r is not None:
            values.update({f"r{k + 4}": r[m, :, k] * scale for k in range(3)})
        sets.append(pyuff.prepare_55(
            model_type=1, analysis_type=2, data_ch=3 if r is not None else 2, spec_data_type=8, data_type=2,
            n_data_per_node=6 if r is not None else 3, node_nums=labels, load_case=1, mode_n=m + 1,
            freq=float(f[m]), modal_m=float(masses[m]), modal_damp_vis=float(np.nan_to_num(z[m])),
            modal_damp_his=0.0, **values))
    pyuff.UFF(str(target)).write_sets(sets, mode="overwrite")
    return target


def flexible_toml(top: FlexibleTop, folder: str | Path | None = None) -> dict[str, Any]:
    """``[table.flexible]`` as TOML keys for a scenario file written to ``folder``: ``modes`` relative to it when
    the file lies under it, else absolute (a relative ``modes`` is taken from the current folder, as
    :func:`~isolator.scenario.flexible.load_flexible` reads it with its default ``base_dir``)."""
    source = Path(top.data.path).resolve()
    modes = str(source)
    if folder is not None:
        try:
            modes = source.relative_to(Path(folder).resolve()).as_posix()
        except ValueError:
            modes = str(source)
    keys: dict[str, Any] = {"modes": modes}
    if top.count is not None:
        keys["count"] = int(top.count)
    if top.max_frequency is not None:
        keys["max_frequency"] = float(top.max_frequency)
    keys["damping"] = float(top.damping)
    keys["origin"] = [float(v) for v in top.origin]
    return keys
