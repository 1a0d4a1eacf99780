"""The paper study writes its figures and a report with the numbers it claims."""

from __future__ import annotations

import re

import pytest

from isolator.cli.app import main


@pytest.mark.slow
def test_paper_study_quick(tmp_path, capsys):
    pytest.importorskip("mujoco")
    assert main(["study", "paper", "--out", str(tmp_path), "--quick"]) == 0
    for name in ("fig_3_3.png", "fig_3_4.png", "fig_3_5.png"):
        assert (tmp_path / name).stat().st_size > 20_000
    report = (tmp_path / "report.md").read_text()
    assert "| **largest** |" in report
    # the exact model agrees with the multibody check far better than the paper model does
    rows = re.findall(r"\| Table 3\.1 \| (\w+) \| ([0-9.e+-]+) \| ([0-9.e+-]+) \|", report)
    assert {r[0] for r in rows} == {"x", "z", "ry"}
    for _, exact, paper in rows:
        assert float(exact) < 1e-6 < float(paper)
