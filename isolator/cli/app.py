"""The ``isolator`` command: a dispatcher over the subcommands each package registers.

The plant's own subcommands come from :mod:`isolator.cli.commands`; every other package adds its
subcommands through the entry-point group ``isolator.commands`` (``pyproject.toml``): each entry point is
a ``register(subparsers)`` function that adds parsers with a ``handler``. So the plant never imports the
packages above it, and a new package adds commands without touching this one.

Every error a user can cause (bad scenario or option, unstable table, diverging run) is printed as one
line, ``isolator: error: ...``, with exit status 2.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from importlib.metadata import entry_points, version

from isolator.cli import commands
from isolator.errors import IsolatorError

__all__ = ["ENTRY_POINT_GROUP", "build_parser", "main"]

#: the entry-point group other packages register their subcommands in
ENTRY_POINT_GROUP = "isolator.commands"


def build_parser() -> argparse.ArgumentParser:
    """The ``isolator`` parser with the plant's subcommands and every registered package's."""
    parser = argparse.ArgumentParser(
        prog="isolator",
        description="Pneumatic isolation tables carrying moving stages: transients, settling, "
        "modes, transmissibility, stability and vibration criteria.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {version('isolator')}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    commands.register(sub)
    for entry in sorted(entry_points(group=ENTRY_POINT_GROUP), key=lambda e: e.name):
        entry.load()(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``isolator`` command; returns the exit status."""
    args = build_parser().parse_args(argv)
    try:
        return int(args.handler(args))
    except IsolatorError as exc:
        print(f"isolator: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into a command that stopped reading
        sys.stderr.close()
        return 0
    except KeyboardInterrupt:
        print("isolator: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
