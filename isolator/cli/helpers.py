"""What the command-line modules of every package share: the scenario argument, reports, figures."""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from isolator.scenario.reader import DEFAULT_SCENARIO

__all__ = ["Handler", "report", "save_figure", "scenario_argument", "use_agg"]

#: a subcommand's handler: the parsed arguments in, the exit status out
Handler = Callable[[argparse.Namespace], int]


def scenario_argument(parser: argparse.ArgumentParser, help_text: str | None = None) -> None:
    """The optional positional ``scenario`` (a file or a bundled name)."""
    parser.add_argument("scenario", nargs="?", default=None,
                        help=help_text or f"scenario file or bundled name (default: {DEFAULT_SCENARIO})")


def use_agg() -> None:
    """Draw figures without a display (files only)."""
    import matplotlib

    matplotlib.use("Agg")


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
