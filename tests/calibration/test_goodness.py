"""The goodness-of-fit test of a calibration: a fit that does not explain its records is refused (exit status 3,
nothing written) naming the experiment, its ratio and the likely cause; the bundled example passes it."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from conftest import run_command
from isolator.calibration import calibrate
from isolator.calibration.definition import bundled_calibrations
from isolator.calibration.experiments import noise_estimate
from isolator.calibration.goodness import NOISE_ESTIMATE_SPREAD
from isolator.errors import MisfitError

EXAMPLE = Path(bundled_calibrations()["table-3-2"]).parent


def _move_only(folder: Path, change=None, name: str = "move.csv") -> Path:
    """The bundled example's move experiment alone, its record changed column by column by ``change(name, col)``."""
    header = (EXAMPLE / "move.csv").read_text().splitlines()[0].split(",")
    data = np.loadtxt(EXAMPLE / "move.csv", delimiter=",", skiprows=1)
    if change is not None:
        data = np.column_stack([change(n, data[:, i]) for i, n in enumerate(header)])
    folder.mkdir(parents=True, exist_ok=True)
    np.savetxt(folder / name, data, delimiter=",", header=",".join(header), comments="", fmt="%.10g")
    path = folder / "calibration.toml"
    fit = ", ".join(f'"isolators[*].{q}.{a}"' for q in ("stiffness", "damping") for a in "xyz")
    path.write_text(f'scenario = {json.dumps(str(EXAMPLE / "table.toml"))}\nfit = [{fit}]\n\n'
                    f'[[experiments]]\nname = "move"\nfile = "{name}"\nkind = "move"\n')
    return path


def test_noise_estimate_spread_matches_monte_carlo():
    """The relative spread of the move's noise estimate the test's degrees of freedom rest on."""
    rng = np.random.default_rng(3)
    n = 3000
    estimates = np.array([noise_estimate(rng.standard_normal(n)) for _ in range(600)])
    assert abs(estimates.mean() - 1) < 0.005
    assert estimates.std() * math.sqrt(n) == pytest.approx(NOISE_ESTIMATE_SPREAD, rel=0.1)


def test_the_bundled_example_passes_comfortably():
    """Both experiments' ratios at least two of the ratio's standard deviations below their limit."""
    result = calibrate("table-3-2")
    assert result.fit_ok
    for name, g in result.goodness.items():
        assert g.ok, g
        assert g.ratio < g.limit - 2 * math.sqrt(2 / g.dof), g
        assert 1.0 < g.limit < 1.1
        data = result.to_dict()["experiments"][name]
        assert data["fit_ok"] is True
        assert data["fit_ratio"] == g.ratio
    assert result.to_dict()["fit_ok"] is True


def test_records_in_mm_per_s2_are_refused_naming_the_unit(tmp_path, capsys):
    path = _move_only(tmp_path, lambda n, c: c * 1000 if n != "t" else c)
    out = tmp_path / "new" / "fitted.toml"
    status, stdout, err = run_command(["calibrate", str(path), "--out", str(out)], capsys)
    assert status == 3
    assert len(err) == 1
    assert stdout == ""
    assert "experiment 'move' (move.csv)" in err[0]
    assert "about 1000 times the model's: mm/s^2?" in err[0]
    ratio = float(err[0].split("weighted residual variance ")[1].split(" ")[0])
    assert ratio > 1000  # the residual stays at about 100 RMS
    assert not out.exists()
    assert not out.parent.exists()
    status, stdout, err = run_command(["calibrate", str(path), "--out", str(out), "--json", "--accept-misfit"],
                                      capsys)
    assert status == 0
    data = json.loads(stdout)
    assert data["fit_ok"] is False
    assert data["experiments"]["move"]["fit_ok"] is False
    assert data["experiments"]["move"]["fit_ratio"] == pytest.approx(ratio, rel=1e-2)
    assert out.exists()
    assert any("does not explain" in line for line in err)  # the warning still says so


def test_a_fit_of_too_few_parameters_is_refused_with_its_ratio():
    """Four of the six parameters fitted: the others stay 15-30 % off and the residual cannot reach the noise."""
    names = ["isolators[*].stiffness.z", "isolators[*].damping.z", "isolators[*].stiffness.x",
             "isolators[*].damping.x"]
    with pytest.raises(MisfitError, match=r"experiment 'move' \(move.csv\): weighted residual variance") as info:
        calibrate("table-3-2", fit=names)
    result = info.value.result
    assert not result.fit_ok
    g = result.goodness["move"]
    assert g.ratio > 10 * g.limit
    assert f"{g.ratio:.3g}" in str(info.value)


def test_a_flipped_sensor_is_named(tmp_path):
    path = _move_only(tmp_path, lambda n, c: -c if n == "a1-z" else c)
    with pytest.raises(MisfitError, match=r"a1-z misfits most; a1-z reads about -1 times the model's: its direction "
                                          r"flipped\?"):
        calibrate(path)
