"""Hostile files (issue 35, items 2 and 3): whatever a scenario, a record, a forces file, a band or a
controller points at, the command reads only regular files, never blocks on a FIFO, never allocates for
``/dev/zero``, refuses a file too large to read before reading it, and quotes at most a short, escaped
excerpt of a file's header in its one line, never a line of the file."""

from __future__ import annotations

import json
import os
import shutil
import threading
import time
import tracemalloc
from pathlib import Path

import pytest
from hostile_cases import BASE, quotes_no_line_of, refused
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import isolator
from isolator import ScenarioError
from isolator.calibration.records import read_record
from isolator.errors import ParameterError
from isolator.scenario import files
from isolator.scenario.files import read_input
from isolator.scenario.names import EXCERPT

SECRET = "TOKEN_0f3a9c1e77d24b5b8e61c0ffee42"
#: a file that is not a table: a password file with a token in it
PASSWD = ("root:x:0:0:root:/root:/bin/bash\n"
          f"ci:x:1000:1000:{SECRET}:/home/ci:/bin/sh\n"
          "daemon:x:1:1:daemon:/usr/sbin:/usr/sbin/nologin\n")


@pytest.fixture
def here(tmp_path, monkeypatch):
    """An empty working folder with the base scenario (two actuators z1, z2) beside it."""
    work = tmp_path / "work"
    work.mkdir()
    shutil.copy(BASE, tmp_path / "base.toml")
    monkeypatch.chdir(work)
    return tmp_path


def _with_samples(folder: Path, target: str) -> Path:
    """A scenario whose carriage's samples profile is ``target``."""
    text = BASE.read_text(encoding="utf-8") + (
        "\n[[carriages]]\nname = \"x\"\nmass = 10.0\nparent = \"table\"\naxis = [1.0, 0.0, 0.0]\n"
        f"origin = [0.0, 0.0, 0.2]\n[carriages.profile]\ntype = \"samples\"\nfile = {json.dumps(target)}\n")
    path = folder / "samples.toml"
    path.write_text(text, encoding="utf-8")
    return path


def _fifo(folder: Path) -> Path:
    path = folder / "pipe.csv"
    os.mkfifo(path)
    return path


def _timed(call, limit: float = 10.0):
    """``call()`` in a thread: it must return within ``limit`` s (a FIFO must not block)."""
    out: list = []
    failed: list[BaseException] = []

    def run() -> None:
        try:
            out.append(call())
        except BaseException as exc:  # raised again in the test's thread
            failed.append(exc)

    thread = threading.Thread(target=run, daemon=True)
    start = time.monotonic()
    thread.start()
    thread.join(limit)
    assert not thread.is_alive(), f"blocked for more than {limit} s"
    if failed:
        raise failed[0]
    return out[0], time.monotonic() - start


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs")
@pytest.mark.parametrize("where", ["scenario", "samples", "forces", "band", "controller"])
def test_a_fifo_is_refused_at_once_naming_the_key(here, capsys, where):
    fifo = _fifo(here)
    argv = {"scenario": ["simulate", str(fifo)],
            "samples": ["simulate", str(_with_samples(here, str(fifo)))],
            "forces": ["simulate", str(here / "base.toml"), "--forces", str(fifo), "--out", "r.csv"],
            "band": ["simulate", str(here / "base.toml"), "--band-json", str(fifo), "--out", "r.csv"],
            "controller": ["simulate", str(here / "base.toml"), "--controller", str(fifo)]}[where]
    line, took = _timed(lambda: refused(argv, capsys))
    assert took < 10.0
    assert "FIFO" in line, line
    key = {"scenario": "scenario file", "samples": "carriages[0].profile.file", "forces": "--forces",
           "band": "--band-json", "controller": "--controller"}[where]
    assert line.startswith(key), line


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="no /dev/zero")
@pytest.mark.parametrize("where", ["scenario", "samples", "forces", "controller"])
def test_a_device_is_refused_without_reading_it(here, capsys, where):
    argv = {"scenario": ["simulate", "/dev/zero"],
            "samples": ["simulate", str(_with_samples(here, "/dev/zero"))],
            "forces": ["simulate", str(here / "base.toml"), "--forces", "/dev/zero", "--out", "r.csv"],
            "controller": ["simulate", str(here / "base.toml"), "--controller", "/dev/zero"]}[where]
    line = refused(argv, capsys)
    assert "character device" in line, line
    assert "only regular files" in line, line


def test_a_fifo_record_is_refused_through_the_api(tmp_path):
    fifo = _fifo(tmp_path)
    with pytest.raises(ScenarioError, match="FIFO"):
        _timed(lambda: read_record(fifo, ["a"]))


@pytest.mark.parametrize("where", ["samples", "forces", "band", "controller"])
def test_a_file_that_is_no_table_is_not_quoted(here, capsys, where):
    target = here / "passwd"
    target.write_text(PASSWD, encoding="utf-8")
    argv = {"samples": ["simulate", str(_with_samples(here, str(target)))],
            "forces": ["simulate", str(here / "base.toml"), "--forces", str(target), "--out", "r.csv"],
            "band": ["simulate", str(here / "base.toml"), "--band-json", str(target), "--out", "r.csv"],
            "controller": ["simulate", str(here / "base.toml"), "--controller", str(target)]}[where]
    line = refused(argv, capsys)
    assert SECRET not in line
    quotes_no_line_of(line, PASSWD)


def test_a_record_that_is_no_table_is_not_quoted(tmp_path):
    target = tmp_path / "passwd.csv"
    target.write_text(PASSWD, encoding="utf-8")
    with pytest.raises(ScenarioError) as error:
        read_record(target, ["a-z"])
    assert SECRET not in str(error.value)
    quotes_no_line_of(str(error.value), PASSWD)


@pytest.mark.skipif(not os.path.exists("/proc/self/environ"), reason="no /proc")
def test_the_environment_is_never_quoted(here, capsys, monkeypatch):
    monkeypatch.setenv("ISOLATOR_TEST_SECRET", SECRET)
    line = refused(["simulate", str(here / "base.toml"), "--forces", "/proc/self/environ", "--out", "r.csv"], capsys)
    assert SECRET not in line
    assert "\\x00" in line or "header" in line  # at most an escaped excerpt
    assert len(line) < 250


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(header=st.text(min_size=1, max_size=300).filter(lambda s: "\n" not in s and "\r" not in s),
       cell=st.text(min_size=1, max_size=300).filter(lambda s: "\n" not in s and "\r" not in s and "," not in s))
def test_generated_headers_and_cells_are_quoted_short_and_escaped(tmp_path_factory, header, cell):
    folder = tmp_path_factory.mktemp("csv")
    for text in (f"{header}\n0,1\n1,2\n", f"t,z1\n0,{cell}\n1,2\n"):
        path = folder / "forces.csv"
        path.write_text(text, encoding="utf-8")
        from isolator.scenario.tables import read_csv_columns

        try:
            read_csv_columns(path, "--forces", ("t",), ("z1", "z2"), increasing="t")
        except ScenarioError as error:
            message = str(error)
            assert message.isprintable()
            quotes_no_line_of(message, text)
            for quoted in message.split("'")[3::2]:  # what follows the path: each quoted excerpt
                assert len(quoted) <= 10 * EXCERPT + 3  # each character at most \U0010ffff


def test_a_file_larger_than_memory_allows_is_refused_before_reading(tmp_path, monkeypatch):
    big = tmp_path / "big.csv"
    with open(big, "wb") as handle:  # sparse: 10^7 rows' worth of bytes, nothing on disk
        handle.truncate(10**7 * 40)
    monkeypatch.setattr(files, "available_memory", lambda: 10**9)
    tracemalloc.start()
    try:
        with pytest.raises(ParameterError) as error:
            read_input(big, "--forces", error=ParameterError)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert str(error.value).startswith("--forces: ")
    assert "400000000 bytes" in str(error.value)
    assert "GB of memory" in str(error.value)
    assert peak < 10**6  # nothing of the file was read


def test_a_two_row_record_spanning_a_million_seconds_is_refused_before_it_is_simulated(tmp_path, monkeypatch,
                                                                                          capsys):
    """Its move experiment would be simulated on a grid of 10^9 steps (it took minutes and all the memory before):
    refused at once naming the experiment, its record sampled far too slowly for the table's modes (the time
    column is checked first, issue 42)."""
    folder = tmp_path / "calibration"
    shutil.copytree(Path(isolator.__file__).parent / "data" / "calibrations" / "table-3-2", folder)
    header, first = (folder / "move.csv").read_text(encoding="utf-8").splitlines()[:2]
    row = first.split(",", 1)[1]
    (folder / "move.csv").write_text(f"{header}\n0,{row}\n1000000,{row}\n", encoding="utf-8")
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    start = time.monotonic()
    line = refused(["calibrate", str(folder / "calibration.toml"), "--out", "fit.toml"], capsys)
    assert time.monotonic() - start < 60
    assert line.startswith("experiments['move']: the record move.csv is sampled at 1e-06 Hz"), line
    assert "too slow for the table's highest mode" in line
