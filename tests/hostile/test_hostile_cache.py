"""The compiled-model cache loads only what it built (issue 35, item 4): made private (0700), refused when
others may write into it, and a library planted under a built one's name (or damaged) is built again,
never loaded."""

from __future__ import annotations

import ctypes
import os
import shutil
import stat

import pytest

from isolator import ParameterError
from isolator.numerics import native

needs_compiler = pytest.mark.skipif(shutil.which("cc") is None and shutil.which("gcc") is None,
                                    reason="no C compiler")
SOURCE = "int probe(void) { return 42; }\n"


def _planted(folder, marker) -> str:
    """C whose library writes ``marker`` as soon as it is loaded, and whose probe() returns 666."""
    return ("#include <stdio.h>\n__attribute__((constructor)) static void planted(void) {\n"
            f"    FILE *f = fopen(\"{marker}\", \"w\"); if (f) {{ fputs(\"ran\", f); fclose(f); }}\n}}\n"
            "int probe(void) { return 666; }\n")


@pytest.fixture
def cache(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.setenv("ISOLATOR_CACHE", str(folder))
    return folder


@needs_compiler
def test_the_cache_folder_is_made_private(cache):
    native.compiled_library("probe", SOURCE)
    assert stat.S_IMODE(cache.stat().st_mode) == 0o700


@pytest.mark.parametrize("mode", [0o777, 0o775, 0o757, 0o1777])
def test_a_cache_others_may_write_into_is_refused(cache, mode):
    cache.mkdir()
    cache.chmod(mode)
    with pytest.raises(ParameterError, match=r"^ISOLATOR_CACHE: others may write into the cache folder .*chmod 700"):
        native.compiled_library("probe", SOURCE)
    assert list(cache.iterdir()) == []  # nothing compiled into it


def test_a_link_as_cache_folder_is_refused(cache, tmp_path):
    target = tmp_path / "elsewhere"
    target.mkdir(mode=0o700)
    cache.symlink_to(target)
    with pytest.raises(ParameterError, match=r"^ISOLATOR_CACHE: .*not a folder"):
        native.compiled_library("probe", SOURCE)


@needs_compiler
@pytest.mark.parametrize("record", ["kept", "removed"])
def test_a_planted_library_is_never_loaded(cache, tmp_path, record):
    library = native.compiled_library("probe", SOURCE)
    marker = tmp_path / "planted-ran"
    evil = native.compiled_library("evil", _planted(tmp_path, marker))  # built (not loaded) elsewhere in the cache
    os.replace(evil, library)  # planted under the real one's name
    if record == "removed":
        library.with_name(library.name + ".sha256").unlink()
    again = native.compiled_library("probe", SOURCE)
    assert again == library
    assert ctypes.CDLL(str(again)).probe() == 42  # the library built from the source, not the planted one
    assert not marker.exists()  # the planted code never ran


@needs_compiler
def test_a_damaged_library_is_built_again(cache):
    library = native.compiled_library("probe", SOURCE)
    library.write_bytes(library.read_bytes()[:100])
    again = native.compiled_library("probe", SOURCE)
    assert ctypes.CDLL(str(again)).probe() == 42
