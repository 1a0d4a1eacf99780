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


def test_a_sequence_waits_for_the_narrowed_window():
    """``run_sequence`` (and so sweeps and sequence design) settles each step into the window less K sigma: the
    same steps as a sequence whose window is that much narrower, and ``window_random`` in its JSON."""
    from isolator import run_sequence

    data = base_dict(points=[{"name": "probe", "position": [0.3, 0.0, 0.45]}])
    carriage = data["carriages"][0]
    del carriage["profile"]
    carriage["limits"] = {"velocity": 0.2, "acceleration": 0.5, "jerk": 5.0}
    data["sequence"] = {"measure": 0.2, "start": 0.3, "initial": {"x-stage": -0.2},
                        "steps": [{"x-stage": 0.1}, {"x-stage": 0.0}]}
    data["simulation"] = {"duration": 30.0, "sample_rate": 1000.0}
    data["disturbances"] = [{"name": "air", "position": [0.0, 0.0, 0.15], "direction": [0.0, 0.0, 1.0],
                             "psd": 1e-4}]  # sigma ~ 22 nm at the probe
    data["windows"] = [{"point": "probe", "translation": 2e-7, "axes": ["z"], "random": 3.0}]
    scenario = make(copy.deepcopy(data))
    sigma = error_budget(scenario, points=["probe"]).value("probe", "z")
    assert 0.05 < 3 * sigma / 2e-7 < 0.8  # a margin that matters, not one that fills the window
    result = run_sequence(scenario)
    assert result.to_dict()["window_random"] == [{"z": pytest.approx(3 * sigma, rel=1e-12)}]
    data["windows"] = [{"point": "probe", "translation": 2e-7 - 3 * sigma, "axes": ["z"]}]
    narrowed = run_sequence(make(data))
    assert [s.settled for s in result.steps] == [s.settled for s in narrowed.steps]
    data["windows"][0]["translation"] = 2e-7
    wide = run_sequence(make(data))
    assert result.steps[0].settled > wide.steps[0].settled
