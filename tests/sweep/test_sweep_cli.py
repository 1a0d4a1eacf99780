"""``isolator sweep``: a run writes its rows and a summary; every bad input one line, exit status 2,
nothing written."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from conftest import run_command as run
from isolator.cli.sweep_command import parse_values
from isolator.errors import ParameterError
from isolator.sweep import cluster


def test_a_sweep_from_the_command_line(tmp_path: Path, capsys):
    out = tmp_path / "rows.csv"
    status, text, err = run(["sweep", "paper-table-3-2", "--scale", "isolators[*].stiffness=0.8:1.2:3",
                             "--set", "isolators[*].damping.z=4000,8000", "--workers", "1", "--frequency", "10",
                             "--out", str(out)], capsys)
    assert status == 0, err
    assert "designs: 6 (6 run now), not ok: 0" in text
    assert "best design: isolators[*].damping.z = " in text
    rows = list(csv.DictReader(out.open()))
    assert [r["design"] for r in rows] == [str(i) for i in range(6)]
    assert [float(r["isolators[*].damping.z"]) for r in rows] == [4000.0] * 3 + [8000.0] * 3
    assert [float(r["isolators[*].stiffness"]) for r in rows[:3]] == [0.8, 1.0, 1.2]
    assert "transmissibility:z@10Hz" in rows[0]
    status, text, err = run(["sweep", "--scale", "isolators[*].stiffness=0.8:1.2:3", "--set",
                             "isolators[*].damping.z=4000,8000", "--workers", "1", "--frequency", "10", "--out",
                             str(out), "--resume"], capsys)
    assert status == 0
    assert "6 from the file" in text


def test_samples_from_the_command_line(tmp_path: Path, capsys):
    out = tmp_path / "rows.csv"
    status, _, err = run(["sweep", "--set", "table.mass=4000:5000", "--samples", "5", "--method", "lhs",
                          "--workers", "1", "--out", str(out)], capsys)
    assert status == 0, err
    masses = [float(r["table.mass"]) for r in csv.DictReader(out.open())]
    assert len(masses) == 5
    assert all(4000 <= m <= 5000 for m in masses)


def test_ranges_are_inclusive_and_log_is_geometric():
    assert parse_values("1:2:3", "--set", False) == [1.0, 1.5, 2.0]
    assert np.allclose(parse_values("1:100:3:log", "--set", False), [1.0, 10.0, 100.0], rtol=1e-14)
    assert parse_values("1,2.5,4", "--set", False) == [1.0, 2.5, 4.0]
    assert parse_values("7", "--set", False) == [7.0]
    assert parse_values("1:2", "--set", True) == [1.0, 2.0]
    with pytest.raises(ParameterError, match="a geometric range"):
        parse_values("0:1:3:log", "--set", False)


@pytest.mark.parametrize(("args", "named"), [
    (["--scale", "isolators[*].stifness=0.5:2:3"], "did you mean 'isolators[*].stiffness'"),
    (["--scale", "isolators[*].stiffness=0.5:2:0"], "COUNT must be a whole number >= 1, got '0'"),
    (["--scale", "isolators[*].stiffness=0.5:2:x"], "COUNT must be a whole number >= 1, got 'x'"),
    (["--scale", "isolators[*].stiffness=a:2:3"], "START must be a number, got 'a'"),
    (["--scale", "isolators[*].stiffness=1,b"], "each value must be a number, got 'b'"),
    (["--scale", "isolators[*].stiffness=1:2:3:lin"], "expected START:STOP:COUNT or START:STOP:COUNT:log"),
    (["--scale", "isolators[*].stiffness"], "expected NAME=VALUES"),
    (["--scale", "table[*].mass=1,2"], "'[*]' after 'table', which has no elements"),
    (["--scale", "isolators[*].stiffness=1,2", "--scale", "table.mass=1,2,3", "--zip"], "zip: the zipped lists"),
    (["--scale", "isolators[*].stiffness=1:2:3", "--samples", "4"], "with --samples give a range START:STOP"),
    (["--scale", "isolators[*].stiffness=1,2", "--scale", "isolators[*].stiffness=3"], "is swept twice"),
    ([], "--set, --scale: give at least one NAME=VALUES"),
    (["--set", "table.mass=4000:5000", "--samples", "4", "--seed", "-1"], "--seed: expected a whole number from 0"),
    (["--set", "table.mass=4000,5000", "--chunk-size", "0"], "chunk_size: must be a whole number >= 1"),
    (["--set", "table.mass=4000,5000", "--frequency", "-3"], "must be finite and >= 0 [Hz]"),
    (["--scale", "isolators[*].stiffness=1,2", "--scheduler", "tcp://127.0.0.1:9"],
     "cannot reach a Dask scheduler at tcp://127.0.0.1:9"),
])
def test_bad_input_is_one_line_and_nothing_written(tmp_path: Path, capsys, monkeypatch, args, named):
    monkeypatch.setattr(cluster, "SCHEDULER_TIMEOUT", 0.5)  # the address is closed: no need to wait 5 s
    out = tmp_path / "rows.csv"
    status, _, err = run(["sweep", *args, "--out", str(out), "--workers", "1"] if "--scheduler" not in args
                         else ["sweep", *args, "--out", str(out)], capsys)
    assert status == 2
    assert len(err) == 1, err
    assert err[0].startswith("isolator: error: "), err
    assert named in err[0], err
    assert not out.exists()


def test_existing_output_and_extensions(tmp_path: Path, capsys):
    out = tmp_path / "rows.csv"
    out.write_text("keep me\n")
    status, _, err = run(["sweep", "--scale", "table.mass=1,2", "--out", str(out)], capsys)
    assert status == 2
    assert len(err) == 1
    assert "exists; --resume continues it, --force overwrites it" in err[0]
    assert out.read_text() == "keep me\n"
    status, _, err = run(["sweep", "--scale", "table.mass=1,2", "--out", str(tmp_path / "rows.xlsx")], capsys)
    assert status == 2
    assert len(err) == 1
    assert "has extension '.xlsx'; supported: .csv, .parquet" in err[0]
    status, _, err = run(["sweep", "--scale", "table.mass=1,2", "--out", str(out), "--resume", "--force"], capsys)
    assert status == 2
    assert len(err) == 1
    assert "not allowed with argument" in err[0]


def test_resume_of_a_finished_parquet_checks_its_designs(tmp_path: Path, capsys):
    pytest.importorskip("pyarrow")
    out = tmp_path / "rows.parquet"
    first = ["sweep", "--scale", "isolators[*].stiffness=0.5:2:4", "--out", str(out), "--workers", "1"]
    assert run(first, capsys)[0] == 0
    status, text, err = run([*first, "--resume"], capsys)
    assert status == 0, err
    assert "4 from the file" in text
    for values, named in (("3:5:4", "design 0 differs"), ("3:5:2", "design 0 differs"),
                          ("0.5,1", "design 2 is not one of this sweep's 2")):
        status, _, err = run(["sweep", "--scale", f"isolators[*].stiffness={values}", "--out", str(out),
                              "--workers", "1", "--resume"], capsys)
        assert status == 2
        assert len(err) == 1, err
        assert "holds another sweep's rows" in err[0], err
        assert named in err[0], err


def test_the_help_names_every_status_and_column(capsys):
    status, text, _ = run(["sweep", "--help"], capsys)
    assert status == 0
    words = " ".join(text.split())
    for named in ("unsettled", "failed", "design, band:<signal>", "dynamic_settling_time_max", "leveling_time",
                  "supply_exhausted", "window_settling_time_max", "moves_per_hour", "total_time",
                  "throughput_per_hour", "unsettled_step", "mode:<k>", ".sweep.json"):
        assert named in words, named
