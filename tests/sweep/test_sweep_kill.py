"""The sweep's own process killed outright (SIGKILL, as the OOM killer does): its pool's workers end with it,
and the sweep finished with --resume gives the rows of an undisturbed run, bit for bit (the command in real
processes; the kills come when rows have landed in the file, found by polling it, not after a sleep)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from isolator.cli.app import main
from isolator.sweep import sweep

psutil = pytest.importorskip("psutil")
pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="SIGKILL and fork")

ROOT = Path(__file__).resolve().parents[2]
DEADLINE = 60.0  # [s] for anything to happen, generous on a loaded machine
DAMPING = "isolators[*].damping=0.3:3:1200"
COMMAND = ["sweep", "paper-table-3-2", "--scale", DAMPING, "--workers", "2", "--chunk-size", "8"]


def rows_in(path: Path) -> int:
    """Whole data rows in a sweep's CSV (the header and a row cut short not counted)."""
    if not path.exists():
        return 0
    return max(0, path.read_bytes().count(b"\n") - 1)


def start(out: Path, *extra: str) -> subprocess.Popen[bytes]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen([sys.executable, "-m", "isolator.cli", *COMMAND, "--out", str(out), *extra], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def kill_once_rows_land(proc: subprocess.Popen[bytes], out: Path, more_than: int) -> list[int]:
    """SIGKILL the sweep once its file holds more than ``more_than`` rows and both its workers run; their ids."""
    end = time.monotonic() + DEADLINE
    workers: list[int] = []
    while time.monotonic() < end and proc.poll() is None:
        workers = [c.pid for c in psutil.Process(proc.pid).children()]
        if rows_in(out) > more_than and len(workers) == 2:
            break
        time.sleep(0.005)
    assert proc.poll() is None, "the sweep ended before it could be killed"
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait(DEADLINE)
    return workers


def ended(pids: list[int]) -> bool:
    return not any(psutil.pid_exists(p) and psutil.Process(p).status() != psutil.STATUS_ZOMBIE for p in pids)


def wait_for(condition, what: str) -> None:
    end = time.monotonic() + DEADLINE
    while not condition():
        assert time.monotonic() < end, f"not within {DEADLINE:g} s: {what}"
        time.sleep(0.01)


@pytest.fixture
def orphans():
    """Worker ids to SIGKILL after the test should they outlive it (a failing test leaves nothing running)."""
    pids: list[int] = []
    yield pids
    for pid in pids:
        if psutil.pid_exists(pid):
            os.kill(pid, signal.SIGKILL)


def test_a_killed_sweep_leaves_no_worker_and_resumes_to_the_undisturbed_rows(tmp_path, orphans):
    out = tmp_path / "rows.csv"
    first = kill_once_rows_land(start(out), out, 0)
    orphans.extend(first)
    wait_for(lambda: ended(first), "the workers of the killed sweep ending")
    kept = rows_in(out)
    assert 0 < kept < 1200
    # killed again while resuming, then finished
    second = kill_once_rows_land(start(out, "--resume"), out, kept)
    orphans.extend(second)
    wait_for(lambda: ended(second), "the workers of the killed resumed sweep ending")
    assert kept < rows_in(out) < 1200
    assert main([*COMMAND, "--out", str(out), "--resume"]) == 0
    undisturbed = tmp_path / "undisturbed.csv"
    sweep("paper-table-3-2", scale={"isolators[*].damping": list(np.linspace(0.3, 3, 1200))},
          workers=2, out=undisturbed)
    assert out.read_bytes() == undisturbed.read_bytes()
