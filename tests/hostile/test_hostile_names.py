"""Hostile names (issue 35, items 5 and 6): one rule for every name a scenario defines, and control
characters escaped in everything the command prints from an input."""

from __future__ import annotations

import tomllib

import pytest
import tomli_w
from hostile_cases import refused
from hypothesis import given
from hypothesis import strategies as st

from conftest import active_dict, base_dict
from isolator import ScenarioError, bundled_scenarios, scenario_from_dict
from isolator.scenario.names import MAX_NAME, check_name, check_names, escaped

#: characters no name may hold: controls (NUL, ESC, newline, DEL, C1), separators, invisible formatting
#: (bidirectional overrides, zero-width joiner)
BAD = st.sampled_from(["\x00", "\x1b", "\n", "\r", "\t", "\x7f", "\x85", "\u2028", "\u202e", "\u200d", "\ufeff"])
SECTIONS = ["carriages", "actuators", "isolators", "points", "sensors"]


def _with_name(section: str, name: str) -> dict:
    """A valid scenario whose first entry of ``section`` is called ``name``."""
    data = active_dict()
    if section == "points":
        data["points"] = [{"name": "p", "position": [0.0, 0.0, 0.2]}]
    if section == "sensors":
        data["sensors"] = [{"name": "s", "on": "table", "position": [0.0, 0.0, 0.0], "direction": [0.0, 0.0, 1.0],
                            "quantity": "acceleration"}]
    data[section][0]["name"] = name
    return data


@given(section=st.sampled_from(SECTIONS), before=st.text(max_size=5).filter(str.isprintable), bad=BAD,
       after=st.text(max_size=5).filter(str.isprintable))
def test_every_section_refuses_a_name_with_a_control_or_invisible_character(section, before, bad, after):
    name = f"a{before}{bad}{after}b"
    with pytest.raises(ScenarioError) as error:
        scenario_from_dict(_with_name(section, name))
    message = str(error.value)
    assert message.startswith(f"{section}[0].name: "), message
    assert message.isprintable()


@given(section=st.sampled_from(SECTIONS),
       name=st.text(st.characters(blacklist_categories=("Cc", "Cf", "Cs", "Co", "Cn", "Zl", "Zp")),
                    min_size=1, max_size=MAX_NAME).map(str.strip)
       .filter(lambda s: s and s.isprintable() and s[0] not in "=+-@"))
def test_every_section_takes_a_printable_name(section, name):
    if name in ("table", "t"):  # a carriage's parent, a record's time column: taken
        name += "-stage"
    scene = scenario_from_dict(_with_name(section, name))
    assert getattr(scene, section)[0].name == name


def test_a_name_too_long_and_one_with_spaces_around_are_refused():
    for name in ("x" * (MAX_NAME + 1), " padded", ""):
        with pytest.raises(ScenarioError, match=r"^carriages\[0\]\.name: "):
            scenario_from_dict(_with_name("carriages", name))


def test_a_nul_in_a_carriage_name_can_no_longer_cut_it_in_c():
    """The issue's case: ``"a\\u0000b"`` became ``"a"`` in the generated C."""
    with pytest.raises(ScenarioError, match=r"carriages\[0\]\.name: .*'a\\x00b'"):
        scenario_from_dict(_with_name("carriages", "a\u0000b"))


def test_the_validator_is_one_public_function_for_any_section():
    check_names(["dust", "wind"], "disturbances")
    with pytest.raises(ScenarioError, match=r"^disturbances\[1\]\.name: 'dust' is used twice"):
        check_names(["dust", "dust"], "disturbances")
    with pytest.raises(ScenarioError, match=r"^disturbances\[0\]\.name: "):
        check_names(["\x1b[2J"], "disturbances")
    assert check_name("x-stage", "carriages[0].name") == "x-stage"


@given(st.text(max_size=60))
def test_escaped_text_is_printable_and_keeps_printable_text(text):
    out = escaped(text)
    assert out.isprintable()
    if text.isprintable():
        assert out == text


def test_a_scenario_name_with_terminal_escapes_is_one_escaped_line(tmp_path, monkeypatch, capsys):
    data = tomllib.loads(bundled_scenarios()["paper-table-3-2"].read_text(encoding="utf-8"))
    data["name"] = "\x1b]0;owned\x07\x1b[2J\x1b[31mred"
    path = tmp_path / "escape.toml"
    path.write_text(tomli_w.dumps(data), encoding="utf-8")
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    line = refused(["simulate", str(path)], capsys)
    assert line.startswith("name: ")
    assert "\\x1b" in line
    assert "\x1b" not in line


def test_an_argument_with_terminal_escapes_is_printed_escaped(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    line = refused(["simulate", "\x1b[2Jnowhere\n.toml"], capsys)
    assert "\\x1b[2Jnowhere\\n.toml" in line


def test_a_base_scenario_with_plain_names_still_reads():
    assert scenario_from_dict(base_dict()).carriages[0].name == "x-stage"
