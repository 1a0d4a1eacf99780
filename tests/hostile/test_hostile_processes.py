"""Sweeps cannot be turned into a fork bomb (issue 35, item 1): a worker count beyond the machine refused in
one line before anything starts, never more worker processes than chunks, and SIGTERM ending a sweep as
Ctrl-C does (its workers stopped, its rows kept)."""

from __future__ import annotations

import importlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from hostile_cases import children, refused

from isolator import ParameterError
from isolator.sweep import sweep
from isolator.sweep.sweep import WORKERS_PER_CORE, check_workers, default_workers

ROOT = Path(__file__).resolve().parents[2]
sweep_module = importlib.import_module("isolator.sweep.sweep")  # the module (isolator.sweep.sweep is the function)


@pytest.fixture
def pools(monkeypatch):
    """The worker counts of every pool the sweep makes."""
    made: list[int] = []
    original = sweep_module.SweepPool

    class Counted(original):  # type: ignore[misc, valid-type]
        def __init__(self, workers: int) -> None:
            made.append(workers)
            super().__init__(workers)

    monkeypatch.setattr(sweep_module, "SweepPool", Counted)
    return made


@pytest.mark.parametrize("workers", ["1e9", str(WORKERS_PER_CORE * default_workers() + 1), "1e300"])
def test_a_worker_count_beyond_the_machine_is_one_line_and_starts_nothing(tmp_path, monkeypatch, capsys, pools,
                                                                          workers):
    monkeypatch.chdir(tmp_path)
    line = refused(["sweep", "--scale", "isolators[*].damping=1,2", "--workers", workers, "--out", "s.csv"], capsys)
    assert line.startswith("--workers: ")
    assert pools == []


def test_the_python_api_refuses_it_too(pools):
    with pytest.raises(ParameterError, match=r"^workers: 1000000000 worker processes"):
        sweep("paper-table-3-2", scale={"isolators[*].damping": [1.0, 2.0]}, workers=10**9)
    assert pools == []
    assert check_workers(WORKERS_PER_CORE * default_workers()) == WORKERS_PER_CORE * default_workers()


def test_never_more_workers_than_chunks(pools):
    before = children()
    most = WORKERS_PER_CORE * default_workers()
    result = sweep("paper-table-3-2", scale={"isolators[*].damping": [1.0, 2.0]}, workers=most, chunk_size=1)
    assert result.tally.runs == 2
    assert pools == [2]  # two chunks: two processes, not the eight asked for
    time.sleep(0.5)
    assert children() <= before


def _descendants(pid: int) -> set[int]:
    found: set[int] = set()
    for task in Path(f"/proc/{pid}/task").glob("*"):
        text = (task / "children").read_text() if (task / "children").exists() else ""
        for child in map(int, text.split()):
            found |= {child, *_descendants(child)}
    return found


@pytest.mark.skipif(not Path("/proc/self/task").is_dir(), reason="needs Linux's /proc")
def test_sigterm_ends_a_sweep_as_ctrl_c_does(tmp_path):
    out = tmp_path / "rows.csv"
    env = {**os.environ, "PYTHONPATH": str(ROOT), "ISOLATOR_QUIET": "1"}
    proc = subprocess.Popen([sys.executable, "-m", "isolator.cli", "sweep", "--scale",
                             "isolators[*].damping=0.5:2:4000", "--workers", "2", "--chunk-size", "20",
                             "--out", str(out)], cwd=tmp_path, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and (not out.exists() or len(out.read_text().splitlines()) < 3):
            assert proc.poll() is None, proc.communicate()
            time.sleep(0.2)
        workers = _descendants(proc.pid)
        assert workers, "the sweep runs in worker processes"
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 128 + signal.SIGTERM, err
    assert err.strip().splitlines()[-1].startswith("isolator: terminated: ")  # with the rows kept and --resume
    assert "Traceback" not in err
    time.sleep(1.0)
    assert not [pid for pid in workers if Path(f"/proc/{pid}").exists()], "a worker outlived the sweep"
    rows = out.read_text().splitlines()
    assert 3 <= len(rows) < 4001  # the rows written are kept, the sweep did not finish
