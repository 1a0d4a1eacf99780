"""Sweeps run: the metrics of each design as a single run gives them, serial and pool alike, failures
recorded per row (a design that tips, a chunk that raises, a worker that dies), linear extras."""

from __future__ import annotations

import functools
import importlib
import os
import sys
from concurrent.futures import Future, ThreadPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import pytest

from conftest import same_columns
from isolator import Simulator, load_scenario
from isolator.analysis.linear import linearise
from isolator.analysis.modes import modes
from isolator.scenario.definitions import SIGNALS
from isolator.simulation import batch
from isolator.sweep import sweep, worker

SCENARIO = "paper-table-3-2"
SIM = Simulator(load_scenario(SCENARIO))
GRID = {"isolators[*].stiffness": [0.6, 1.0, 1.7], "isolators[*].damping": [0.5, 2.0]}


def test_each_row_is_the_single_run_of_its_design():
    result = sweep(SCENARIO, scale=GRID, set={"carriages[1].mass": [150.0]}, workers=1)
    assert result.columns[:3] == ("carriages[1].mass", "isolators[*].stiffness", "isolators[*].damping")
    assert result.columns[3:5] == ("settling_time_max", "settling:x")
    assert len(result) == 6
    table = result.table()
    for r in range(6):
        k, c = table["isolators[*].stiffness"][r], table["isolators[*].damping"][r]
        p = SIM.scaled_parameters(k, c)
        p[SIM.layout.names.index("carriages[1].mass")] = 150.0
        run = SIM.run(p=p)
        expected = [np.nan if v is None else v for v in run.settling_time.values()]
        np.testing.assert_allclose([table[f"settling:{s}"][r] for s in SIGNALS], expected, rtol=0, atol=1e-9)
        np.testing.assert_allclose([table[f"peak:{s}"][r] for s in SIGNALS], list(run.peak.values()), rtol=1e-9)
        assert table["status"][r] == ("ok" if np.all(np.isfinite(expected)) else "unsettled")  # the run's verdict
        assert table["design"][r] == r


def test_a_pool_gives_the_serial_rows_in_design_order():
    serial = sweep(SCENARIO, scale=GRID, workers=1)
    pooled = sweep(SCENARIO, scale=GRID, workers=2, chunk_size=1)
    threads = sweep(SCENARIO, scale=GRID, executor=ThreadPoolExecutor(2), chunk_size=4)
    same_columns(serial.table(), pooled.table())
    same_columns(serial.table(), threads.table())


def test_a_design_that_tips_is_recorded_and_the_others_kept():
    result = sweep(SCENARIO, scale={"isolators[*].stiffness": [1.0, 1e-4, 0.9]}, workers=1)
    assert result["status"].tolist() == ["ok", "tipped", "ok"]
    assert "the table would tip" in result["reason"][1]
    assert result["reason"][0] == ""
    assert np.isnan(result["settling_time_max"][1])
    assert np.all(np.isfinite(result["settling_time_max"][[0, 2]]))
    assert result.tally.failed == 1


def test_a_design_too_big_for_the_memory_is_refused_not_run(monkeypatch):
    monkeypatch.setattr(batch, "MEMORY_SHARE", 1e9)  # as if every run needed more than the machine has
    result = sweep(SCENARIO, scale={"isolators[*].stiffness": [1.0, 2.0]}, workers=1)
    assert result["status"].tolist() == ["refused", "refused"]
    assert "of memory, more than the" in result["reason"][0]


def test_an_invalid_design_is_recorded():
    result = sweep(SCENARIO, set={"table.inertia.x": [1000.0, 1e5]}, workers=1)
    assert result["status"].tolist() == ["ok", "invalid"]
    assert "table.inertia" in result["reason"][1]


def test_a_chunk_that_raises_is_retried_once_then_recorded(monkeypatch):
    original, calls = worker.run_chunk, []
    plain = sweep(SCENARIO, scale=GRID, workers=1)["status"].tolist()  # "ok", or "unsettled" within the run

    def flaky(chunk: worker.Chunk) -> worker.ChunkResult:
        calls.append(chunk.start)
        if chunk.start == 2:  # always fails
            raise RuntimeError("a bad node")
        if chunk.start == 4 and calls.count(4) == 1:  # fails once
            raise RuntimeError("a hiccup")
        return original(chunk)

    monkeypatch.setattr(worker, "run_chunk", flaky)
    for options in ({"workers": 1}, {"executor": ThreadPoolExecutor(2)}):
        calls.clear()
        result = sweep(SCENARIO, scale=GRID, chunk_size=2, **options)
        assert sorted(calls) == [0, 2, 2, 4, 4]
        assert result["status"].tolist() == [*plain[:2], "failed", "failed", *plain[4:]]
        assert result["reason"][2] == "after 2 attempts: RuntimeError: a bad node"
        assert np.all(np.isfinite(result["peak:z"][[0, 1, 4, 5]]))
        assert np.all(np.isnan(result["peak:z"][[2, 3]]))


class _Dying(ThreadPoolExecutor):
    """An executor whose chunk starting at design 3 kills its worker on the first try."""

    tries: ClassVar[dict[int, int]] = {}

    def submit(self, fn: Any, /, *args: Any, **kwargs: Any) -> Future:
        chunk = args[0]
        self.tries[chunk.start] = self.tries.get(chunk.start, 0) + 1
        if chunk.start == 3 and self.tries[chunk.start] == 1:
            future: Future = Future()
            future.set_exception(BrokenProcessPool("a worker died"))
            return future
        return super().submit(fn, *args, **kwargs)


def test_a_chunk_whose_worker_died_is_run_again():
    result = sweep(SCENARIO, scale=GRID, executor=_Dying(2), chunk_size=3)
    assert _Dying.tries == {0: 1, 3: 2}
    same_columns(result.table(), sweep(SCENARIO, scale=GRID, workers=1).table())


def _dies_once(marker: Path, chunk: worker.Chunk) -> worker.ChunkResult:
    """Kill the worker process the first time the chunk starting at design 2 comes (the marker remembers)."""
    if chunk.start == 2 and not marker.exists():
        marker.touch()
        os._exit(1)
    return ORIGINAL(chunk)


ORIGINAL = worker.run_chunk


@pytest.mark.skipif(sys.platform != "linux", reason="the patched task reaches the workers by fork")
def test_a_process_pool_whose_worker_died_is_renewed_and_nothing_lost(monkeypatch, tmp_path):
    monkeypatch.setattr(worker, "run_chunk", functools.partial(_dies_once, tmp_path / "died"))
    with pytest.warns(UserWarning, match="renewed its pool"):
        result = sweep(SCENARIO, scale=GRID, workers=2, chunk_size=2)
    assert (tmp_path / "died").exists()
    monkeypatch.setattr(worker, "run_chunk", ORIGINAL)
    table = result.table()
    assert "failed" not in table["status"].tolist()  # every chunk in flight when the pool broke ran again
    same_columns(table, sweep(SCENARIO, scale=GRID, workers=1).table())


def _always_dies(chunk: worker.Chunk) -> worker.ChunkResult:
    """Kill the worker process whenever the chunk starting at design 0 comes."""
    if chunk.start == 0:
        os._exit(1)
    return ORIGINAL(chunk)


@pytest.mark.skipif(sys.platform != "linux", reason="the patched task reaches the workers by fork")
def test_a_chunk_that_always_kills_its_worker_fails_alone(monkeypatch):
    damping = {"isolators[*].damping": [0.5 + 0.1 * i for i in range(12)]}
    monkeypatch.setattr(importlib.import_module("isolator.sweep.worker"), "run_chunk", _always_dies)
    with pytest.warns(UserWarning, match="renewed its pool"):
        result = sweep(SCENARIO, scale=damping, workers=2, chunk_size=2)
    monkeypatch.setattr(importlib.import_module("isolator.sweep.worker"), "run_chunk", ORIGINAL)
    table = result.table()
    assert table["status"].tolist() == ["failed"] * 2 + ["ok"] * 10  # the chunks in flight with it were spared
    assert table["reason"][0].startswith("after 2 attempts: the worker died")
    assert table["design"].tolist() == list(range(12))
    serial = sweep(SCENARIO, scale=damping, workers=1).table()
    np.testing.assert_allclose(table["settling_time_max"][2:], serial["settling_time_max"][2:], rtol=1e-9)
    np.testing.assert_allclose(table["peak:z"][2:], serial["peak:z"][2:], rtol=1e-9)


def test_transmissibility_and_modes_per_design():
    result = sweep(SCENARIO, scale={"isolators[*].stiffness": [0.7, 1.4]}, workers=1, frequencies=[2.0, 20.0],
                   modes=True)
    assert result.columns[-12:] == ("transmissibility:x@2Hz", "transmissibility:y@2Hz", "transmissibility:z@2Hz",
                                    "transmissibility:x@20Hz", "transmissibility:y@20Hz", "transmissibility:z@20Hz",
                                    *[f"mode:{k}" for k in range(1, 7)])
    lin = linearise(SIM.scenario, parameters=SIM.scaled_parameters(1.4, 1.0))
    h = lin.frequency_response(np.array([20.0]), ["ground:z"], ["z"])[0, 0, 0]
    assert result["transmissibility:z@20Hz"][1] == pytest.approx(abs(h), rel=1e-12)
    np.testing.assert_allclose([result[f"mode:{k}"][1] for k in range(1, 7)], modes(lin).frequencies_hz, rtol=1e-12)


def test_a_design_that_does_not_settle_is_unsettled_counted_and_skipped(tmp_path):
    damping = {"isolators[*].damping": [1.0, 0.02, 0.005]}
    result = sweep(SCENARIO, scale=damping, workers=1, out=tmp_path / "rows.csv")
    assert result["status"].tolist() == ["ok", "unsettled", "unsettled"]
    assert result["reason"][0] == ""
    for why in result["reason"][1:]:
        assert why.startswith("no settling time: x, y, z"), why
        assert why.endswith("not settled in the band by the run's end at 12 s ([simulation] duration)"), why
    assert np.isnan(result["settling_time_max"][1:]).all()
    assert (result.tally.failed, result.tally.statuses) == (2, {"unsettled": 2})
    summary = result.summary().splitlines()
    assert summary[0] == "designs: 3 (3 run now), not ok: 2 (2 unsettled)"
    assert summary[2].startswith("best design (of the 1 ok; skipped 2 unsettled): isolators[*].damping = 1,")
    resumed = sweep(SCENARIO, scale=damping, workers=1, out=tmp_path / "rows.csv", resume=True)
    assert resumed.summary().splitlines()[0] == "designs: 3 (0 run now, 3 from the file), not ok: 2 (2 unsettled)"
    none = sweep(SCENARIO, scale={"isolators[*].damping": [0.005]}, workers=1)
    assert none.summary().splitlines()[2] == "best design: none (no design is ok with a settling_time_max; 1 unsettled)"
