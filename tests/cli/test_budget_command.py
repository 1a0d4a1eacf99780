"""``isolator budget`` (issue 32): its JSON, CSV and figure, and one line for bad input with nothing written."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
import tomli_w

from conftest import base_dict
from isolator import error_budget, load_scenario
from isolator.cli.app import main


def exit_code(args: list[str]) -> int:
    """The command's exit status, whether argparse or the command refused."""
    try:
        return main(args)
    except SystemExit as exc:
        return int(exc.code or 0)


def test_budget_json_csv_and_figure(tmp_path, capsys):
    out, plot = tmp_path / "b.csv", tmp_path / "b.png"
    assert main(["budget", "paper-table-3-2-budget", "--points", "probe", "--json", "--out", str(out),
                 "--plot", str(plot)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert set(data) == {"quantity", "band", "controller", "points", "worse_than_passive"}
    assert data["worse_than_passive"] == []
    assert data["band"] == [0.1, 1000.0]
    assert data["controller"] is None
    assert list(data["points"]) == ["probe"]
    z = data["points"]["probe"]["z"]
    expected = error_budget(load_scenario("paper-table-3-2-budget"), points=["probe"])
    assert z["rms"] == pytest.approx(expected.value("probe", "z"), rel=1e-12)
    assert len(z["sources"]) == 10
    assert sum(v**2 for v in z["sources"].values()) == pytest.approx(z["rms"] ** 2, rel=1e-9)
    with open(out) as handle:
        rows = list(csv.reader(handle))
    header = rows[0]
    assert header[0] == "frequency_hz"
    assert header[1:13] == [f"probe:x:{s}" for s in expected.sources] + ["probe:x:total", "probe:x:cumulative"]
    table = np.array(rows[1:], dtype=float)
    assert table[0, 0] == pytest.approx(0.1)
    assert table[-1, 0] == pytest.approx(1000.0)
    assert table[-1, header.index("probe:z:cumulative")] == pytest.approx(z["rms"], rel=1e-9)
    # velocity at each row is not in this file; the ASD columns square-sum to the total's
    sources = [header.index(f"probe:y:{s}") for s in expected.sources]
    np.testing.assert_allclose(np.sqrt((table[:, sources] ** 2).sum(axis=1)), table[:, header.index("probe:y:total")],
                               rtol=1e-9, atol=1e-30)
    assert plot.stat().st_size > 20_000


def test_budget_text_names_the_largest_source(capsys):
    assert main(["budget", "paper-table-3-2-budget", "--points", "lens", "--quantity", "velocity",
                 "--band", "1:100"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 4
    assert lines[0] == "band 1-100 Hz"  # the band it integrated over
    assert lines[3].startswith("lens:z: ")
    assert "µm/s RMS; largest floor:z" in lines[3]


@pytest.mark.parametrize(("args", "message"), [
    (["--band", "0:10"], "--band: must be 0 < low < high"),
    (["--band", "5"], "--band: expected LO:HI in Hz"),
    (["--band", "10:1"], "--band: must be 0 < low < high"),
    (["--points", "nose"], "--points: no point named 'nose'"),
    (["--quantity", "jerk"], "argument --quantity: invalid choice"),
    (["--controller", "/nonexistent"], "--controller: /nonexistent/controller.json: cannot read"),
    (["--position", "x-stage=9"], "--position x-stage: puts the carriage's mass"),
])
def test_bad_budget_options_one_line_nothing_written(tmp_path, capsys, args, message):
    out = tmp_path / "deep" / "b.csv"
    assert exit_code(["budget", "paper-table-3-2-budget", "--out", str(out), *args]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0, err
    assert message in err
    assert not out.exists()


def test_a_scenario_without_random_sources_is_refused(tmp_path, capsys):
    path = tmp_path / "quiet.toml"
    path.write_text(tomli_w.dumps(base_dict()))
    assert exit_code(["budget", str(path)]) == 2
    err = capsys.readouterr().err
    assert "no random source for a budget" in err
    assert err.strip().endswith("; the bundled paper-table-3-2-budget has ten (the command's default)")
