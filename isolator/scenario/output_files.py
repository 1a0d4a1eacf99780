"""Output files written whole or not at all: a temporary file beside the target, then renamed over it.

Every file a user names (a response or budget CSV, a figure, a controller, a report, an optimised
scenario) is written through :func:`atomic_output`: into a new file in the target's folder, flushed to
disk, then put in place with :func:`os.replace`. So a crash, a full disk or Ctrl-C never leaves half a file
(the old one stays as it was), and a symbolic link at the target is replaced by the file, never followed to
a file elsewhere (nor its dangling target created). A target that exists and is neither a regular file
nor a link (``/dev/null``, a FIFO) cannot be replaced and is written in place. Every failure is an
:class:`OSError` carrying the target's name (``filename``), whatever call failed (``/dev/full`` fails on
the last flush, with no name of its own); the command line prints it with the option that named the file.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import stat
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

__all__ = ["atomic_output", "save_figure_file", "write_output_bytes", "write_output_text"]


def _status(target: Path) -> os.stat_result | None:
    """The target's own status (a link's, not its target's); None if there is nothing there."""
    try:
        return os.lstat(target)
    except OSError:
        return None


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike[str], mode: str = "w", *, encoding: str | None = "utf-8",
                  newline: str | None = None) -> Iterator[IO[Any]]:
    """A file handle whose content replaces ``path`` only once the block ends without an exception.

    Parameters
    ----------
    path : path
        The file to write (a link there is replaced, not followed).
    mode : {"w", "wb"}
        Text or bytes.
    encoding, newline : str, optional
        As :func:`open` takes them (text only).

    Yields
    ------
    file object

    Raises
    ------
    OSError
        With ``filename`` the target: the folder is not writable, the disk is full, ...; the target is then
        as it was (the temporary file removed).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> with atomic_output(folder / "a.csv") as handle:
    ...     _ = handle.write("t,x\\n")
    >>> (folder / "a.csv").read_text()
    't,x\\n'
    """
    target = Path(path)
    binary = "b" in mode
    kwargs: dict[str, Any] = {} if binary else {"encoding": encoding, "newline": newline}
    before = _status(target)
    if before is not None and not (stat.S_ISREG(before.st_mode) or stat.S_ISLNK(before.st_mode)):
        with _named(target), open(target, mode, **kwargs) as handle:  # a device, a FIFO: in place
            yield handle
            handle.flush()
        return
    temporary = target.with_name(f".{target.name[:40]}.{secrets.token_hex(6)}.tmp")
    with _named(target):
        fd = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0), 0o666)
    try:
        with _named(target), os.fdopen(fd, mode, **kwargs) as handle:
            if before is not None and stat.S_ISREG(before.st_mode):
                os.fchmod(fd, stat.S_IMODE(before.st_mode))  # a file replaced keeps its permissions
            yield handle
            handle.flush()
            os.fsync(fd)
        with _named(target):
            os.replace(temporary, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(temporary)
        raise


@contextlib.contextmanager
def _named(target: Path) -> Iterator[None]:
    """An :class:`OSError` raised inside as one naming ``target`` (its reason kept)."""
    try:
        yield
    except OSError as exc:
        if exc.filename == str(target):
            raise
        raise OSError(exc.errno, exc.strerror or str(exc), str(target)) from None


def write_output_text(path: str | os.PathLike[str], text: str, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` through :func:`atomic_output`; returns the path."""
    with atomic_output(path, encoding=encoding) as handle:
        handle.write(text)
    return Path(path)


def write_output_bytes(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` through :func:`atomic_output`; returns the path."""
    with atomic_output(path, "wb") as handle:
        handle.write(data)
    return Path(path)


def save_figure_file(fig: Any, path: str | os.PathLike[str], **options: Any) -> Path:
    """A matplotlib figure saved to ``path`` through :func:`atomic_output`, in the format of its extension
    (matplotlib's default without one); ``options`` go to ``savefig`` (``dpi``). Returns the path."""
    suffix = Path(path).suffix.lower().lstrip(".")
    with atomic_output(path, "wb") as handle:
        fig.savefig(handle, format=suffix or None, **options)
    return Path(path)
