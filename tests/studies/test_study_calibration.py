"""The calibration study on the bundled example: the profile optimised on the calibrated model settles sooner on
the true table than the one optimised on the datasheet, and its model predicts it."""

from __future__ import annotations

import pytest

from isolator.cli.app import main
from studies.calibration import run_calibration_study


@pytest.mark.slow
def test_calibration_buys_settling_time_on_the_true_table(tmp_path):
    study = run_calibration_study(tmp_path, progress=False)
    actual = {k: m.settling_time_max for k, m in study.actual.items()}
    assert all(v is not None for v in actual.values()), actual
    assert actual["calibrated"] < 0.8 * actual["datasheet"] < 0.8 * actual["paper"]  # type: ignore[operator]
    predicted = study.predicted["calibrated"].settling_time_max
    assert predicted is not None
    assert abs(predicted - actual["calibrated"]) < 0.05 * actual["calibrated"]  # type: ignore[operator]
    wrong = study.predicted["datasheet"].settling_time_max
    assert wrong is not None
    assert wrong < 0.8 * actual["datasheet"]  # type: ignore[operator]  # the datasheet model promised too much
    for name in ("report.md", "calibration.png", "settling.png", "residual.png"):
        assert (tmp_path / name).stat().st_size > 1000


def test_the_command_refuses_a_bad_fraction(tmp_path, capsys):
    assert main(["study", "calibration", "--out", str(tmp_path), "--fraction", "2"]) == 2
    assert "--fraction" in capsys.readouterr().err
