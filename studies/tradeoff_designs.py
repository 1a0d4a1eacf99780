"""The trade-off study's ``designs.csv``: every design's numbers, with the band its settling time is measured in."""

from __future__ import annotations

import csv
from typing import Any

import numpy as np

from .reporting import band_cell

__all__ = ["write_designs_csv"]


def _status(study: Any, i: int, j: int) -> str:
    if not study.stable[i]:
        return "tips"
    if (i, j) in study.failures:
        return "diverged"
    return "ok" if np.isfinite(study.settling_time[i, j]) else "no settling time"


def write_designs_csv(study: Any) -> None:
    """``designs.csv`` of a :class:`studies.tradeoff.TradeoffStudy`: one row per design."""
    with open(study.folder / "designs.csv", "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["stiffness_scale", "damping_scale", "settling_time_max_s", "band",
                         f"transmissibility_at_{study.reference_hz:g}_hz", "peak_transmissibility",
                         "peak_frequency_hz", "status"])
        for i, ks in enumerate(study.stiffness):
            for j, cs in enumerate(study.damping):
                writer.writerow([f"{ks:.6g}", f"{cs:.6g}", f"{study.settling_time[i, j]:.6g}",
                                 band_cell(study.band, study.half_widths[i, j]),
                                 f"{study.transmissibility[i, j]:.6g}", f"{study.peak[i, j]:.6g}",
                                 f"{study.peak_hz[i, j]:.6g}", _status(study, i, j)])
