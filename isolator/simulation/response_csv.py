"""A run's samples as CSV (:meth:`isolator.Response.to_csv`) and its summary as JSON-ready types
(:meth:`isolator.Response.to_dict`)."""

from __future__ import annotations

import csv
import math
from pathlib import Path
from typing import Any

import numpy as np

from isolator.scenario.definitions import SIGNALS
from isolator.scenario.output_files import atomic_output
from isolator.scenario.readable import clean_time

__all__ = ["response_dict", "write_response_csv"]


def write_response_csv(response: Any, path: str | Path) -> Path:
    """Write a :class:`~isolator.simulation.response.Response`'s samples to ``path``:
    ``t,x,y,z,rx,ry,rz,q:<carriage>...`` [s, m, rad], ``<point>:x,:y,:z`` per point [m] (a bending top's
    ``:ex,:ey,:ez`` after them), ``s:<sensor>`` per sensor (its SI quantity), ``f:<actuator>`` [N] when
    actuators applied forces, then a pneumatic run's ``p:<isolator>`` [Pa] and ``h:<group>`` [m] columns;
    returns the path."""
    path = Path(path)
    r = response
    header = ["t", *SIGNALS, *[f"q:{n}" for n in r.carriage_names]]
    columns = [r.t, r.signals.T, r.q.T]
    if r.point_names:
        header += [f"{n}:{a}" for n in r.point_names for a in "xyz"]
        columns.append(r.point_signals.reshape(-1, r.t.size).T)
        if r.point_set.elastic_columns:  # a top that bends: <point>:ex, :ey, :ez
            header += list(r.point_set.elastic_columns)
            columns.append(r.point_set.elastic(r.states).reshape(-1, r.t.size).T)
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
    with atomic_output(path, newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        for row in data:
            writer.writerow([f"{v:.10g}" for v in row])
    return path


def response_dict(response: Any) -> dict[str, Any]:
    """A :class:`~isolator.simulation.response.Response`'s summary as plain JSON-ready types (the ``isolator
    simulate --json`` object)."""

    def num(v: float | None) -> float | None:  # full precision: JSON is read back (--band-json)
        return None if v is None or not math.isfinite(v) else float(v)

    return {
        "name": response.name,
        "model": response.model,
        "move_start": num(clean_time(response.move_start)),  # as the inputs give them (not 7.8999999999999995)
        "stop_time": num(clean_time(response.stop_time)),
        "move_time": num(clean_time(response.stop_time - response.move_start)),
        "signals": list(SIGNALS),
        "peak": {k: num(v) for k, v in response.peak.items()},
        "final": {k: (None if response.final is None else float(response.final[i])) for i, k in enumerate(SIGNALS)},
        "settling_time": {k: num(v) for k, v in response.settling_time.items()},
        "settling_time_max": num(response.settling_time_max),
        "notes": {k: r.reason for k, r in response.settling.items() if r.reason},
        "band": response.band.to_dict(),
        "point_peak": {n: {a: num(float(np.max(np.abs(response.point_signals[i, j])))) for j, a in enumerate("xyz")}
                       for i, n in enumerate(response.point_names)},
        **_deflection(response),
        **({} if response.windows is None else response.windows.to_dict()),
        **({} if response.pneumatic is None else response.pneumatic.to_dict()),
    }


def _deflection(response: Any) -> dict[str, Any]:
    """``deflection_at_rest`` on a bending top: each point's elastic translation at the initial equilibrium."""
    points = response.point_set
    if points is None or points.rest is None:
        return {}
    return {"deflection_at_rest": {n: [float(v) for v in points.rest[i]] for i, n in enumerate(points.names)}}
