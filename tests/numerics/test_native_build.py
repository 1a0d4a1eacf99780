"""Processes that need the same compiled library at once (a sweep's workers on a fresh cache) each get a
whole library: the builds do not share a source or object file, and wait for each other."""

from __future__ import annotations

import ctypes
import multiprocessing
import shutil

import pytest

from isolator.numerics import native
from isolator.numerics.native_cache import verified

pytestmark = pytest.mark.skipif(shutil.which("cc") is None and shutil.which("gcc") is None, reason="no C compiler")
#: enough functions that a build takes a fraction of a second: a window for the builds to overlap
FUNCTIONS = 3000
SOURCE = "".join(f"double f{i}(double x) {{ return x * {i}.0 + {i % 7}.5 / (x + 1.0); }}\n"
                 for i in range(FUNCTIONS))


def _build_and_call(cache: str) -> float:
    import os

    os.environ["ISOLATOR_CACHE"] = cache
    lib = ctypes.CDLL(str(native.compiled_library("race", SOURCE, ("-O0", "-fPIC", "-shared"))))
    last = getattr(lib, f"f{FUNCTIONS - 1}")
    last.restype, last.argtypes = ctypes.c_double, [ctypes.c_double]
    return float(last(1.0))


def test_simultaneous_builds_of_one_library_give_whole_libraries(tmp_path):
    cache = tmp_path / "cache"
    with multiprocessing.get_context("spawn").Pool(4) as pool:
        values = pool.map(_build_and_call, [str(cache)] * 8)
    assert values == [pytest.approx((FUNCTIONS - 1) + (FUNCTIONS - 1) % 7 / 2 + 0.25)] * 8
    libraries = sorted(cache.glob("race-*.so"))
    assert len(libraries) == 1
    assert verified(libraries[0])
    assert not list(cache.glob("*.c"))  # nothing left of the builds
    assert not list(cache.glob("*.o"))
