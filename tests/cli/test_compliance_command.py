"""``isolator compliance``: the contract's JSON and CSV, the default frequencies, one line for bad input; and the
rigid top's curve against the rigid body's mass line ``(1/m + (r x n) . J^-1 (r x n)) / w^2`` far above its
modes (the closed form of a free rigid body, independent of the linear model)."""

from __future__ import annotations

import csv
import dataclasses
import json

import numpy as np
import pytest

from conftest import run_command
from isolator import linearise, load_scenario
from isolator.analysis.point_compliance import point_compliance
from isolator.scenario.definitions import Point


def test_json_csv_and_the_default_frequencies(tmp_path, capsys):
    out = tmp_path / "c.csv"
    status, stdout, stderr = run_command(["compliance", "paper-table-3-2-flexible", "--point", "corner", "--json",
                                          "--out", str(out)], capsys)
    assert status == 0, stderr
    data = json.loads(stdout)
    assert set(data) == {"frequency_hz", "magnitude", "phase_deg"}
    assert len(data["frequency_hz"]) == 2000
    assert data["frequency_hz"][0] == pytest.approx(1.0)
    assert data["frequency_hz"][-1] == pytest.approx(2000.0)
    rows = list(csv.reader(out.open()))
    assert rows[0] == ["frequency_hz", "magnitude", "phase_deg"]
    assert len(rows) == 2001
    assert float(rows[5][1]) == pytest.approx(data["magnitude"][4], rel=1e-15)


@pytest.mark.parametrize(("args", "option"), [
    (["--point", "nowhere"], "--point"),
    (["--point", "corner", "--response", "nowhere"], "--response"),
    (["--point", "corner", "--band", "10:1"], "--band"),
    (["--point", "corner", "--band", "a:b"], "--band"),
    (["--point", "corner", "--count", "1"], "--count"),
])
def test_bad_input_is_one_line_and_writes_nothing(tmp_path, capsys, args, option):
    out = tmp_path / "c.csv"
    status, _, stderr = run_command(["compliance", "paper-table-3-2-flexible", *args, "--out", str(out)], capsys)
    assert status == 2
    assert len(stderr) == 1
    assert option in stderr[0]
    assert not out.exists()


def test_a_rigid_free_body_follows_its_mass_line():
    base = load_scenario("paper-table-3-2")
    r = np.array([0.9, 0.4, 0.15])
    scenario = dataclasses.replace(base, carriages=(), points=(Point("corner", tuple(r)),),
                                   simulation=dataclasses.replace(base.simulation, duration=2.0))
    f = np.array([300.0, 600.0])
    c = point_compliance(linearise(scenario), "corner", "z", frequency_hz=f)
    n = np.array([0.0, 0.0, 1.0])
    arm = np.cross(r, n)
    flexibility = 1 / scenario.table.mass + arm @ (arm / np.asarray(scenario.table.inertia))
    np.testing.assert_allclose(c.magnitude, flexibility / (2 * np.pi * f) ** 2, rtol=2e-3)
    assert np.all(np.abs(np.abs(c.phase_deg) - 180.0) < 2.0)  # a mass: in antiphase
