"""The cluster's faults, with real processes: a Dask worker killed mid-sweep costs no row; a scheduler killed
mid-sweep ends the command with one error line naming --resume, the rows written kept, and the sweep resumed
(here on the local pool) gives the undisturbed rows bit for bit."""

from __future__ import annotations

import importlib
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import isolator.sweep.runner as runner
from isolator.cli.app import main
from isolator.sweep import sweep

distributed = pytest.importorskip("distributed")
pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="SIGKILL")

ROOT = Path(__file__).resolve().parents[2]
DEADLINE = 60.0  # [s] for anything to happen, generous on a loaded machine
DAMPING = [0.3 + 2.7 * i / 1199 for i in range(1200)]
COMMAND = ["sweep", "paper-table-3-2", "--scale", "isolators[*].damping=0.3:3:1200", "--chunk-size", "8"]


def rows_in(path: Path) -> int:
    return max(0, path.read_bytes().count(b"\n") - 1) if path.exists() else 0


def wait_for(condition: Any, what: str) -> None:
    end = time.monotonic() + DEADLINE
    while not condition():
        assert time.monotonic() < end, f"not within {DEADLINE:g} s: {what}"
        time.sleep(0.005)


@pytest.fixture(scope="module")
def undisturbed(tmp_path_factory) -> bytes:
    out = tmp_path_factory.mktemp("undisturbed") / "rows.csv"
    sweep("paper-table-3-2", scale={"isolators[*].damping": list(np.linspace(0.3, 3, 1200))}, workers=2, out=out)
    return out.read_bytes()


def test_a_killed_dask_worker_costs_no_row(tmp_path, monkeypatch):
    grid = {"isolators[*].damping": DAMPING[:96]}
    local = sweep("paper-table-3-2", scale=grid, workers=1).table()
    cluster = distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None)
    original, killed = runner.run_chunks, []

    def hooked(chunks: Any, executor: Any, in_flight: int, done: Any, *rest: Any) -> None:
        def after(result: Any) -> None:
            done(result)
            if not killed:  # the first chunk has landed: SIGKILL a worker process of the cluster
                pid = next(iter(client.run(os.getpid).values()))
                os.kill(pid, signal.SIGKILL)
                killed.append(pid)

        original(chunks, executor, in_flight, after, *rest)

    monkeypatch.setattr(importlib.import_module("isolator.sweep.sweep"), "run_chunks", hooked)
    with cluster, distributed.Client(cluster) as client:
        through = sweep("paper-table-3-2", scale=grid, executor=client.get_executor(), chunk_size=4).table()
    assert killed
    for name, values in local.items():
        assert values.tolist() == through[name].tolist() if values.dtype == object else \
            np.array_equal(values, through[name], equal_nan=True), name


@pytest.fixture
def scheduler(tmp_path):
    """A Dask scheduler and one worker, each its own process (so that the scheduler can be killed)."""
    file = tmp_path / "scheduler.json"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "env": env}
    started = [subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                                 "--port", "0", "--no-dashboard", "--scheduler-file", str(file)], **quiet)]
    try:
        wait_for(lambda: file.exists() and file.read_text().strip().endswith("}"), "the scheduler starting")
        address = json.loads(file.read_text())["address"]
        started.append(subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address, "--nthreads",
                                         "1", "--no-dashboard"], **quiet))
        with distributed.Client(address, timeout=DEADLINE) as client:
            client.wait_for_workers(1, timeout=DEADLINE)
        yield started[0], address
    finally:
        for proc in started:
            proc.kill()
            proc.wait()


def test_a_killed_scheduler_is_one_error_naming_resume_and_the_sweep_resumes(scheduler, tmp_path, undisturbed,
                                                                               capsys):
    process, address = scheduler
    out = tmp_path / "rows.csv"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    sweeping = subprocess.Popen([sys.executable, "-m", "isolator.cli", *COMMAND, "--scheduler", address, "--out",
                                 str(out)], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        wait_for(lambda: rows_in(out) > 0 or sweeping.poll() is not None, "rows landing")
        assert sweeping.poll() is None, "the sweep ended before its scheduler could be killed"
        process.send_signal(signal.SIGKILL)  # mid-sweep
        _, err = sweeping.communicate(timeout=DEADLINE)
    finally:
        sweeping.kill()
    lines = [line for line in err.splitlines() if not line.startswith("isolator sweep: ")]  # progress, if slow
    assert sweeping.returncode == 2, err
    assert len(lines) == 1, err
    assert lines[0].startswith("isolator: error: the executor"), err
    assert "--resume" in lines[0]
    assert f"kept in '{out}'" in lines[0]
    kept = out.read_bytes()
    assert 0 < rows_in(out) < 1200
    assert undisturbed.startswith(kept)  # every row written is kept, as it was
    # resumed without the cluster, on the local pool
    assert main([*COMMAND, "--workers", "2", "--out", str(out), "--resume"]) == 0
    assert f"{rows_in(out)} " == "1200 "
    assert out.read_bytes() == undisturbed
    capsys.readouterr()
