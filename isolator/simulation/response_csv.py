"""A run's samples as CSV (:meth:`isolator.Response.to_csv`)."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np

from isolator.scenario.definitions import SIGNALS

__all__ = ["write_response_csv"]


def write_response_csv(response: Any, path: str | Path) -> Path:
    """Write a :class:`~isolator.simulation.response.Response`'s samples to ``path``:
    ``t,x,y,z,rx,ry,rz,q:<carriage>...`` [s, m, rad], ``<point>:x,:y,:z`` per point [m], ``s:<sensor>``
    per sensor (its SI quantity), ``f:<actuator>`` [N] when actuators applied forces, then a pneumatic run's
    ``p:<isolator>`` [Pa] and ``h:<group>`` [m] columns, to ``path``; returns the path."""
    path = Path(path)
    r = response
    header = ["t", *SIGNALS, *[f"q:{n}" for n in r.carriage_names]]
    columns = [r.t, r.signals.T, r.q.T]
    if r.point_names:
        header += [f"{n}:{a}" for n in r.point_names for a in "xyz"]
        columns.append(r.point_signals.reshape(-1, r.t.size).T)
    if r.sensor_names:
        header += [f"s:{n}" for n in r.sensor_names]
        columns.append(r.sensor_signals.T)
    if r.actuator_forces.size and np.any(r.actuator_forces):
        header += [f"f:{n}" for n in r.actuator_names]
        columns.append(r.actuator_forces.T)
    if r.pneumatic is not None:
        extra = r.pneumatic.columns
        header += list(extra)
        columns.append(np.array(list(extra.values())).T)
    data = np.column_stack(columns)
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        for row in data:
            writer.writerow([f"{v:.10g}" for v in row])
    return path
