"""Issue 26, item 2: default output names made from a scenario's ``name`` are safe (a slug of at most 100
characters, in the working directory); a path the user gives is used as given; every output path is
checked before any work."""

from __future__ import annotations

import time
import tomllib
from pathlib import Path

import pytest
import tomli_w

from isolator import bundled_scenarios
from isolator.cli.app import main


def _named(tmp_path: Path, name: str) -> Path:
    data = tomllib.loads(bundled_scenarios()["paper-table-3-2"].read_text(encoding="utf-8"))
    data["name"] = name
    data["simulation"]["duration"] = 8.5
    path = tmp_path / "scenario.toml"
    path.write_text(tomli_w.dumps(data), encoding="utf-8")
    return path


@pytest.mark.parametrize(("name", "expected"), [
    ("../../escape", "escape.png"),
    ("/tmp/absolute", "tmp-absolute.png"),
    ("bell\x07and\nnewline", "bell-and-newline.png"),
    ("...", "scenario.png"),
    ("Tisch für Sensoren", "Tisch-fur-Sensoren.png"),
])
def test_default_names_are_slugs_in_the_working_directory(name, expected):
    from isolator.cli.helpers import default_output

    assert default_output(name, ".png") == Path(expected)


def test_a_long_name_is_cut_to_100_characters():
    from isolator.cli.helpers import default_output

    path = default_output("x" * 5000, ".png")
    assert path == Path("x" * 100 + ".png")


def test_a_scenario_named_outside_the_folder_writes_its_figure_inside(tmp_path, monkeypatch, capsys):
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    assert main(["simulate", str(_named(tmp_path, "../../escaped"))]) == 0
    assert (work / "escaped.png").is_file()
    assert not (tmp_path / "escaped.png").exists()
    assert not (tmp_path.parent / "escaped.png").exists()


def test_a_5000_character_name_still_writes_its_figure(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", str(_named(tmp_path, "n" * 5000))]) == 0
    assert (tmp_path / ("n" * 100 + ".png")).is_file()


def test_a_given_path_too_long_for_the_file_system_is_refused_before_any_work(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    start = time.perf_counter()
    assert main(["simulate", "paper-table-3-2", "--plot", "p" * 300 + ".png"]) == 2
    message = capsys.readouterr().err.strip()
    assert time.perf_counter() - start < 5.0
    assert message.startswith("isolator: error: --plot: ")
    assert "file systems take at most 255" in message
    assert len(message) < 200


def test_a_given_path_is_used_as_given(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "sub").mkdir()
    assert main(["simulate", "paper-table-3-2", "--plot", "sub/../given name.png"]) == 0
    assert (tmp_path / "given name.png").is_file()
