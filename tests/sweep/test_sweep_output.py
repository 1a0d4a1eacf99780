"""Rows streamed to CSV or Parquet as chunks arrive, read back; an interrupted sweep resumed from the file."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from conftest import same_columns
from isolator.errors import ParameterError
from isolator.simulation.settling import Band
from isolator.sweep import sweep, worker

SCENARIO = "paper-table-3-2"
GRID = {"isolators[*].stiffness": [0.6, 1.0, 1.7], "isolators[*].damping": [0.5, 1.0, 2.0]}


def test_streamed_rows_are_the_kept_rows(tmp_path: Path):
    kept = sweep(SCENARIO, scale=GRID, workers=1)
    streamed = sweep(SCENARIO, scale=GRID, workers=1, out=tmp_path / "rows.csv", chunk_size=2)
    assert streamed._kept is None  # nothing kept in memory: read back from the file
    same_columns(kept.table(), streamed.table(), rtol=0.0)
    assert streamed["status"].tolist() == kept["status"].tolist()
    assert (tmp_path / "rows.csv").read_text().splitlines()[0].startswith(
        "isolators[*].stiffness,isolators[*].damping,settling_time_max,settling:x,")


def test_an_interrupted_sweep_resumes_to_the_clean_result(tmp_path: Path, monkeypatch):
    clean = sweep(SCENARIO, scale=GRID, workers=1, out=tmp_path / "clean.csv")
    lines = (tmp_path / "clean.csv").read_text().splitlines(keepends=True)
    cut = tmp_path / "cut.csv"
    cut.write_text("".join(lines[:5]) + lines[5][:17])  # four rows, then an interrupt mid-row
    with pytest.raises(ParameterError, match=r"exists; resume=True continues it, force=True overwrites it"):
        sweep(SCENARIO, scale=GRID, workers=1, out=cut)
    assert cut.read_text() == "".join(lines[:5]) + lines[5][:17]  # nothing overwritten
    ran: list[int] = []
    original = worker.run_chunk
    monkeypatch.setattr(worker, "run_chunk", lambda chunk: ran.append(chunk.start) or original(chunk))
    resumed = sweep(SCENARIO, scale=GRID, workers=1, out=cut, resume=True, chunk_size=2)
    assert ran == [4, 6, 8]  # designs 0-3 were on disk
    assert cut.read_text() == (tmp_path / "clean.csv").read_text()
    same_columns(resumed.table(), clean.table(), rtol=0.0)
    assert resumed.tally.resumed == 4
    assert resumed.tally.runs == 5
    assert resumed.tally.best == clean.tally.best


def test_resume_refuses_another_sweeps_file(tmp_path: Path):
    out = tmp_path / "rows.csv"
    sweep(SCENARIO, scale=GRID, workers=1, out=out)
    with pytest.raises(ParameterError, match="holds other columns"):
        sweep(SCENARIO, scale={"isolators[*].stiffness": [1.0]}, workers=1, out=out, resume=True)
    with pytest.raises(ParameterError, match="holds another sweep's rows"):
        sweep(SCENARIO, scale={**GRID, "isolators[*].stiffness": [0.6, 1.1, 1.7]}, workers=1, out=out, resume=True)
    forced = sweep(SCENARIO, scale={"isolators[*].stiffness": [1.0]}, set={}, workers=1, out=out, force=True)
    assert len(forced["design"]) == 1


def test_resume_refuses_a_file_of_another_scenario_model_or_band(tmp_path: Path):
    out, scale = tmp_path / "rows.csv", {"isolators[*].damping": [0.5, 1.0]}
    sweep("paper-table-3-2", scale=scale, workers=1, out=out)
    sidecar = tmp_path / "rows.csv.sweep.json"
    described = json.loads(sidecar.read_text())
    assert described["model"] == "exact"
    assert described["band"] is None
    assert described["frequencies"] == []
    for kwargs, named in (({"scenario": "paper-table-3-1"}, "differs in: the scenario;"),
                          ({"model": "paper"}, "differs in: model;"),
                          ({"band": Band("absolute", None, None, (1e-6,) * 6)}, "differs in: band;"),
                          ({"frequencies": [10.0], "modes": True}, "differs in: frequencies, modes;")):
        with pytest.raises(ParameterError, match="was written by another sweep") as caught:
            sweep(**{"scenario": "paper-table-3-2", **kwargs}, scale=scale, workers=1, out=out, resume=True)
        assert named in str(caught.value)
    forced = sweep("paper-table-3-1", scale=scale, workers=1, out=out, force=True)  # --force: a new description
    assert sidecar.exists()
    assert sweep("paper-table-3-1", scale=scale, workers=1, out=out, resume=True).tally.resumed == 2
    sidecar.unlink()  # a file from before the description: resumed as it is
    assert sweep("paper-table-3-2", scale=scale, workers=1, out=out, resume=True).tally.resumed == 2
    assert forced.tally.runs == 2


def test_bad_output_paths(tmp_path: Path):
    with pytest.raises(ParameterError, match=r"out: .* has extension '\.txt'; supported: \.csv, \.parquet"):
        sweep(SCENARIO, scale=GRID, out=tmp_path / "rows.txt")
    (tmp_path / "rows.csv").write_text("x\n")
    with pytest.raises(ParameterError, match="resume, force: choose one"):
        sweep(SCENARIO, scale=GRID, out=tmp_path / "rows.csv", resume=True, force=True)


def test_parquet_without_pyarrow_names_the_install(tmp_path: Path, monkeypatch):
    monkeypatch.setitem(sys.modules, "pyarrow", None)
    with pytest.raises(ParameterError, match="needs pyarrow: pip install pyarrow"):
        sweep(SCENARIO, scale=GRID, out=tmp_path / "rows.parquet")
    assert not list(tmp_path.iterdir())


def test_parquet_is_written_when_the_sweep_ends(tmp_path: Path):
    pytest.importorskip("pyarrow")
    out = tmp_path / "rows.parquet"
    result = sweep(SCENARIO, scale=GRID, workers=1, out=out, chunk_size=4)
    assert out.exists()
    assert not (tmp_path / "rows.parquet.partial.csv").exists()
    same_columns(result.table(), sweep(SCENARIO, scale=GRID, workers=1).table(), rtol=0.0)
    again = sweep(SCENARIO, scale=GRID, workers=1, out=out, resume=True)
    assert again.tally.runs == 0
    assert again.tally.resumed == 9
