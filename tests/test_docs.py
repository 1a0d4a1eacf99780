"""Docs that cannot go stale: every code and console block of the README and of the documentation's pages
(``docs/*.md``, ``docs/guide/*.md``) runs here, through sybil, and what it shows is compared with what the
code does now.

- ``python`` blocks run in the page's own namespace (one per page, blocks in page order, in an empty
  folder); a block written as a doctest (``>>>``) compares what it shows (``...`` for the volatile parts);
- ``console`` blocks: each ``$ isolator ...`` command (``\\`` continues it; pipes as in a shell) runs in
  that folder, and the lines shown under it are compared with what it prints now (``...`` stands for any
  text, e.g. timings); a command shown with an ``isolator: error:`` line must fail, every other must
  succeed; a command shown without output only has to succeed;
- ``bash`` blocks: each ``isolator`` line runs and must succeed; a line with placeholders (``[--json]``,
  ``SCENARIO``, ``...``) is a synopsis, and each of its options must be one its subcommand takes;
- a command whose output the page does not show runs in a reduced form, to keep this module to minutes: a
  study with ``--quick`` (every study takes it: shorter runs, the same code), a sweep of more than
  :data:`MAX_SAMPLES` samples with that many (:func:`_reduced`); what a page shows is never reduced;
- ``toml`` blocks must parse, a ``c`` block of the controller's interface must match the header
  :func:`controllers.feedback.write_c` writes.

A number the prose states is shown by a block or checked like one: an invisible block computes it, shows it
as the text says it and finds that text in ``__prose__`` (the page's prose, its blocks and comments left out,
whitespace collapsed), so the sentence and the code cannot drift apart.

A block a test cannot run (set-up commands CI runs itself, a Dask cluster) is preceded by
``<!-- skip: next "the reason" -->``, which sybil reads and GitHub and MyST do not show; set-up a block
needs (a bad scenario file to show an error) is an ``<!-- invisible-code-block: python -->``.
"""

from __future__ import annotations

import doctest
import os
import re
import shlex
import stat
import subprocess
import sys
import tomllib
from pathlib import Path
from unittest import SkipTest

import matplotlib
import pytest
from sybil import Example, Sybil
from sybil.parsers.markdown import CodeBlockParser, PythonCodeBlockParser, SkipParser

ROOT = Path(__file__).resolve().parents[1]
#: the pages whose blocks run: the README, the site's hand-written pages and the user guide
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")), *sorted((ROOT / "docs" / "guide").glob("*.md"))]
#: pages whose blocks take long (studies, optimisations); CI runs them, ``-m "not slow"`` leaves them out
SLOW = {"docs/guide/calibration", "docs/guide/control", "docs/guide/export", "docs/guide/profiles-sequences",
        "docs/guide/sweeps", "docs/guide/validation", "README", "docs/index"}
FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
_CHECKER = doctest.OutputChecker()
_PLACEHOLDER = re.compile(r"\[|\.\.\.|\b[A-Z][A-Z0-9_]{2,}\b")
#: a sweep whose output a page does not show runs at most this many samples
MAX_SAMPLES = 64


def _reduced(command: str) -> str:
    """``command`` as run when its output is not shown: studies ``--quick``, samples at most MAX_SAMPLES."""
    if re.match(r"isolator study \w", command) and "--quick" not in command:
        command = re.sub(r"(isolator study [\w-]+(?: [^-#\s][^\s#]*)?)", r"\1 --quick", command, count=1)
    return re.sub(r"--samples (\d+)", lambda m: f"--samples {min(int(m.group(1)), MAX_SAMPLES)}", command)


def _commands(block: str) -> list[tuple[str, str]]:
    """A console block's ``$ `` commands (continuation lines joined) with the text shown under each."""
    commands: list[tuple[str, list[str]]] = []
    lines = iter(block.splitlines())
    for line in lines:
        if line.startswith("$ "):
            command = line[2:]
            while command.rstrip().endswith("\\"):
                command = command.rstrip()[:-1].rstrip() + " " + next(lines).strip()
            commands.append((command, []))
        elif commands:
            commands[-1][1].append(line)
        elif line.strip():
            raise ValueError(f"console block: output before the first '$ ' command: {line!r}")
    return [(command, "\n".join(shown).strip("\n")) for command, shown in commands]


def _shell(command: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """``command`` run by bash in ``cwd``, ``isolator`` being this interpreter's ``python -m isolator.cli``."""
    env = dict(os.environ, COLUMNS="120", PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    env["PATH"] = os.pathsep.join([str(cwd / ".bin"), env.get("PATH", "")])
    return subprocess.run(["bash", "-c", command], cwd=cwd, env=env, capture_output=True, text=True, timeout=900,
                          check=False)


def _console(example: Example) -> str | None:
    cwd = example.namespace["__folder__"]
    for command, shown in _commands(example.parsed):
        done = _shell(command if shown else _reduced(command), cwd)
        fails = "isolator: error:" in shown
        got = done.stdout + done.stderr if fails else done.stdout
        if (done.returncode != 0) != fails:
            return f"$ {command}\nexit status {done.returncode}\n{done.stdout}{done.stderr[-3000:]}"
        if shown and not _CHECKER.check_output(shown + "\n", got, FLAGS):
            return f"$ {command}\nshown:\n{shown}\nprinted now:\n{got}"
    return None


def _isolator_lines(block: str) -> list[str]:
    """A bash block's ``isolator`` command lines (continuations joined, comments cut)."""
    joined = re.sub(r"\\\n\s*", " ", block)
    lines = [line.split(" #", 1)[0].strip() for line in joined.splitlines()]
    return [line for line in lines if line.startswith("isolator ")]


def _options(argv: list[str]) -> set[str]:
    """The options the subcommand of ``argv`` (``isolator study NAME`` included) takes."""
    from isolator.cli.app import build_parser

    parser = build_parser()
    for word in argv[1:3]:
        actions = [a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction"]
        if not actions or word not in actions[0].choices:  # type: ignore[attr-defined]
            break
        parser = actions[0].choices[word]  # type: ignore[attr-defined]
    return {option for action in parser._actions for option in action.option_strings}


def _bash(example: Example) -> str | None:
    lines = _isolator_lines(example.parsed)
    if not lines:
        return f"a bash block without an isolator command must say why it is skipped:\n{example.parsed}"
    for line in lines:
        if _PLACEHOLDER.search(line.replace("isolators[", "")):
            argv = shlex.split(line.replace("|", " "))
            unknown = {w.split("=")[0] for w in re.findall(r"--[a-z][a-z0-9-]*", line)} - _options(argv)
            if unknown:
                return f"{line}\n{argv[1]} takes no option {sorted(unknown)}"
            continue
        done = _shell(_reduced(line), example.namespace["__folder__"])
        if done.returncode != 0:
            return f"{line}\nexit status {done.returncode}\n{done.stderr[-3000:]}"
    return None


def _toml(example: Example) -> None:
    tomllib.loads(example.parsed)


def _c(example: Example) -> str | None:
    """The controller's C interface as a page shows it: each macro and function is in the header written."""
    import control
    import numpy as np

    from controllers.feedback import from_statespace, write_c
    from isolator import load_scenario

    scenario = load_scenario("paper-table-3-2-geophones")
    sensors, actuators = [s.name for s in scenario.sensors], [a.name for a in scenario.actuators]
    gain = control.ss([], [], [], -np.eye(len(sensors)))
    header, _ = write_c(from_statespace(gain, 1000.0, sensors, actuators), example.namespace["__folder__"] / ".c")
    text = Path(header).read_text(encoding="utf-8")
    names = re.findall(r"#define (\w+)|\b(isolator_ctrl_\w+)\s*[;(]", example.parsed)
    missing = sorted({a or b for a, b in names} - set(re.findall(r"\w+", text)))
    return f"the header write_c writes has no {missing}" if missing or not names else None


DOCS = Sybil(
    parsers=[
        PythonCodeBlockParser(doctest_optionflags=FLAGS),
        CodeBlockParser("console", _console),
        CodeBlockParser("bash", _bash),
        CodeBlockParser("toml", _toml),
        CodeBlockParser("c", _c),
        SkipParser(),
    ],
    path=str(ROOT),
)


def _run_page(page: Path, folder: Path) -> list[str]:
    """Every example of ``page`` in order; returns the reasons of the skipped ones."""
    bin_dir = folder / ".bin"
    bin_dir.mkdir()
    shim = bin_dir / "isolator"
    shim.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m isolator.cli "$@"\n', encoding="utf-8")
    shim.chmod(shim.stat().st_mode | stat.S_IXUSR)
    (folder / "docs").mkdir()
    (folder / "docs" / "examples").symlink_to(ROOT / "docs" / "examples")
    document = DOCS.parse(page)
    document.namespace["__folder__"] = folder
    document.namespace["__prose__"] = prose(page.read_text(encoding="utf-8"))
    skipped = []
    for example in document:
        try:
            example.evaluate()
        except SkipTest as why:
            skipped.append(str(why))
    return skipped


def prose(text: str) -> str:
    """A page's prose, whitespace collapsed: without its fenced blocks and HTML comments (where invisible blocks
    are), for the checks of numbers the text states (``shown in __prose__``)."""
    text = re.sub(r"<!--.*?-->", " ", text, flags=re.S)
    text = re.sub(r"^(```|~~~)[^\n]*\n.*?^\1", " ", text, flags=re.S | re.M)
    return " ".join(text.split())


def _page_id(page: Path) -> str:
    return page.relative_to(ROOT).with_suffix("").as_posix()


@pytest.mark.parametrize(
    "page", [pytest.param(p, marks=[pytest.mark.slow] if _page_id(p) in SLOW else []) for p in PAGES], ids=_page_id
)
def test_every_block_of_the_page_runs_as_shown(page: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    matplotlib.use("Agg")
    monkeypatch.chdir(tmp_path)
    try:
        _run_page(page, tmp_path)
    finally:
        import matplotlib.pyplot as plt

        plt.close("all")


def test_a_changed_number_fails_the_page(tmp_path: Path):
    """The console blocks are compared: one number changed in a shown output is a failure naming it."""
    page = tmp_path / "page.md"
    page.write_text("```console\n$ isolator scenarios | head -1\npaper-table-3-1\t...\n```\n", encoding="utf-8")
    (tmp_path / "run").mkdir()
    _run_page(page, tmp_path / "run")
    page.write_text("```console\n$ isolator scenarios | head -1\npaper-table-3-7\t...\n```\n", encoding="utf-8")
    (tmp_path / "again").mkdir()
    with pytest.raises(AssertionError, match="paper-table-3-7"):
        _run_page(page, tmp_path / "again")


def test_a_number_in_the_prose_is_checked_by_its_invisible_block(tmp_path: Path):
    """A sentence stating a number, and an invisible block that computes it and finds the sentence in the prose:
    the page fails when the text says another number (the block's own expected output does not count)."""
    block = ("<!-- invisible-code-block: python\n>>> shown = f\"settles in {0.5385:.2g} s\"\n>>> shown\n"
             "'settles in 0.54 s'\n>>> shown in __prose__\nTrue\n-->\n")
    page = tmp_path / "page.md"
    page.write_text("H-infinity settles\nin 0.54 s.\n\n" + block, encoding="utf-8")
    (tmp_path / "run").mkdir()
    _run_page(page, tmp_path / "run")
    page.write_text("H-infinity settles\nin 0.42 s.\n\n" + block, encoding="utf-8")
    (tmp_path / "again").mkdir()
    with pytest.raises(AssertionError, match=r"Expected:\s+True\s+Got:\s+False"):
        _run_page(page, tmp_path / "again")
    assert prose("a\n```python\n>>> 1\n```\nb <!-- c -->  d") == "a b d"


def test_console_blocks_are_read_as_commands_and_output():
    block = "$ isolator a \\\n      --b c\nline 1\n...\n$ isolator d\n"
    assert _commands(block) == [("isolator a --b c", "line 1\n..."), ("isolator d", "")]
    assert _isolator_lines("isolator x --y 1   # comment\npip install .\n") == ["isolator x --y 1"]
    assert _reduced("isolator study tradeoff --out d") == "isolator study tradeoff --quick --out d"
    assert _reduced("isolator study tradeoff paper-table-3-2-sequence --out d") == \
        "isolator study tradeoff paper-table-3-2-sequence --quick --out d"
    assert _reduced("isolator study robustness --out r --samples 200") == \
        "isolator study robustness --quick --out r --samples 64"
    assert _reduced("isolator sweep x --samples 10 --out s.csv") == "isolator sweep x --samples 10 --out s.csv"


def test_there_are_blocks_on_every_page():
    """The pages keep their examples (a regex change that finds none would pass every page vacuously)."""
    counts = {_page_id(page): len(list(DOCS.parse(page))) for page in PAGES}
    assert counts["README"] >= 4
    assert sum(counts.values()) >= 60, counts
