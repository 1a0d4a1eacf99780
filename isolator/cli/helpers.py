"""What the command-line modules of every package share: the scenario argument, output paths checked
before any work, memory estimates, reports, figures."""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import unicodedata
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from isolator.errors import ParameterError
from isolator.scenario.reader import DEFAULT_SCENARIO
from isolator.simulation.resources import available_memory, check_memory, check_run_memory

if TYPE_CHECKING:
    pass

__all__ = [
    "Handler",
    "available_memory",
    "check_memory",
    "check_run_memory",
    "count",
    "default_output",
    "figure_path",
    "output_folder",
    "output_path",
    "report",
    "save_figure",
    "scenario_argument",
    "use_agg",
]

#: a subcommand's handler: the parsed arguments in, the exit status out
Handler = Callable[[argparse.Namespace], int]
#: the longest default file name (without its extension) made from a scenario's name
NAME_LENGTH = 100
#: how much of a path an error message quotes
QUOTED = 60


def default_output(name: str, suffix: str) -> Path:
    """A default output file in the working directory named after ``name`` (a scenario's): a slug of it
    (ASCII letters, digits, ``.``, ``_`` and ``-``; every other run of characters one ``-``; no leading dot),
    at most :data:`NAME_LENGTH` characters, ``scenario`` when nothing is left; then ``suffix``."""
    ascii_name = unicodedata.normalize("NFKD", str(name)).encode("ascii", "ignore").decode()
    slug = re.sub(r"[^A-Za-z0-9._-]+", "-", ascii_name).strip(".-")[:NAME_LENGTH].strip(".-")
    return Path((slug or "scenario") + suffix)


def _quoted(path: Path) -> str:
    """A path as an error message quotes it (long ones shortened)."""
    text = str(path)
    return text if len(text) <= QUOTED else f"{text[: QUOTED - 20]}...{text[-17:]}"


def scenario_argument(parser: argparse.ArgumentParser, help_text: str | None = None) -> None:
    """The optional positional ``scenario`` (a file or a bundled name)."""
    parser.add_argument("scenario", nargs="?", default=None,
                        help=help_text or f"scenario file or bundled name (default: {DEFAULT_SCENARIO})")


def count(text: str) -> int:
    """An argparse type: a whole number, also written as ``1e3``."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got '{text}'") from None
    if not math.isfinite(value) or value != int(value):
        raise argparse.ArgumentTypeError(f"expected a whole number, got '{text}'")
    return int(value)


def use_agg() -> None:
    """Draw figures without a display (files only)."""
    import matplotlib

    matplotlib.use("Agg")


def output_folder(path: Path, option: str) -> Path:
    """A folder to write into, made if missing; a :class:`ParameterError` naming ``option`` if it cannot be."""
    if path.exists() and not path.is_dir():
        raise ParameterError(f"{option}: '{path}' is a file, not a folder")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ParameterError(f"{option}: cannot make the folder '{path}' ({exc.strerror})") from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise ParameterError(f"{option}: cannot write into the folder '{path}' (permission denied)")
    return path


def output_path(path: Path, option: str, suffixes: Sequence[str]) -> Path:
    """A file to write, checked before any work: a known extension (case-insensitive), its folder made if
    missing, writable. Every problem is a :class:`ParameterError` naming ``option``."""
    if path.suffix.lower() not in suffixes:
        got = f"'{path.suffix}'" if path.suffix else "none"
        raise ParameterError(f"{option}: '{_quoted(path)}' has extension {got}; supported: {', '.join(suffixes)}")
    longest = max((len(os.fsencode(part)) for part in path.parts), default=0)
    if longest > 255:
        raise ParameterError(f"{option}: '{_quoted(path)}' has a name of {longest} bytes; file systems take at most "
                             "255")
    if path.is_dir():
        raise ParameterError(f"{option}: '{path}' is a folder, not a file")
    parent = path.parent
    for above in (parent, *parent.parents):  # the nearest existing ancestor must be a folder
        if above.exists():
            if not above.is_dir():
                raise ParameterError(f"{option}: cannot write '{path}': '{above}' is a file, not a folder")
            break
    output_folder(parent, option)
    if path.exists() and not os.access(path, os.W_OK):
        raise ParameterError(f"{option}: cannot write '{path}' (permission denied)")
    return path


def figure_path(path: Path | None, option: str) -> Path | None:
    """:func:`output_path` for a figure: an extension matplotlib writes."""
    if path is None:
        return None
    from matplotlib.figure import Figure

    formats = Figure().canvas.get_supported_filetypes()
    return output_path(path, option, tuple(f".{ext}" for ext in sorted(formats)))


def save_figure(fig: Any, path: Path) -> None:
    """Write a matplotlib figure at 120 dpi and close it."""
    import matplotlib.pyplot as plt

    fig.savefig(path, dpi=120)
    plt.close(fig)


def report(
    as_json: bool, data: dict[str, Any], text: str, files: Sequence[tuple[str, Path | None]], indent: int | None = 2
) -> int:
    """Print the JSON, or the text followed by a ``label: path`` line per file written; exit status 0."""
    if as_json:
        print(json.dumps(data, indent=indent))
        return 0
    print(text)
    for label, path in files:
        if path is not None:
            print(f"{label}: {path}")
    return 0
