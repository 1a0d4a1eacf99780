"""``isolator budget`` after trust round 4 (issue 42): the band stated, bands refused in one line or answered in
valid JSON, carriages parked beyond their travel refused, a loop worse than the passive table warned about on
stderr and listed in the JSON, and a bare ``isolator budget`` that runs."""

from __future__ import annotations

import json

import pytest
import tomli_w
from analysis.test_budget_loop import GAIN, sensed_table, skyhook
from cli.test_budget_command import exit_code

from conftest import make
from isolator.cli.app import main


def strict(text: str) -> dict:
    """JSON that refuses NaN and infinity (Python's reader takes them, other languages' do not)."""
    def refuse(word: str) -> None:
        raise ValueError(f"not JSON: {word}")
    return json.loads(text, parse_constant=refuse)


def test_a_bare_budget_runs_on_the_bundled_budget_table(capsys):
    assert main(["budget", "--points", "probe"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "band 0.1-1000 Hz"
    assert lines[1].startswith("probe:x: 2624 nm RMS")


def test_a_band_reaching_1e_minus_300_is_valid_json_and_a_figure(tmp_path, capsys):
    plot = tmp_path / "low.png"
    assert main(["budget", "paper-table-3-2-budget", "--points", "probe", "--band", "1e-300:10", "--json",
                 "--plot", str(plot)]) == 0
    out, err = capsys.readouterr()
    data = strict(out)
    assert data["band"] == [1e-300, 10.0]
    assert data["points"]["probe"]["z"]["rms"] > 0
    assert "Traceback" not in err
    assert plot.stat().st_size > 10_000


@pytest.mark.parametrize("band", ["1e300:1e301", "1e-3:1e7"])
def test_a_band_beyond_a_megahertz_is_one_line_naming_band(tmp_path, capsys, band):
    assert exit_code(["budget", "paper-table-3-2-budget", "--band", band, "--plot", str(tmp_path / "b.png")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0, err
    assert err.startswith("isolator: error: --band: ends at ")
    assert not (tmp_path / "b.png").exists()


def test_a_band_without_the_floor_notes_it_and_prints_no_nan(capsys):
    assert main(["budget", "paper-table-3-2-budget", "--band", "200:300"]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0] == "band 200-300 Hz"
    assert "note: floor:z has nothing inside the band" in out
    assert "nan" not in out


def test_a_position_beyond_the_carriages_travel_is_refused(capsys):
    assert exit_code(["budget", "paper-table-3-2-budget", "--position", "x-stage=0.75"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == ("isolator: error: --position x-stage: 0.75 m is beyond the carriage's travel, -0.7 to 0.7 m "
                   "(its profile's range)")


def test_a_loop_worse_than_passive_is_said_on_stderr_and_in_the_json(tmp_path, capsys):
    data = sensed_table(noise_psd=1e-8)  # (m/s)^2/Hz: the geophones' noise a million times too large
    path = tmp_path / "noisy.toml"
    path.write_text(tomli_w.dumps(data))
    folder = tmp_path / "ctrl"
    folder.mkdir()
    skyhook(make(data), GAIN, 1000.0).to_json(folder / "controller.json")
    assert main(["budget", str(path), "--controller", str(folder), "--json"]) == 0
    out, err = capsys.readouterr()
    worse = strict(out)["worse_than_passive"]
    assert [(w["point"], w["axis"]) for w in worse] == [("probe", "x"), ("probe", "y"), ("probe", "z")]
    assert all(w["closed"] > w["passive"] > 0 and w["largest"].startswith("sensor:") for w in worse)
    lines = err.strip().splitlines()
    assert len(lines) == 3
    for w, line in zip(worse, lines, strict=True):
        assert line.startswith(f"isolator: warning: probe:{w['axis']}: the closed loop's ")
        assert f"(largest source {w['largest']})" in line
    quiet = tmp_path / "quiet.toml"
    quiet.write_text(tomli_w.dumps(sensed_table(noise_psd=1e-14)))
    assert main(["budget", str(quiet), "--controller", str(folder), "--json"]) == 0
    out, err = capsys.readouterr()
    assert strict(out)["worse_than_passive"] == []
    assert "warning" not in err
