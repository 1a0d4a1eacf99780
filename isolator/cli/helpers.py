"""What the command-line modules of every package share: the scenario argument, output paths checked
before any work, memory estimates, reports, figures."""

from __future__ import annotations

import argparse
import contextlib
import json
import logging
import math
import os
import re
import sys
import unicodedata
import warnings
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from isolator.errors import ParameterError
from isolator.scenario.names import escaped
from isolator.scenario.output_files import save_figure_file
from isolator.scenario.reader import DEFAULT_SCENARIO
from isolator.simulation.resources import available_memory, check_memory, check_run_memory

if TYPE_CHECKING:
    pass

__all__ = [
    "API_WORDS",
    "CLI_NAMES",
    "MADE_FOLDERS",
    "OUTPUT_OPTIONS",
    "Handler",
    "available_memory",
    "check_memory",
    "check_run_memory",
    "command_words",
    "count",
    "default_output",
    "figure_path",
    "output_failure",
    "output_folder",
    "output_path",
    "remove_made_folders",
    "report",
    "save_figure",
    "scenario_argument",
    "scheduler_arguments",
    "scheduler_client",
    "seed",
    "use_agg",
    "written",
]

#: a subcommand's handler: the parsed arguments in, the exit status out
Handler = Callable[[argparse.Namespace], int]
#: the longest default file name (without its extension) made from a scenario's name
NAME_LENGTH = 100
#: how much of a path an error message quotes
QUOTED = 60
#: the folders :func:`output_folder` made for the command running now, deepest first
MADE_FOLDERS: list[Path] = []
#: the option that named each output file of the command running now (:func:`output_path`), by path
OUTPUT_OPTIONS: dict[str, str] = {}


def remove_made_folders() -> None:
    """Remove the folders the failed command made (those still empty), deepest first; forget them all."""
    for folder in MADE_FOLDERS:
        with contextlib.suppress(OSError):
            folder.rmdir()  # only an empty one: nothing the command or anyone else wrote is removed
    MADE_FOLDERS.clear()


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


#: how the messages of :func:`isolator.sweep.cluster.connect` name the command's options
CLI_NAMES = {"scheduler": "--scheduler", "ca": "--tls-ca-file", "cert": "--tls-cert", "key": "--tls-key",
             "tls": "--tls-ca-file, --tls-cert, --tls-key"}


#: Python names the API's messages cite, and the command-line way to the same thing
API_WORDS = {"Simulator(...).layout.names": "'isolator sweep SCENARIO --list'",
             "Simulator.layout.names": "'isolator sweep SCENARIO --list'"}


def command_words(message: str) -> str:
    """An API message as a command-line user reads it: the Python names of :data:`API_WORDS` replaced."""
    for api, cli in API_WORDS.items():
        message = message.replace(api, cli)
    return message


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


def seed(text: str) -> int:
    """An argparse type: a random seed, a whole number from 0 to 2**32 - 1 (numpy's seeds are not negative)."""
    value = count(text)
    if not 0 <= value < 2**32:
        raise argparse.ArgumentTypeError(f"expected a whole number from 0 to {2**32 - 1}, got '{text}'")
    return value


def use_agg() -> None:
    """Draw figures without a display (files only)."""
    import matplotlib

    matplotlib.use("Agg")


def output_folder(path: Path, option: str) -> Path:
    """A folder to write into, made if missing (recorded in :data:`MADE_FOLDERS`: a command that fails removes
    them again, :func:`remove_made_folders`); a :class:`ParameterError` naming ``option`` if it cannot be."""
    if path.exists() and not path.is_dir():
        raise ParameterError(f"{option}: '{path}' is a file, not a folder")
    missing = [folder for folder in (path, *path.parents) if not folder.exists()]  # deepest first
    try:
        path.mkdir(parents=True, exist_ok=True)
        MADE_FOLDERS.extend(missing)
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
    OUTPUT_OPTIONS[str(path)] = option
    return path


def output_failure(exc: OSError) -> str:
    """The one line of an output that could not be written (:mod:`isolator.scenario.output_files` names the
    file): the option that named it, the file, the reason (``--out out.csv: No space left on device``)."""
    name = exc.filename
    option = OUTPUT_OPTIONS.get(str(name), "") if name is not None else ""
    reason = exc.strerror or str(exc) or type(exc).__name__
    return f"{option} {name}: {reason}" if option else f"{name or 'output'}: {reason}"  # escaped when printed


def figure_path(path: Path | None, option: str) -> Path | None:
    """:func:`output_path` for a figure: an extension matplotlib writes."""
    if path is None:
        return None
    from matplotlib.figure import Figure

    formats = Figure().canvas.get_supported_filetypes()
    return output_path(path, option, tuple(f".{ext}" for ext in sorted(formats)))


def save_figure(fig: Any, path: Path) -> None:
    """Write a matplotlib figure at 120 dpi (whole or not at all: :func:`save_figure_file`) and close it."""
    import matplotlib.pyplot as plt

    try:
        save_figure_file(fig, path, dpi=120)
    finally:
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
            print(written(label, path))
    return 0


def written(label: str, path: object) -> str:
    """The ``label: path`` line of a file written, the path escaped (:func:`escaped`: a name's control
    characters cannot drive the terminal)."""
    return f"{label}: {escaped(path)}"


def scheduler_arguments(parser: argparse.ArgumentParser, where: Any = None) -> None:
    """``--scheduler`` (into ``where``, e.g. a group exclusive with ``--workers``) and the TLS options, named as
    Dask's own command line names them."""
    (where or parser).add_argument(
        "--scheduler", metavar="tls://HOST:PORT",
        help="run on a Dask cluster through its scheduler: tls://HOST:PORT with --tls-ca-file, --tls-cert and "
        "--tls-key (or Dask's TLS configuration), or tcp://HOST:PORT (unencrypted: on this machine only)")
    tls = parser.add_argument_group("TLS to the Dask scheduler (as 'dask scheduler --protocol tls' takes them)")
    tls.add_argument("--tls-ca-file", type=Path, metavar="CA.pem",
                     help="the CA certificate that signed the scheduler's and this client's certificates")
    tls.add_argument("--tls-cert", type=Path, metavar="CERT.pem", help="this client's certificate")
    tls.add_argument("--tls-key", type=Path, metavar="KEY.pem", help="this client's private key (unencrypted)")


@contextlib.contextmanager
def scheduler_client(args: argparse.Namespace) -> Iterator[Any]:
    """The Dask client of ``--scheduler`` (None without one), every problem one line naming the option, closed
    at the end. Its warnings (a plain tcp:// scheduler beyond this machine) are printed at once, and Dask's own
    log lines are silenced while it runs: the command reports what goes wrong in one line."""
    files = {"ca": args.tls_ca_file, "cert": args.tls_cert, "key": args.tls_key}
    given = [k for k, v in files.items() if v is not None]
    if given and args.scheduler is None:
        raise ParameterError(f"{CLI_NAMES[given[0]]}: only with --scheduler tls://HOST:PORT")
    if given and len(given) < 3:
        missing = ", ".join(CLI_NAMES[k] for k in files if files[k] is None)
        raise ParameterError(f"{missing}: TLS needs all three of --tls-ca-file, --tls-cert and --tls-key")
    if args.scheduler is None:
        yield None
        return
    from isolator.sweep.cluster import connect, import_distributed, tls_security

    import_distributed("--scheduler")  # Dask sets its loggers' levels as it is imported: silenced after
    quiet = [*_silence("distributed"), *_silence("tornado")]  # tornado: the event loop Dask's client runs on
    try:
        security = tls_security(files["ca"], files["cert"], files["key"], CLI_NAMES) if given else None
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            client = connect(args.scheduler, security, names=CLI_NAMES)
        for w in caught:
            print(f"isolator: warning: {escaped(w.message)}", file=sys.stderr, flush=True)
        try:
            yield client
        finally:
            with contextlib.suppress(Exception):
                client.close(timeout=2)
    finally:
        for logger, level in quiet:
            logger.setLevel(level)


def _silence(prefix: str) -> list[tuple[logging.Logger, int]]:
    """Raise the loggers under ``prefix`` above CRITICAL; their levels before, to restore."""
    names = [prefix, *[n for n in logging.root.manager.loggerDict if n.startswith(prefix + ".")]]
    loggers = [logging.getLogger(n) for n in names]
    before = [(logger, logger.level) for logger in loggers]
    for logger in loggers:
        logger.setLevel(logging.CRITICAL + 1)
    return before


def parse_positions(items: Sequence[str] | None, option: str = "--position") -> dict[str, float] | None:
    """Carriage positions [m] from repeated ``NAME=Q`` options (None when none was given)."""
    if not items:
        return None
    positions = {}
    for item in items:
        name, sep, value = item.partition("=")
        try:
            positions[name.strip()] = float(value)
        except ValueError:
            raise ParameterError(f"{option}: expected NAME=Q with Q in metres, got '{item}'") from None
        if not sep:
            raise ParameterError(f"{option}: expected NAME=Q with Q in metres, got '{item}'")
    return positions


def read_controller(path: Path, option: str) -> Any:
    """The exported controller of a folder (its ``controller.json``) or a JSON file, every problem one
    :class:`ParameterError` naming ``option``."""
    from isolator.simulation.discrete_controller import DiscreteController

    named = path.exists() and not path.is_dir()  # a file (or a FIFO: refused as one)
    source = path if named else path / "controller.json"
    try:
        return DiscreteController.from_json(source)
    except ParameterError as exc:  # the reading's own errors start with the path
        named = str(exc).startswith(escaped(source, 120))
        raise ParameterError(f"{option}: {exc}" if named else f"{option}: '{source}': {exc}") from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else f"{type(exc).__name__}: {exc}"
        raise ParameterError(f"{option}: cannot read '{source}': {reason}") from None
    except (KeyError, TypeError, AttributeError) as exc:
        raise ParameterError(f"{option}: '{source}' is not a controller.json ({type(exc).__name__}: {exc})"
                             ) from None
