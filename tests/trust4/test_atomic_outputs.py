"""Trust round 4 (issue 42), item 9: every output written whole or not at all, a link at the target replaced
(never followed to a file elsewhere, nor a dangling link's target created), and a write that fails one line
naming the option and the file."""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import run_command
from isolator.scenario.output_files import atomic_output, write_output_bytes, write_output_text

BUDGET = "paper-table-3-2-budget"
FIXTURES = [HealthCheck.function_scoped_fixture]


@given(text=st.text(max_size=200), dangling=st.booleans())
@settings(suppress_health_check=FIXTURES, max_examples=30)
def test_a_link_at_the_target_is_replaced_and_what_it_points_at_is_untouched(tmp_path, text, dangling):
    elsewhere = tmp_path / "elsewhere" / f"victim-{dangling}.txt"
    elsewhere.parent.mkdir(exist_ok=True)
    if not dangling:
        elsewhere.write_text("precious")
    link = tmp_path / f"out-{dangling}.txt"
    link.unlink(missing_ok=True)
    link.symlink_to(elsewhere)
    write_output_text(link, text)
    assert not link.is_symlink()
    assert link.read_bytes() == text.encode()
    if dangling:
        assert not elsewhere.exists()
    else:
        assert elsewhere.read_text() == "precious"


@given(old=st.binary(max_size=100), new=st.binary(min_size=1, max_size=100))
@settings(suppress_health_check=FIXTURES, max_examples=20)
def test_a_write_that_fails_midway_leaves_the_old_file_and_no_temporary(tmp_path, old, new):
    target = tmp_path / "kept.bin"
    target.write_bytes(old)
    def crash() -> None:
        with atomic_output(target, "wb") as handle:
            handle.write(new)
            raise RuntimeError("crash")

    with pytest.raises(RuntimeError):
        crash()
    assert target.read_bytes() == old
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept.bin"]


def test_a_replaced_file_keeps_its_permissions(tmp_path):
    target = tmp_path / "r.csv"
    target.write_text("old")
    target.chmod(0o640)
    write_output_bytes(target, b"new")
    assert stat.S_IMODE(target.stat().st_mode) == 0o640


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="no /dev/full")
def test_a_full_device_is_an_error_naming_it():
    with pytest.raises(OSError) as error:
        write_output_text("/dev/full", "x" * 100_000)
    assert error.value.errno == errno.ENOSPC
    assert error.value.filename == "/dev/full"


def test_budget_out_and_plot_replace_links_instead_of_following_them(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    victim = tmp_path / "victim.csv"
    victim.write_text("precious")
    Path("b.csv").symlink_to(victim)
    Path("b.png").symlink_to(tmp_path / "nowhere" / "made.png")
    status, _, err = run_command(["budget", BUDGET, "--out", "b.csv", "--plot", "b.png"], capsys)
    assert status == 0, err
    assert victim.read_text() == "precious"
    assert not (tmp_path / "nowhere").exists()
    for name in ("b.csv", "b.png"):
        assert not Path(name).is_symlink()
        assert Path(name).stat().st_size > 0
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]


@pytest.mark.skipif(os.geteuid() != 0, reason="making a device node needs root")
def test_a_full_disk_at_out_is_one_line_naming_the_option_and_the_file(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    os.mknod("full.csv", stat.S_IFCHR | 0o666, os.makedev(1, 7))  # a /dev/full with a .csv name
    status, _, err = run_command(["budget", BUDGET, "--out", "full.csv"], capsys)
    assert status == 2
    assert err == ["isolator: error: --out full.csv: No space left on device"]
