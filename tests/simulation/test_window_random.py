"""``[[windows]] random = K`` (issue 32): windows narrowed by K sigma of the budgeted random motion."""

from __future__ import annotations

import copy
import json
import subprocess
import sys

import pytest

from conftest import base_dict, make
from isolator import simulate
from isolator.analysis.budget import error_budget
from isolator.errors import ScenarioError


def windowed(translation: float, random: float | None, axes: tuple[str, ...] = ("z",)) -> dict:
    data = base_dict()
    data["simulation"]["duration"] = 8.0
    data["points"] = [{"name": "probe", "position": [0.3, 0.0, 0.5]}]
    window = {"point": "probe", "translation": translation, "axes": list(axes)}
    if random is not None:
        window["random"] = random
    data["windows"] = [window]
    data["ground"] = {"spectrum": {"vc": "VC-G"}}
    return data


def test_a_random_window_settles_as_the_window_narrowed_by_k_sigma():
    k = 2.5
    scenario = make(windowed(2e-6, k))
    sigma = error_budget(scenario, points=["probe"]).value("probe", "z")
    response = simulate(scenario)
    out = response.to_dict()
    assert out["window_random"] == [{"z": pytest.approx(k * sigma, rel=1e-12)}]
    narrowed = simulate(make(windowed(2e-6 - k * sigma, None)))
    assert response.window_settling_time == narrowed.window_settling_time
    assert response.window_settling_time[0] > simulate(make(windowed(2e-6, None))).window_settling_time[0]
    assert "window_random" not in narrowed.to_dict()


def test_a_window_the_random_motion_fills_is_refused_naming_it():
    data = windowed(2e-6, 1e3, ("x", "z"))
    with pytest.raises(ScenarioError, match=r"windows\[0\]: the random motion alone fills it on x: 1000 sigma = "):
        simulate(make(data))
    data = windowed(2e-6, 2.0)
    del data["ground"]
    with pytest.raises(ScenarioError, match=r"windows\[0\]\.random: the scenario has no random source"):
        simulate(make(data))


@pytest.mark.parametrize("value", [0, -1.0, "3"])
def test_bad_random_names_the_key(value):
    data = windowed(2e-6, 1.0)
    data["windows"][0]["random"] = value
    with pytest.raises(ScenarioError, match=r"windows\[0\]\.random: must be"):
        make(copy.deepcopy(data))


def test_the_command_refuses_a_filled_window_in_one_line(tmp_path):
    import tomli_w

    path = tmp_path / "filled.toml"
    path.write_text(tomli_w.dumps(windowed(2e-6, 1e3)))
    out = tmp_path / "r.csv"
    run = subprocess.run([sys.executable, "-m", "isolator.cli", "simulate", str(path), "--out", str(out), "--json"],
                         capture_output=True, text=True, check=False)
    assert run.returncode == 2
    assert run.stderr.strip().count("\n") == 0
    assert "windows[0]: the random motion alone fills it" in run.stderr
    assert not out.exists()
    run = subprocess.run([sys.executable, "-m", "isolator.cli", "budget", str(path), "--json"],
                         capture_output=True, text=True, check=True)
    assert json.loads(run.stdout)["points"]["probe"]["z"]["rms"] > 0
