"""The folder of compiled models and the checks that make loading from it safe.

A library loaded with ctypes runs as the user, so the cache folder (``$ISOLATOR_CACHE``, default
``~/.cache/isolator``) must be the user's own: :func:`private_cache` makes it 0700 and refuses one that
belongs to another user or that others may write into (as ssh refuses a loose ``~/.ssh``). Each library's
SHA-256 is recorded beside it when it is built (:func:`record_hash`), and :func:`verified` tells whether a
library found there is still the one built: one planted there, or damaged, is built again, never loaded.
"""

from __future__ import annotations

import hashlib
import os
import stat
import tempfile
from pathlib import Path

from isolator.errors import ParameterError

__all__ = ["cache_dir", "private_cache", "record_hash", "verified"]


def cache_dir() -> Path:
    """Folder holding compiled models (``$ISOLATOR_CACHE`` or ``~/.cache/isolator``)."""
    env = os.environ.get("ISOLATOR_CACHE")
    base = Path(env) if env else Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "isolator"
    return base


def private_cache() -> Path:
    """:func:`cache_dir`, made private (0700) if missing, refused if others could write into it.

    A library found there is loaded into the process (code run as the user), so the folder must be the
    user's own, as ssh requires of ``~/.ssh``.

    Raises
    ------
    ParameterError
        Naming ``ISOLATOR_CACHE``: the folder cannot be made, is not a folder, belongs to another user, or
        its group or others may write into it (with the ``chmod`` that fixes it).
    """
    folder = cache_dir()
    try:
        folder.parent.mkdir(parents=True, exist_ok=True)
        folder.mkdir(mode=0o700, exist_ok=True)
        info = folder.lstat()
    except OSError as exc:
        raise ParameterError(f"ISOLATOR_CACHE: cannot make the cache folder '{folder}' "
                             f"({exc.strerror or type(exc).__name__})") from None
    if not stat.S_ISDIR(info.st_mode):
        raise ParameterError(f"ISOLATOR_CACHE: '{folder}' is not a folder (a link or a file); compiled models "
                             "are kept only in a folder of one's own")
    if hasattr(os, "geteuid") and info.st_uid != os.geteuid():
        raise ParameterError(f"ISOLATOR_CACHE: the cache folder '{folder}' belongs to another user (uid "
                             f"{info.st_uid}); its libraries would run as you: use a folder of your own")
    if info.st_mode & 0o022:
        raise ParameterError(f"ISOLATOR_CACHE: others may write into the cache folder '{folder}' (mode "
                             f"{stat.S_IMODE(info.st_mode):o}), and its libraries run as you: chmod 700 '{folder}'")
    return folder


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def record_hash(library: Path, built: Path) -> None:
    """Keep the hash of ``built``, about to become ``library``, beside it (``<library>.sha256``), written
    before the library appears."""
    digest = _sha256(built)
    fd, tmp = tempfile.mkstemp(suffix=".sha256", dir=library.parent)
    with os.fdopen(fd, "w") as handle:
        handle.write(digest + "\n")
    os.replace(tmp, library.with_name(library.name + ".sha256"))


def verified(library: Path) -> bool:
    """Whether ``library`` is a regular file whose hash is the one recorded when it was built here."""
    try:
        if not stat.S_ISREG(library.lstat().st_mode):
            return False
        recorded = library.with_name(library.name + ".sha256").read_text().strip()
        return recorded == _sha256(library)
    except (OSError, UnicodeDecodeError):
        return False
