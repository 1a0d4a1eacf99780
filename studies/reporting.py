"""What the studies share in writing their reports: the output folder, progress lines, numbers,
units and Markdown tables, and ``report.md`` itself."""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import numpy as np

from isolator import SIGNALS, Band
from isolator.scenario.arguments import check_public
from isolator.scenario.output_files import write_output_text

__all__ = [
    "band_cell",
    "band_lines",
    "design_band",
    "fmt",
    "largest",
    "micro_unit",
    "output_folder",
    "progress_printer",
    "table_header",
    "table_row",
    "write_json",
    "write_report",
]


def output_folder(out: str | Path) -> Path:
    """The study's output folder, created (with its parents) if need be."""
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    return folder


def progress_printer(enabled: bool = True, prefix: str = "") -> Callable[[str], None]:
    """A function printing ``prefix + text`` on stderr at once (progress, apart from results), or nothing when
    not ``enabled``."""

    def say(text: str) -> None:
        if enabled:
            print(f"{prefix}{text}", file=sys.stderr, flush=True)

    return say


def fmt(value: float | None, spec: str = ".3g", suffix: str = "") -> str:
    """``value`` formatted by ``spec`` with ``suffix``, or ``n/a`` for None or NaN."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "n/a"
    return f"{value:{spec}}{suffix}"


def largest(values: Iterable[float | None]) -> float | None:
    """The largest value, or None when any is None (a signal that never settles)."""
    known: list[float] = []
    for value in values:
        if value is None:
            return None
        known.append(value)
    return max(known)


def micro_unit(signal: str) -> tuple[float, str]:
    """Scale and unit a table signal is reported in: micrometres or microradians."""
    if signal not in SIGNALS:
        raise ValueError(f"signal: must be one of {', '.join(SIGNALS)}, got '{signal}'")
    return 1e6, "µrad" if signal.startswith("r") else "µm"


def table_row(cells: Iterable[object]) -> str:
    """One row of a Markdown table."""
    return "| " + " | ".join(str(c) for c in cells) + " |"


def table_header(columns: Iterable[object]) -> list[str]:
    """A Markdown table's header row and its separator."""
    names = list(columns)
    return [table_row(names), "|" + "---|" * len(names)]


def write_report(folder: Path, lines: Iterable[str], name: str = "report.md") -> Path:
    """Write the lines, one per line, to ``folder / name``; return its path."""
    path = folder / name
    write_output_text(path, "\n".join(lines) + "\n")
    return path


def write_json(folder: Path, data: Any, name: str = "results.json") -> Path:
    """Write ``data`` as indented JSON to ``folder / name``; return its path."""
    path = folder / name
    write_output_text(path, json.dumps(_plain(data), indent=2, allow_nan=False) + "\n")
    return path


def _plain(value: Any) -> Any:
    """JSON types: NaN and infinities become null, numpy numbers floats."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if isinstance(value, bool) or value is None or isinstance(value, str | int):
        return value
    number = float(value)
    return number if math.isfinite(number) else None


def band_lines(band: Band, why: str, scenario: str = "SCENARIO") -> list[str]:
    """The report's statement of a (resolved) settling band: how it was chosen and why, its six
    half-widths, and the command that reproduces a settling time in it."""
    widths = ", ".join(f"{k} {v * 1e6:.4g} {micro_unit(k)[1]}" for k, v in band.widths.items())
    return [
        f"Settling band: {band.how()}: ±({widths}). {why}",
        f"Reproduce a settling time in this band: `isolator simulate {scenario} --band {band.option()}`.",
    ]


def design_band(rule: Band, half_widths: np.ndarray) -> Band | None:
    """The band ``rule`` resolved to one design's six half-widths [m, rad] (None: NaN, no run)."""
    if not np.all(np.isfinite(half_widths)):
        return None
    return Band(rule.kind, rule.fraction, rule.baseline, tuple(float(v) for v in half_widths))


def band_cell(rule: Band, half_widths: np.ndarray) -> str:
    """A design's band as ``isolator simulate --band`` takes it (``x=...,rz=...``, m and rad), or ""."""
    band = design_band(rule, half_widths)
    return "" if band is None else band.option()


check_public(globals())
