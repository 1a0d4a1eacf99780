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


@pytest.mark.slow
def test_paper_study_settling_times_are_reproduced_by_simulate(tmp_path, capsys):
    """Each model in its own run's 5 % band, stated in the report; simulate --band reproduces both."""
    import json

    from isolator import Band

    assert main(["study", "paper", "--out", str(tmp_path), "--quick"]) == 0
    capsys.readouterr()
    results = json.loads((tmp_path / "results.json").read_text())
    assert "Settling band: 5 % of each signal's own peak" in (tmp_path / "report.md").read_text()
    for model in ("exact", "paper"):
        band = results[model]["band"]
        assert band["kind"] == "own"
        option = Band.from_dict(band["half_widths"]).option()
        assert main(["simulate", "paper-table-3-2", "--json", "--model", model, "--band", option]) == 0
        data = json.loads(capsys.readouterr().out)
        assert data["settling_time"] == results[model]["settling_time"]
