"""The corpus ``tests/bad_inputs/``: every class of bad input, through the command and the Python API.

Each file is one class of mistake a user makes (a scenario that is not UTF-8, a key misspelt, a forces
file with one row, ...). Through ``isolator`` each must give exit status 2 and exactly one line on stderr
naming the file or key and the reason, and no traceback; through the Python API the same message as an
:class:`IsolatorError`, never a raw Python, numpy or casadi exception.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from isolator.cli.app import main
from isolator.errors import IsolatorError, ParameterError, ScenarioError
from isolator.scenario.reader import load_scenario
from isolator.scenario.tables import load_spectrum
from isolator.simulation.actuation import load_forces

CORPUS = Path(__file__).resolve().parents[1] / "bad_inputs"


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, list[str]]:
    """The exit status and the stderr lines of ``isolator argv``, run in-process."""
    try:
        status = main(argv)
    except SystemExit as exc:  # argparse's own exits
        status = int(exc.code or 0)
    err = capsys.readouterr().err
    return status, err.splitlines()


def one_error_line(status: int, lines: list[str], *named: str) -> str:
    assert status == 2, lines
    assert len(lines) == 1, lines
    line = lines[0]
    assert line.startswith("isolator: error: "), line
    assert "Traceback" not in line
    for text in named:
        assert text in line, (text, line)
    return line.removeprefix("isolator: error: ")


# scenario files: (file, what the message names)
SCENARIOS = [
    ("not-utf8.toml", ("not-utf8.toml", "line 1", "UTF-8")),
    ("bom.toml", ("bom.toml", "byte-order mark")),
    ("directory.toml", ("directory.toml", "folder")),
    ("empty.toml", ("empty.toml", "empty")),
    ("deep-nesting.toml", ("deep-nesting.toml", "nested")),
    ("typo-key.toml", ("isolators[0].stifness: unknown key; did you mean 'stiffness'?",)),
    ("typo-table.toml", ("tabel: unknown key; did you mean 'table'?",)),
    ("samples-one-row.toml", ("carriages[0].profile.file", "samples-one-row.csv", "1 data row")),
    ("samples-not-increasing.toml", ("carriages[0].profile.file", "samples-not-increasing.csv", "line 4",
                                     "must increase")),
    ("samples-nan.toml", ("carriages[0].profile.file", "samples-nan.csv", "line 3", "q", "nan")),
]

# forces files for base.toml: (file, what the message names)
FORCES = [
    ("forces-empty.csv", ("--forces", "forces-empty.csv", "empty")),
    ("forces-no-rows.csv", ("--forces", "forces-no-rows.csv", "no data rows")),
    ("forces-one-row.csv", ("--forces", "forces-one-row.csv", "1 data row")),
    ("forces-not-increasing.csv", ("--forces", "forces-not-increasing.csv", "line 4", "must increase")),
    ("forces-nan.csv", ("--forces", "forces-nan.csv", "line 3", "z1", "nan")),
    ("forces-missing-t.csv", ("--forces", "forces-missing-t.csv", "column 't'", "missing")),
    ("forces-unknown-column.csv", ("--forces", "forces-unknown-column.csv", "column 'z3'", "z1, z2")),
    ("forces-no-actuator.csv", ("--forces", "forces-no-actuator.csv", "no actuator", "z1, z2")),
    ("forces-short-row.csv", ("--forces", "forces-short-row.csv", "line 3")),
]

# spectrum files given to criteria as the wrong kind: (file, kind, what the message names)
SPECTRA = [
    ("third-octave-as-psd.csv", "psd", ("--spectrum", "third-octave-as-psd.csv", "third-octave")),
    ("psd-as-third-octave.csv", "third-octave", ("--spectrum", "psd-as-third-octave.csv", "psd")),
]


@pytest.mark.parametrize(("name", "named"), SCENARIOS)
def test_bad_scenario_files(name: str, named: tuple[str, ...], capsys: pytest.CaptureFixture[str]) -> None:
    status, lines = run(["stability", str(CORPUS / name)], capsys)
    message = one_error_line(status, lines, *named)
    with pytest.raises(ScenarioError) as caught:
        load_scenario(CORPUS / name)
    assert str(caught.value) == message


@pytest.mark.parametrize(("name", "named"), FORCES)
def test_bad_forces_files(name: str, named: tuple[str, ...], capsys: pytest.CaptureFixture[str]) -> None:
    status, lines = run(["simulate", str(CORPUS / "base.toml"), "--json", "--forces", str(CORPUS / name)], capsys)
    message = one_error_line(status, lines, *named)
    with pytest.raises(ParameterError) as caught:
        load_forces(CORPUS / name, load_scenario(CORPUS / "base.toml"), key="--forces")
    assert str(caught.value) == message


@pytest.mark.parametrize(("name", "kind", "named"), SPECTRA)
def test_spectrum_of_the_other_kind(name: str, kind: str, named: tuple[str, ...],
                                    capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["criteria", str(CORPUS / "base.toml"), "--spectrum", str(CORPUS / name), "--kind", kind]
    message = one_error_line(*run(argv, capsys), *named)
    with pytest.raises(ScenarioError) as caught:
        load_spectrum(CORPUS / name, kind, key="--spectrum")
    assert str(caught.value) == message


def test_every_corpus_file_is_tried() -> None:
    tried = {n for n, _ in SCENARIOS} | {n for n, _ in FORCES} | {n for n, _, _ in SPECTRA}
    tried |= {n.replace(".toml", ".csv") for n, _ in SCENARIOS if n.startswith("samples-")}
    tried |= {"base.toml", "README.md", "long-duration.toml", "extreme-damping.toml"}
    assert {p.name for p in CORPUS.iterdir()} == tried


def _options(tmp: Path) -> list[tuple[list[str], tuple[str, ...]]]:
    base = str(CORPUS / "base.toml")
    (tmp / "a-file").write_text("")
    return [
        (["simulate", base, "--json", "--plot", str(tmp / "x.xyz")], ("--plot", "'.xyz'", ".png", ".pdf")),
        (["simulate", base, "--json", "--out", str(tmp / "x.xlsx")], ("--out", "'.xlsx'", ".csv")),
        (["simulate", base, "--json", "--out", str(tmp / "a-file" / "r.csv")], ("--out", "a-file")),
        (["transmissibility", base, "--points", "1e9"], ("--points", "1e+09", "GB")),
        (["transmissibility", base, "--points", "-3"], ("--points", ">= 2")),
        (["transmissibility", base, "--points", "nan"], ("--points",)),
        (["transmissibility", base, "--time", "nan"], ("time",)),
        (["simulate", str(CORPUS / "long-duration.toml"), "--json"],
         ("simulation.duration", "simulation.sample_rate", "GB")),
        (["simulate", base, "--model", "bogus"], ("--model", "bogus", "isolator simulate --help")),
        (["study", "paper", "--out", str(tmp / "s"), "--controller", "lqr"], ("--controller",)),
        (["study", "tradeoff", "--out", str(tmp / "s"), "--frequency", "nan"], ("--frequency",)),
        (["optimise-profile", base, "--max-move-time-increase", "-1"], ("max_move_time_increase",)),
        ([], ("COMMAND", "isolator --help")),
        (["simulate", "paper-table-3-3"], ("paper-table-3-3: no such scenario", "did you mean 'paper-table-3-2'?")),
        (["modes", base, "--travel", str(tmp / "t.png")], ("--travel", "no [[carriages]]")),
        (["simulate", base, "--bogus"], ("--bogus", "isolator simulate --help")),
    ]


def test_bad_options(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for argv, named in _options(tmp_path):
        one_error_line(*run(argv, capsys), *named)


def test_output_folders_are_made(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out, plot = tmp_path / "new" / "deeper" / "r.csv", tmp_path / "figures" / "run.pdf"
    assert main(["simulate", str(CORPUS / "base.toml"), "--out", str(out), "--plot", str(plot)]) == 0
    assert out.stat().st_size > 0
    assert plot.stat().st_size > 0
    assert capsys.readouterr().err == ""


def test_extreme_damping_is_a_result_or_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    status, lines = run(["simulate", str(CORPUS / "extreme-damping.toml"), "--json"], capsys)
    if status != 0:
        one_error_line(status, lines)
    else:
        assert lines == []


def test_api_raises_only_isolator_errors() -> None:
    """What the commands above catch, the API raises as an IsolatorError (never numpy's or Python's)."""
    calls: list[Callable[[], Any]] = [
        lambda: load_scenario(CORPUS / "deep-nesting.toml"),
        lambda: load_scenario(CORPUS / "not-utf8.toml"),
        lambda: load_forces(CORPUS / "forces-empty.csv", load_scenario(CORPUS / "base.toml")),
        lambda: load_spectrum(CORPUS / "forces-empty.csv", "psd"),
    ]
    for call in calls:
        with pytest.raises(IsolatorError):
            call()


def test_compiling_says_so_once(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                capsys: pytest.CaptureFixture[str]) -> None:
    from isolator.numerics import native

    monkeypatch.setenv("ISOLATOR_CACHE", str(tmp_path))
    monkeypatch.delenv("ISOLATOR_QUIET")
    monkeypatch.setattr(native, "_ANNOUNCED", set())
    native.compiled_library("probe", "int probe(void) { return 1; }\n")
    native.compiled_library("probe2", "int probe2(void) { return 2; }\n")
    assert capsys.readouterr().err == "isolator: compiling the model for this structure (first use, a few seconds)...\n"
    monkeypatch.setenv("ISOLATOR_QUIET", "1")
    monkeypatch.setattr(native, "_ANNOUNCED", set())
    native.compiled_library("probe3", "int probe3(void) { return 3; }\n")
    assert capsys.readouterr().err == ""
