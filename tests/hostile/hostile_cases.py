"""What every hostile-input test asserts about a command that refuses its input (issue 35).

``refused(argv, capsys)`` runs ``isolator argv`` in-process in the current (empty, per test) working folder
and checks the contract for an input the toolkit did not write itself: exit status 2, exactly one line on
stderr starting ``isolator: error:``, no control character in it (escaped), no traceback, no file or folder
written, no process left running; it returns the line for the test's own checks (the key it names, no file
content).
"""

from __future__ import annotations

import multiprocessing
import os
from pathlib import Path

import pytest

from isolator.cli.app import main
from isolator.scenario.names import EXCERPT

BASE = Path(__file__).resolve().parents[1] / "bad_inputs" / "base.toml"


def tree(folder: Path) -> set[str]:
    """Every path under ``folder`` (relative)."""
    return {str(p.relative_to(folder)) for p in folder.rglob("*")}


def children() -> set[int]:
    """The process ids of this process's children now (Linux: /proc), else multiprocessing's."""
    found: set[int] = set()
    task = Path(f"/proc/{os.getpid()}/task")
    if task.is_dir():
        for thread in task.iterdir():
            text = (thread / "children").read_text() if (thread / "children").exists() else ""
            found.update(int(pid) for pid in text.split())
        return found
    return {p.pid for p in multiprocessing.active_children() if p.pid is not None}


def refused(argv: list[str], capsys: pytest.CaptureFixture[str], status: int = 2) -> str:
    """Run ``isolator argv`` here; assert the refusal contract; the error line (without its prefix)."""
    here = Path.cwd()
    before, procs = tree(here), children()
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's own exits
        code = int(exc.code or 0)
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    assert code == status, (code, lines)
    assert len(lines) == 1, lines
    line = lines[0]
    assert line.startswith("isolator: error: "), line
    assert "Traceback" not in captured.err
    assert line.isprintable(), line  # control characters escaped
    assert tree(here) == before, "a refused command wrote something"
    assert children() <= procs, "a refused command left a process running"
    return line.removeprefix("isolator: error: ")


def quotes_no_line_of(message: str, text: str) -> None:
    """No line (nor any run of more than EXCERPT characters of one) of ``text`` appears in ``message``."""
    for line in text.splitlines():
        line = line.strip()
        if len(line) > EXCERPT:
            for start in range(len(line) - EXCERPT):
                assert line[start:start + EXCERPT + 1] not in message, (line, message)
