"""Input files read safely: regular files only, their size checked against memory before they are read.

Scenario files, records, sampled profiles, forces files and controller folders come from elsewhere (a
colleague, a vendor, a pull request). :func:`read_input` opens a file without blocking (a FIFO or a
terminal would otherwise hang the command for ever), refuses anything that is not a regular file
(``/dev/zero``, a FIFO, a socket, a folder) naming the key it came from, and refuses a file whose reading
would need more memory than the machine has, with the size it would need, before reading a byte of it.
Messages quote paths and short excerpts only (:func:`isolator.scenario.names.escaped`), never a line of
an arbitrary file.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import stat
import sys
from collections.abc import Iterator
from typing import BinaryIO

from isolator.errors import IsolatorError, ParameterError, ScenarioError
from isolator.scenario.names import escaped

__all__ = ["READ_FACTOR", "available_memory", "check_input", "check_memory", "long_integer", "parse_json",
           "read_input", "read_input_text", "read_text_table"]

#: memory [bytes] reading a text table takes per byte of the file (the text, its lines, the cells as Python
#: strings in lists: one- or two-character cells cost some 30 bytes each)
READ_FACTOR = 32.0
#: what is read of a regular file that gives no size (those of /proc) [bytes]
_SMALL = 1 << 20
#: how much of a path a message quotes [characters]
_PATH = 120


def available_memory() -> int | None:
    """Bytes of memory available to a new allocation (Linux ``MemAvailable``), None if unknown."""
    try:
        with open("/proc/meminfo") as handle:
            for line in handle:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def _gb(n: float) -> str:
    return f"{n / 1e9:.3g} GB"


def check_memory(needed: float, what: str, fix: str, error: type[IsolatorError] = ParameterError) -> None:
    """Refuse up front what needs more memory than the machine has available, with the estimate.

    ``what`` starts with the key or option it comes from (``--points: 1e+09 frequencies``)."""
    have = available_memory()
    if have is not None and needed > have:
        raise error(f"{what} need about {_gb(needed)} of memory, more than the {_gb(have)} this machine has "
                    f"available; {fix}")


def _kind(mode: int) -> str:
    """What a file that is not a regular one is."""
    for test, name in ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return "not a regular file"


@contextlib.contextmanager
def _opened(path: str | os.PathLike[str], key: str, error: type[IsolatorError], factor: float
            ) -> Iterator[tuple[BinaryIO, int]]:
    """An input file opened without blocking, checked (regular, small enough), and its size [bytes]."""
    where = f"{key}: '{escaped(path, _PATH)}'" if key else escaped(path, _PATH)
    try:  # O_NONBLOCK: opening a FIFO with no writer returns at once rather than waiting for one
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:  # as "key: cannot read 'path' (reason)"
        reason = "no such file" if isinstance(exc, FileNotFoundError) else \
            "a folder, not a file" if isinstance(exc, IsADirectoryError) else exc.strerror or type(exc).__name__
        shown = escaped(path, _PATH)
        raise error(f"{key}: cannot read '{shown}' ({reason})" if key else f"{shown}: cannot read ({reason})") from None
    with os.fdopen(fd, "rb") as handle:
        info = os.fstat(fd)  # of what was opened, not of what the name points at now
        if not stat.S_ISREG(info.st_mode):
            raise error(f"{where}: is {_kind(info.st_mode)}; only regular files are read")
        check_memory(info.st_size * factor, f"{where}: {info.st_size} bytes", "give a smaller file", error)
        try:
            yield handle, info.st_size
        except OSError as exc:
            raise error(f"{where}: cannot be read ({exc.strerror or type(exc).__name__})") from None


def check_input(path: str | os.PathLike[str], key: str, *, error: type[IsolatorError] = ScenarioError,
                factor: float = READ_FACTOR) -> int:
    """The size [bytes] of an input file another library will read, checked as :func:`read_input` checks it."""
    with _opened(path, key, error, factor) as (_, size):
        return size


def read_input(path: str | os.PathLike[str], key: str, *, error: type[IsolatorError] = ScenarioError,
               factor: float = READ_FACTOR) -> bytes:
    """The bytes of an input file, checked before it is read.

    Parameters
    ----------
    path : path
        The file.
    key : str
        The key or option it came from, named first in every error ("": the path comes first).
    error : type
        The error to raise: :class:`ScenarioError` for a file a scenario names, :class:`ParameterError` for
        one an argument or option names.
    factor : float
        Memory reading it takes per byte of the file (default :data:`READ_FACTOR`, a text table).

    Returns
    -------
    bytes

    Raises
    ------
    IsolatorError
        Of kind ``error``, naming ``key`` and the path: no such file, not a regular file (a folder, a FIFO, a
        device, a socket: these are never read), unreadable, or larger than the memory reading it would take
        (with that size).
    """
    with _opened(path, key, error, factor) as (handle, size):
        return handle.read(max(size, _SMALL))  # /proc's files say 0 bytes: read as a small one


def read_input_text(path: str | os.PathLike[str], key: str, *, error: type[IsolatorError] = ScenarioError,
                    factor: float = READ_FACTOR, bom: bool = True) -> str:
    """:func:`read_input` decoded as UTF-8 (a byte-order mark dropped when ``bom``); not UTF-8 is ``error``
    naming the byte offset (never quoting the file)."""
    raw = read_input(path, key, error=error, factor=factor)
    try:
        return raw.decode("utf-8-sig" if bom else "utf-8")
    except UnicodeDecodeError as exc:
        where = f"{key}: '{escaped(path, _PATH)}'" if key else escaped(path, _PATH)
        raise error(f"{where}: not UTF-8 text (byte 0x{raw[exc.start]:02x} at offset "
                    f"{exc.start}); save it as UTF-8") from None


def parse_json(text: str, where: str, *, error: type[IsolatorError] = ParameterError) -> object:
    """JSON read strictly, every problem one ``error`` starting with ``where`` (a file, an option and its file).

    Stricter than :func:`json.loads` where it silently picks an answer: a key given twice in one object
    is refused naming the key (Python's decoder keeps the last one), and ``NaN``/``Infinity`` (no JSON
    numbers) are refused; a syntax error names its line and column, never the content around it.

    Examples
    --------
    >>> parse_json('{"a": 1}', "f.json")
    {'a': 1}
    >>> parse_json('{"a": 1, "a": 2}', "f.json")
    Traceback (most recent call last):
    ...
    isolator.errors.ParameterError: f.json: the key 'a' is given twice in one JSON object (keep one)
    """
    def pairs(items: list[tuple[str, object]]) -> dict[str, object]:
        out: dict[str, object] = {}
        for key, value in items:
            if key in out:
                raise error(f"{where}: the key '{escaped(key, 40)}' is given twice in one JSON object (keep one)")
            out[key] = value
        return out

    def constant(name: str) -> float:
        raise error(f"{where}: {name} is not a JSON number (every number must be finite)")

    try:
        return json.loads(text, object_pairs_hook=pairs, parse_constant=constant)
    except IsolatorError:
        raise
    except json.JSONDecodeError as exc:  # where, and the decoder's reason: no content quoted
        raise error(f"{where}: cannot read as JSON (line {exc.lineno}, column {exc.colno}: {exc.msg})") from None
    except RecursionError:
        raise error(f"{where}: cannot read as JSON (nested too deeply)") from None
    except ValueError:  # an integer of more digits than Python converts
        raise error(f"{where}: {long_integer(text)}") from None


def long_integer(text: str) -> str:
    """Where ``text`` holds a whole number too long for Python to read (``sys.get_int_max_str_digits``), as a
    message's reason: its line, the key before it on that line (if any) and its digits, never the number.

    Examples
    --------
    >>> long_integer("[table]\\nmass = " + "1" * 5000)
    "line 2: the number of 'mass' has 5000 digits (at most 4300 are read; no physical value needs more)"
    """
    most = sys.get_int_max_str_digits() or 4300
    for number, line in enumerate(text.splitlines(), 1):
        found = re.search(rf"\d(?:_?\d){{{most},}}", line)
        if found:
            keys = re.findall(r"([A-Za-z_][\w.-]*)[\"']?\s*[=:]", line[:found.start()])
            whose = f" of '{escaped(keys[-1], 40)}'" if keys else ""
            digits = sum(c.isdigit() for c in found.group())
            return (f"line {number}: the number{whose} has {digits} digits (at most {most} are read; "
                    "no physical value needs more)")
    return f"a whole number longer than {most} digits (no physical value needs more)"


#: the control characters no text table holds (all of C0 and C1 but tab, line feed, vertical tab, form feed and
#: carriage return)
_CONTROL = re.compile("[\x00-\x08\x0e-\x1f\x7f-\x9f]")


def read_text_table(path: str | os.PathLike[str], key: str, expected: str, *,
                    error: type[IsolatorError] = ScenarioError) -> str:
    """:func:`read_input_text` of a file that must be a text table (CSV), refused without quoting any of it
    when it holds a control character (a NUL, an escape: a binary file, ``/proc/self/environ``), naming the
    line and saying what was ``expected`` (``a CSV record: a header t,<sensor>,... and rows of numbers``).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "r.csv"
    >>> _ = path.write_bytes(b"SECRET=x\\x00PATH=/bin")
    >>> read_text_table(path, "", "a CSV table")
    Traceback (most recent call last):
    ...
    isolator.errors.ScenarioError: .../r.csv: line 1 holds the control character 0x00; expected a CSV table (a ...
    """
    text = read_input_text(path, key, error=error)
    found = _CONTROL.search(text)
    if found is not None:
        where = f"{key}: '{escaped(path, _PATH)}'" if key else escaped(path, _PATH)
        line = text.count("\n", 0, found.start()) + 1
        raise error(f"{where}: line {line} holds the control character 0x{ord(found.group()):02x}; expected "
                    f"{expected} (a text file)")
    return text
