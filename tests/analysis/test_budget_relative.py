"""``isolator budget --relative A:B``: the random elastic translation of one point relative to another, per
source; zero on a rigid top; on a top that bends, the integral of ``|H_A - H_B|^2 S`` of the linear model's
elastic outputs, computed here on a fine grid of its own."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys

import numpy as np
import pytest
from synthetic_top import with_synthetic_top, without_top_modes

from isolator import linearise
from isolator.analysis.budget import error_budget
from isolator.errors import ParameterError
from isolator.scenario.definitions import Point
from isolator.scenario.random_sources import Disturbance, SpectralDensity


def _scenario():
    base = with_synthetic_top(frequencies=(60.0, 90.0, 120.0))
    psd = SpectralDensity.flat(1e-2)
    force = Disturbance("hammer", (0.5, 0.25, 0.15), (0.0, 0.0, 1.0), psd)
    return dataclasses.replace(base, points=(Point("tool", (0.8, 0.4, 0.15)), Point("part", (0.0, 0.0, 0.15))),
                               disturbances=(force,))


def test_relative_motion_is_the_difference_of_the_elastic_outputs():
    scenario = _scenario()
    budget = error_budget(scenario, relative=["tool:part"], band=(1.0, 500.0))
    got = budget.to_dict()["relative"]["tool:part"]["z"]["rms"]
    lin = linearise(scenario)
    f = np.geomspace(1.0, 500.0, 200_000)
    weights = budget_weights(lin)
    h = lin.frequency_response(f, None, ["tool:ez", "part:ez"]) @ weights  # (nf, 2)
    want = np.sqrt(np.trapezoid(np.abs(h[:, 0] - h[:, 1]) ** 2 * 1e-2, f))
    assert got == pytest.approx(want, rel=2e-3)
    assert got > 1e-3 * budget.value("tool", "z")  # the top's bending is there


def budget_weights(lin):
    from isolator.analysis.elastic_outputs import point_force_weights

    d = lin.scenario.disturbances[0]
    return point_force_weights(lin, d.position, d.direction)


def test_a_rigid_top_has_no_relative_motion():
    budget = error_budget(without_top_modes(_scenario()), relative=["tool:part"])
    assert all(v["rms"] == 0.0 for v in budget.to_dict()["relative"]["tool:part"].values())


@pytest.mark.parametrize("pair", ["tool", "tool:tool", "tool:nope", ":part"])
def test_a_bad_pair_is_named(pair):
    with pytest.raises(ParameterError, match="relative"):
        error_budget(_scenario(), relative=[pair])


def test_the_command_writes_the_pairs_in_json_and_csv(tmp_path):
    out = tmp_path / "b.csv"
    run = subprocess.run([sys.executable, "-m", "isolator.cli", "budget", "paper-table-3-2-budget", "--relative",
                          "probe:lens", "--json", "--out", str(out)], capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stderr
    data = json.loads(run.stdout)
    assert set(data["relative"]["probe:lens"]) == {"x", "y", "z"}
    header = out.read_text().splitlines()[0].split(",")
    assert "probe:lens:z:floor:z" in header
    bad = subprocess.run([sys.executable, "-m", "isolator.cli", "budget", "paper-table-3-2-budget", "--relative",
                          "probe"], capture_output=True, text=True, check=False)
    assert bad.returncode == 2
    assert bad.stderr.count("\n") == 1
    assert "--relative" in bad.stderr
