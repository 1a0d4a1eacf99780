"""Building a compiled library for :func:`isolator.numerics.native.compiled_library`: this CPU's identity (part of
the cache key) and vector width, the lock that makes processes needing one library build it in turn, and
the build itself, in a folder of its own, moved into place at once."""

from __future__ import annotations

import contextlib
import functools
import os
import subprocess
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path

try:  # POSIX: builds of one library by several processes wait for each other
    import fcntl
except ImportError:  # pragma: no cover - Windows: each process builds in its own folder
    fcntl = None  # type: ignore[assignment]

from isolator.numerics.native_cache import record_hash

__all__ = ["build_library", "build_lock", "cpu_identity", "vector_lanes"]


@functools.cache
def cpu_identity() -> str:
    """This CPU's model and flags (``/proc/cpuinfo``; the platform's names elsewhere): part of a library's cache
    key, since ``-march=native`` compiles for them."""
    try:
        with open("/proc/cpuinfo") as handle:
            lines = [ln for ln in handle if ln.startswith(("model name", "flags"))]
        return "".join(sorted(set(lines)))
    except OSError:
        import platform

        return platform.processor() + platform.machine()


def vector_lanes() -> int:
    """Doubles in one vector register of this CPU, as ``-march=native`` compiles for it: 8 with AVX-512, else 4
    (AVX; other CPUs run four lanes as well, in two or four instructions)."""
    return 8 if "avx512f" in cpu_identity().split() else 4


@contextlib.contextmanager
def build_lock(path: Path) -> Iterator[None]:
    """Hold an exclusive lock on ``path`` (made if missing) across processes: two processes that need the same
    library (a sweep's workers, on a fresh cache) build it one after the other, the second finding it built."""
    with open(path, "a") as handle:
        if fcntl is not None:
            fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            if fcntl is not None:
                fcntl.flock(handle, fcntl.LOCK_UN)


def build_library(compiler: str, name: str, source: str, flags: Sequence[str], language: str, target: Path) -> None:
    """Compile ``source`` into ``target`` in a folder of this build's own (no other build shares its source or
    object file), its hash recorded, then moved into place at once."""
    with tempfile.TemporaryDirectory(dir=target.parent) as tmp:
        src = Path(tmp, name + (".c" if language == "c" else ".cpp"))
        src.write_text(source)
        obj, built = Path(tmp, name + ".o"), Path(tmp, name + ".so")
        # compile with the flags, link without them: -ffast-math at link time would add the start-up
        # code that switches the whole process to flushing subnormal numbers to zero
        compile_flags = [f for f in flags if f != "-shared"]
        for step in ([compiler, *compile_flags, "-c", "-o", str(obj), str(src)],
                     [compiler, "-shared", "-fPIC", "-o", str(built), str(obj), "-lm"]):
            done = subprocess.run(step, capture_output=True, text=True)
            if done.returncode != 0:
                lines = done.stderr.splitlines()
                errors = [ln for ln in lines if "error" in ln] or lines or [""]
                raise RuntimeError(f"{compiler} failed on {name}: {errors[0].strip()}")
        record_hash(target, built)
        os.replace(built, target)
