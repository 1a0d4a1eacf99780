"""The control study's loop formulas against independent computations: the hybrid loop's transmissibility
against the time-varying simulation of a floor sine with the controller in the compiled loop, and the noise
motion against a Monte Carlo run of the sampled loop."""

from __future__ import annotations

import math
import tomllib
from importlib.resources import files

import numpy as np
import pytest

from controllers.feedback import design_controller, sensor_plant
from isolator import Simulator, scenario_from_dict
from isolator.analysis.linear import linearise
from studies.sensor_loops import loop_response, noise_motion

RATE = 2000.0


def _still_table(ground_hz: float | None = None) -> dict:
    text = (files("isolator") / "data" / "scenarios" / "paper-table-3-2-geophones.toml").read_text()
    data = tomllib.loads(text)
    data["carriages"] = []
    data["simulation"] = {"duration": 8.0, "sample_rate": 1000.0}
    if ground_hz is not None:
        data["ground"] = {"z": {"type": "sine", "amplitude": 1e-6, "omega": 2 * math.pi * ground_hz}}
    return data


@pytest.mark.parametrize("method", ["skyhook", "lqg"])
def test_transmissibility_equals_the_simulated_floor_sine(method: str) -> None:
    f0 = 3.0
    scenario = scenario_from_dict(_still_table(f0))
    ctrl = design_controller(scenario, method, RATE)
    run = Simulator(scenario).run(controller=ctrl)
    t, v = run.t, run.sensor("v-z1")
    tail = t > 5.0
    w = 2 * math.pi * f0
    basis = np.column_stack([np.sin(w * t[tail]), np.cos(w * t[tail]), np.ones(tail.sum()), t[tail]])
    coef = np.linalg.lstsq(basis, v[tail], rcond=None)[0]
    measured = math.hypot(coef[0], coef[1]) / (w * 1e-6)  # table velocity per floor velocity
    predicted = loop_response(sensor_plant(linearise(scenario)), ctrl, np.array([f0])).transmissibility[0, 2]
    passive = loop_response(sensor_plant(linearise(scenario)), ctrl, np.array([f0])).passive[0, 2]
    assert measured == pytest.approx(predicted, rel=0.02)
    assert abs(predicted - passive) > 0.2 * passive  # the controller changes it: the check can tell


def test_noise_motion_equals_a_monte_carlo_run_of_the_sampled_loop() -> None:
    scenario = scenario_from_dict(_still_table())
    ctrl = design_controller(scenario, "skyhook", RATE)
    plant = sensor_plant(linearise(scenario))
    exact = noise_motion(plant, ctrl)
    sampled = plant.discrete(RATE)
    a, b, c = (np.asarray(x) for x in (sampled.A, sampled.B, sampled.C))
    ac, bc, cc, dc = ctrl.matrices()
    outputs = list(plant.lin.system.output_labels)
    rows = np.asarray(plant.lin.system.C)[[outputs.index(s) for s in ("z", "rx")]]
    rows = np.hstack([rows, np.zeros((2, a.shape[0] - rows.shape[1]))])
    noise = np.array([s.noise for s in scenario.sensors])
    rng = np.random.default_rng(1)
    x, xc = np.zeros(a.shape[0]), np.zeros(ac.shape[0])
    total, count, forces = np.zeros(2), 0, np.zeros(12)
    for k in range(120_000):
        y = c @ x + noise * rng.standard_normal(noise.size)  # geophones with lagged actuators: no feedthrough
        u = cc @ xc + dc @ y
        x, xc = a @ x + b[:, :12] @ u, ac @ xc + bc @ y
        if k >= 20_000:
            total += (rows @ x) ** 2
            forces += u**2
            count += 1
    rms = np.sqrt(total / count)
    assert rms[0] == pytest.approx(exact.table_rms["z"], rel=0.1)
    assert rms[1] == pytest.approx(exact.table_rms["rx"], rel=0.1)
    np.testing.assert_allclose(np.sqrt(forces / count), exact.force_rms, rtol=0.1)


def test_an_accelerometer_sees_the_floor_as_a_geophone_does() -> None:
    """Floor-to-sensor transmissibility is a ratio of like quantities: accelerometers and geophones at the same
    points give the same passive curve (the floor's improper acceleration term included)."""
    f = np.array([1.0, 5.0, 20.0, 100.0])
    curves = []
    for quantity in ("velocity", "acceleration"):
        data = _still_table()
        for s in data["sensors"]:
            s["quantity"] = quantity
        scenario = scenario_from_dict(data)
        ctrl = design_controller(scenario, "skyhook", RATE, options={"gain": 1e4})
        curves.append(loop_response(sensor_plant(linearise(scenario)), ctrl, f).passive)
    np.testing.assert_allclose(curves[1], curves[0], rtol=1e-9)


def test_the_control_study_leaves_out_a_design_the_sensors_cannot_carry(tmp_path, capsys) -> None:
    """Geophones away from the actuators: skyhook cannot be designed, the study says why and goes on with
    the others."""
    import tomli_w

    from isolator.cli.app import main

    text = (files("isolator") / "data" / "scenarios" / "paper-table-3-2-geophones.toml").read_text()
    data = tomllib.loads(text)
    data["sensors"][0]["position"] = [0.5, 0.2, 0.15]
    path = tmp_path / "moved.toml"
    path.write_text(tomli_w.dumps(data))
    assert main(["study", "control", str(path), "--quick", "--out", str(tmp_path / "out")]) == 0
    out = capsys.readouterr().out
    assert "lqg (sensors): settling" in out
    report = (tmp_path / "out" / "report.md").read_text()
    assert "- skyhook left out: sensors: skyhook needs a table velocity or acceleration sensor collocated" in report
    assert "Default weights chosen by a search" in report  # the chosen weights against the method's own
    row = next(line for line in report.splitlines() if line.startswith("| lqg | max_velocity"))
    searched, own = (float(v) for v in row.split(" | ")[2:4])
    assert searched < own
