"""A sweep that runs longer than 2 s shows how far it has got: a bar in a real pseudo-terminal, one line per
tenth of the designs otherwise; a shorter one shows nothing."""

from __future__ import annotations

import io
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from isolator.sweep.progress import DELAY, Progress

ROOT = Path(__file__).resolve().parents[2]
# about 5 s on a loaded 2-core machine (designs with their modes and transmissibilities, one process)
LONG = ["sweep", "paper-table-3-2", "--scale", "isolators[*].damping=0.5:2:1500", "--modes", "--frequency", "5",
        "--frequency", "50", "--workers", "1"]
SHORT = ["sweep", "paper-table-3-2", "--scale", "isolators[*].damping=0.5:2:4", "--workers", "1"]


def wall_time(summary: str) -> float:
    found = re.search(r"wall time: ([0-9.e+-]+) s", summary)
    assert found, summary
    return float(found.group(1))


def in_a_terminal(argv: list[str]) -> tuple[str, str]:
    """The command with its stderr on a pseudo-terminal: (stdout, what the terminal showed)."""
    import pty

    main, follower = pty.openpty()
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen([sys.executable, "-m", "isolator.cli", *argv], stdout=subprocess.PIPE, stderr=follower,
                            env=env, text=True)
    os.close(follower)
    shown = b""
    while True:
        try:
            chunk = os.read(main, 4096)
        except OSError:  # the terminal closed with the command
            break
        if not chunk:
            break
        shown += chunk
    out, _ = proc.communicate(timeout=120)
    os.close(main)
    assert proc.returncode == 0, shown
    return out, shown.decode(errors="replace")


@pytest.mark.skipif(sys.platform == "win32", reason="needs a pseudo-terminal")
def test_a_long_sweep_shows_a_bar_in_a_terminal_and_a_short_one_nothing(tmp_path):
    out, shown = in_a_terminal([*LONG, "--out", str(tmp_path / "long.csv")])
    if wall_time(out) < DELAY + 0.5:
        pytest.skip("this machine ran the long sweep in under 2.5 s")
    assert "1500/1500" in shown  # tqdm's bar, finished
    assert "run/s" in shown
    assert "\r" in shown
    out, shown = in_a_terminal([*SHORT, "--out", str(tmp_path / "short.csv")])
    assert wall_time(out) < DELAY
    assert shown == ""


def test_a_long_sweep_writes_a_line_per_tenth_elsewhere(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, "-m", "isolator.cli", *LONG, "--out", str(tmp_path / "long.csv")],
                          capture_output=True, text=True, env=env, timeout=120, check=True)
    if wall_time(done.stdout) < DELAY + 0.5:
        pytest.skip("this machine ran the long sweep in under 2.5 s")
    lines = done.stderr.splitlines()
    percents = [int(re.fullmatch(r"isolator sweep: (\d+) % \(\d+ of 1500 designs, [0-9.]+ s\)", line).group(1))
                for line in lines]
    assert percents == sorted(set(percents))
    assert percents[-1] == 100
    assert set(percents) <= {10, 20, 30, 40, 50, 60, 70, 80, 90, 100}


def test_lines_come_after_the_delay_one_per_tenth_from_where_the_sweep_resumed():
    stream = io.StringIO()
    progress = Progress(100, 30, stream, terminal=False, delay=0.0)
    for _ in range(70):
        progress(1)
    progress(-1)
    assert [line.split(" (")[0] for line in stream.getvalue().splitlines()] == [
        f"isolator sweep: {p} %" for p in (40, 50, 60, 70, 80, 90, 100)]
    quiet = io.StringIO()
    waiting = Progress(100, 0, quiet, terminal=False, delay=3600.0)
    waiting(100)
    assert quiet.getvalue() == ""
