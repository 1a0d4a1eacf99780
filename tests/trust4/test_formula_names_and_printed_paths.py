"""Trust round 4 (issue 42), item 10: no name begins as a spreadsheet formula, and the paths of the files a
command wrote are printed escaped, as every other printed input is."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from conftest import active_dict, run_command
from isolator import ScenarioError, scenario_from_dict
from isolator.cli.helpers import written
from isolator.scenario.names import FORMULA_STARTS, check_name

SECTIONS = ["carriages", "actuators", "isolators", "points", "sensors"]
TAIL = st.text(st.characters(min_codepoint=32, max_codepoint=0x24F), max_size=30).filter(str.isprintable)


def _named(section: str, name: str) -> dict:
    data = active_dict()
    data["points"] = [{"name": "p", "position": [0.0, 0.0, 0.2]}]
    data["sensors"] = [{"name": "s", "on": "table", "position": [0.0, 0.0, 0.0], "direction": [0.0, 0.0, 1.0],
                        "quantity": "acceleration"}]
    data[section][0]["name"] = name
    return data


@given(section=st.sampled_from(SECTIONS), start=st.sampled_from(FORMULA_STARTS), tail=TAIL)
def test_a_name_beginning_as_a_formula_is_refused_saying_why(section, start, tail):
    name = (start + tail).rstrip()
    with pytest.raises(ScenarioError) as error:
        scenario_from_dict(_named(section, name))
    message = str(error.value)
    assert message.startswith(f"{section}[0].name: must not begin with '{start}'"), message
    assert "spreadsheet" in message
    assert message.isprintable()


def test_the_hyperlink_of_the_issue_is_refused():
    with pytest.raises(ScenarioError, match=r"^points\[0\]\.name: must not begin with '='"):
        check_name('=HYPERLINK("http://x","y")', "points[0].name")


@given(start=st.text(st.characters(min_codepoint=33, max_codepoint=0x24F), min_size=1, max_size=1)
       .filter(lambda c: c.isprintable() and c not in FORMULA_STARTS), tail=TAIL)
def test_a_name_with_a_formula_character_inside_is_still_a_name(start, tail):
    name = (start + tail).rstrip()
    assert check_name(name, "points[0].name") == name


def test_a_scenario_file_whose_stem_begins_with_a_minus_is_named_without_it(tmp_path):
    from isolator import load_scenario

    base = Path(__file__).parents[1] / "bad_inputs" / "base.toml"
    path = tmp_path / "-table.toml"
    path.write_text(base.read_text().replace('name = "base"\n', "", 1))
    assert load_scenario(path).name == "table"


@given(path=st.text(st.characters(min_codepoint=0, max_codepoint=0x9F), min_size=1, max_size=30))
def test_the_written_line_escapes_every_control_character(path):
    assert written("figure", path).isprintable()


def test_a_figure_path_with_a_terminal_escape_is_printed_escaped(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    name = "red\x1b[31m.png"
    status, out, err = run_command(["modes", "paper-table-3-1", "--plot", name], capsys)
    assert status == 0, err
    assert (tmp_path / name).is_file()
    assert "\x1b" not in out
    assert "figure: red\\x1b[31m.png" in out


def test_a_sweep_prints_its_rows_path_escaped(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    name = "rows\x1b]0;title\x07.csv"
    status, out, err = run_command(["sweep", "paper-table-3-1", "--set", "table.mass=4000:4400:2", "--workers", "1",
                                    "--out", name], capsys)
    assert status == 0, err
    assert (tmp_path / name).is_file()
    assert "\x1b" not in out
    assert "\x07" not in out
    assert "rows: rows\\x1b]0;title\\x07.csv" in out
