"""The ``isolator`` command: a dispatcher over the subcommands each package registers.

The plant's own subcommands come from :mod:`isolator.cli.commands`; every other package adds its
subcommands through the entry-point group ``isolator.commands`` (``pyproject.toml``): each entry point is
a ``register(subparsers)`` function that adds parsers with a ``handler``. So the plant never imports the
packages above it, and a new package adds commands without touching this one.

Every error a user can cause (bad scenario or option, unstable table, diverging run) is printed as one
line, ``isolator: error: ...``, with exit status 2 (``isolator stability`` exits with 3 for a table that
would tip; an interrupt with 130). Bad options and arguments too: one line naming the option and the
subcommand's ``--help``. What numpy warns about during a command is summed up in one line after a result,
and left out after an error; a machine out of memory or a numerical failure the toolkit did not foresee
is one error line as well, never a traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import signal
import sys
import threading
import warnings
from collections.abc import Iterator, Sequence
from importlib.metadata import entry_points, version
from typing import NoReturn

import numpy as np

from isolator.cli import commands, fmu_command, sweep_command
from isolator.cli.helpers import MADE_FOLDERS, OUTPUT_OPTIONS, command_words, output_failure, remove_made_folders
from isolator.errors import IsolatorError
from isolator.scenario.names import escaped

__all__ = ["ENTRY_POINT_GROUP", "build_parser", "main"]

#: the entry-point group other packages register their subcommands in
ENTRY_POINT_GROUP = "isolator.commands"


class _Parser(argparse.ArgumentParser):
    """A parser whose errors are one line naming the subcommand's help (its subparsers are of this class)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"isolator: error: {escaped(message)} (see '{self.prog} --help')\n")


def build_parser() -> argparse.ArgumentParser:
    """The ``isolator`` parser with the plant's subcommands and every registered package's."""
    parser = _Parser(
        prog="isolator",
        description="Pneumatic isolation tables carrying moving stages: transients, settling, "
        "modes, transmissibility, stability and vibration criteria.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {version('isolator')}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    commands.register(sub)
    sweep_command.register(sub)
    fmu_command.register(sub)
    for entry in sorted(entry_points(group=ENTRY_POINT_GROUP), key=lambda e: e.name):
        entry.load()(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``isolator`` command; returns the exit status."""
    parser = build_parser()
    args, extra = parser.parse_known_args(argv)
    args.argv = list(sys.argv[1:] if argv is None else argv)  # the command as typed (e.g. to name its --resume)
    if extra:  # an option of another subcommand (or none): name the subcommand whose help lists the real ones
        prog = " ".join(["isolator", args.command, *([args.study] if getattr(args, "study", None) else [])])
        parser.exit(2, f"isolator: error: unrecognized arguments for '{prog}': {escaped(' '.join(extra))} "
                    f"(see '{prog} --help')\n")
    MADE_FOLDERS.clear()
    OUTPUT_OPTIONS.clear()
    with warnings.catch_warnings(record=True) as caught, _terminated_as_interrupted():  # the filters as they
        warnings.simplefilter("always", RuntimeWarning)  # are (deprecations stay hidden)
        status = _run(args)
    if status not in (0, 3):  # a refused command leaves no folder behind it made for its outputs
        remove_made_folders()
    MADE_FOLDERS.clear()
    if status in (0, 3):
        _summarise(caught)
    return status


def _run(args: argparse.Namespace) -> int:
    try:
        return int(args.handler(args))
    except IsolatorError as exc:
        return _error(command_words(str(exc)))  # 'isolator sweep SCENARIO --list', not a Python name
    except MemoryError as exc:
        return _error(f"out of memory ({exc or 'an allocation failed'}): the inputs ask for more than this "
                      "machine has (a very long run, a high sample rate, or a design so stiff that the "
                      "integrator needs very many steps)")
    except (ArithmeticError, np.linalg.LinAlgError, RecursionError) as exc:
        return _error(f"numerical failure ({type(exc).__name__}: {exc}); the inputs' magnitudes are likely "
                      "extreme (masses, stiffness, damping many orders of magnitude apart)")
    except BrokenPipeError:  # output piped into a command that stopped reading
        sys.stderr.close()
        return 0
    except OSError as exc:  # writing an output (the paths were checked before any work)
        return _error(output_failure(exc))
    except Terminated:
        print("isolator: terminated", file=sys.stderr)
        return 128 + signal.SIGTERM
    except KeyboardInterrupt:
        print("isolator: interrupted", file=sys.stderr)
        return 130


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the command is, so that it ends as an interrupt (Ctrl-C) does: a sweep stops its
    workers and keeps its rows."""


@contextlib.contextmanager
def _terminated_as_interrupted() -> Iterator[None]:
    """SIGTERM raises :class:`Terminated` while a command runs (in the main thread only: signals go there)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def raise_terminated(signum: int, frame: object) -> None:
        raise Terminated

    before = signal.signal(signal.SIGTERM, raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, before)


def _error(message: str) -> int:
    print(f"isolator: error: {escaped(message)}", file=sys.stderr)  # what an input put there cannot drive the terminal
    return 2


def _summarise(caught: list[warnings.WarningMessage]) -> None:
    """One line per distinct warning; numpy's floating-point warnings summed up in one line."""
    numeric = [w for w in caught if issubclass(w.category, RuntimeWarning) and "encountered" in str(w.message)]
    for text in dict.fromkeys(escaped(w.message) for w in caught if w not in numeric):
        print(f"isolator: warning: {text}", file=sys.stderr)
    if numeric:
        first = escaped(numeric[0].message)
        print(f"isolator: warning: numpy warned {len(numeric)} time(s) ('{first}'): some inputs are of extreme "
              "magnitude; check the results", file=sys.stderr)


if __name__ == "__main__":
    sys.exit(main())
