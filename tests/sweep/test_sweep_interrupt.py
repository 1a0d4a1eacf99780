"""An interrupted sweep (Ctrl-C) stops its worker processes at once and keeps the rows written so far."""

from __future__ import annotations

import importlib
import multiprocessing

import pytest

import isolator.sweep.runner as runner
from isolator.sweep import sweep


def test_an_interrupt_stops_the_workers_and_keeps_the_rows(tmp_path, monkeypatch):
    seen = []
    original = runner.run_chunks

    def interrupted(chunks, executor, in_flight, done, *rest):
        def after_one(result):
            done(result)
            seen.append(result.start)
            raise KeyboardInterrupt

        return original(chunks, executor, in_flight, after_one, *rest)

    monkeypatch.setattr(importlib.import_module("isolator.sweep.sweep"), "run_chunks", interrupted)
    out = tmp_path / "rows.csv"
    with pytest.raises(KeyboardInterrupt):
        sweep("paper-table-3-2", scale={"isolators[*].damping": [0.5 + 0.01 * i for i in range(64)]}, workers=2,
              chunk_size=8, out=out)
    assert seen == [0]
    assert multiprocessing.active_children() == []  # no worker left running
    rows = out.read_text().strip().splitlines()
    assert len(rows) == 1 + 8  # the header and the first chunk
    monkeypatch.undo()
    resumed = sweep("paper-table-3-2", scale={"isolators[*].damping": [0.5 + 0.01 * i for i in range(64)]},
                    workers=1, out=out, resume=True)
    assert resumed.tally.resumed == 8
    assert len(out.read_text().strip().splitlines()) == 65
