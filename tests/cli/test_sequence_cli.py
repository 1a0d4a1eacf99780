"""``isolator sequence``: the per-step table, CSV and JSON outputs, --pattern, exit status 4 for a step that does
not settle, bad input exit status 2."""

from __future__ import annotations

import contextlib
import csv
import json
from pathlib import Path

import pytest

from isolator.cli.app import main
from isolator.scenario.reader import bundled_scenarios

BUNDLED = "paper-table-3-2-sequence"


def _short(tmp_path: Path, duration: float) -> Path:
    """The bundled sequence with a shorter ``[simulation] duration``."""
    text = bundled_scenarios()[BUNDLED].read_text()
    path = tmp_path / "short.toml"
    path.write_text(text.replace("duration = 200.0", f"duration = {duration}"))
    return path


def test_table_outputs_and_figure(tmp_path, capsys):
    steps, response, plot = tmp_path / "steps.csv", tmp_path / "out" / "response.csv", tmp_path / "seq.png"
    assert main(["sequence", BUNDLED, "--out", str(steps), "--response", str(response), "--plot", str(plot)]) == 0
    out = capsys.readouterr().out
    assert "paper-table-3-2-sequence (exact model): 20 steps, measure 0.1 s" in out
    assert "step  start [s]   stop [s] settled [s]    end [s]   move [s] settle [s]" in out
    assert "\n  19 " in out
    assert "total time:" in out
    assert "steps per hour" in out
    assert f"steps: {steps}" in out
    with open(steps) as handle:
        rows = list(csv.reader(handle))
    assert rows[0] == ["step", "start", "stop", "settled", "end", "move", "settle"]
    assert len(rows) == 21
    assert [int(r[0]) for r in rows[1:]] == list(range(20))
    with open(response) as handle:
        header = next(csv.reader(handle))
    assert header == ["t", "x", "y", "z", "rx", "ry", "rz", "q:x-stage", "q:y-stage", "probe:x", "probe:y",
                      "probe:z", "step"]
    assert plot.stat().st_size > 20_000


def test_json(capsys):
    assert main(["sequence", "--json", "--model", "paper"]) == 0  # the bundled sequence by default
    data = json.loads(capsys.readouterr().out)
    assert {"steps", "total_time", "throughput_per_hour", "unsettled"} <= set(data)
    assert data["model"] == "paper"
    assert data["name"] == BUNDLED
    assert len(data["steps"]) == 20
    assert set(data["steps"][0]) >= {"start", "stop", "settled", "end", "move", "settle"}
    assert data["unsettled"] is None
    assert data["throughput_per_hour"] == pytest.approx(3600 * 20 / data["total_time"])


def test_pattern_builds_a_serpentine_raster(capsys):
    assert main(["sequence", BUNDLED, "--json", "--pattern", "x-stage=-0.1:0.1:3",
                 "--pattern", "y-stage=0:0.05:2"]) == 0
    data = json.loads(capsys.readouterr().out)
    targets = [(round(s["targets"]["x-stage"], 9), round(s["targets"]["y-stage"], 9)) for s in data["steps"]]
    assert targets == [(-0.1, 0.0), (0.0, 0.0), (0.1, 0.0), (0.1, 0.05), (0.0, 0.05), (-0.1, 0.05)]
    assert data["steps_in_sequence"] == 6


def test_unsettled_step_exits_4_naming_it(tmp_path, capsys):
    steps = tmp_path / "steps.csv"
    assert main(["sequence", str(_short(tmp_path, 10.0)), "--out", str(steps)]) == 4
    captured = capsys.readouterr()
    assert captured.err.strip().splitlines() == [
        "isolator: error: step 1 did not settle within the run's 10 s ([simulation] duration); "
        "later steps did not run"]
    assert "step 1 did not settle" in captured.out
    with open(steps) as handle:
        rows = list(csv.reader(handle))
    assert rows[2][0] == "1"
    assert rows[2][3] == ""
    assert rows[2][4] == ""
    assert main(["sequence", str(_short(tmp_path, 10.0)), "--json"]) == 4
    assert json.loads(capsys.readouterr().out)["unsettled"] == 1


@pytest.mark.parametrize(("args", "words"), [
    (["paper-table-3-2"], "sequence: the scenario has no [sequence]"),
    (["paper-table-3-2", "--pattern", "x-stage=0:0.1:2"], "--pattern: the scenario 'paper-table-3-2' has no"),
    ([BUNDLED, "--pattern", "z-stage=0:0.1:2"], "--pattern: unknown carriage 'z-stage'"),
    ([BUNDLED, "--pattern", "x-stage=0:0.1"], "--pattern: expected NAME=START:STOP:COUNT"),
    ([BUNDLED, "--pattern", "x-stage=0:1.5:2"], "--pattern: sequence.steps[1].x-stage:"),
    ([BUNDLED, "--out", "steps.txt"], "--out: 'steps.txt' has extension '.txt'"),
    ([BUNDLED, "--plot", "seq.nope"], "--plot:"),
    ([BUNDLED, "--model", "wrong"], "argument --model"),
])
def test_bad_input_exits_2(args, words, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) if "--model" in args else contextlib.nullcontext():
        status = main(["sequence", *args])
        assert status == 2
    err = capsys.readouterr().err
    assert err.startswith("isolator: error: "), err
    assert words in err, err
    assert len(err.strip().splitlines()) == 1

