"""Output-feedback designs from the sensors (skyhook, LQG, H-infinity), each checked by a property of the
design that its own construction does not assume."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from conftest import active_dict, make
from controllers.feedback import design_controller, design_positions, hinf_design, lqg_design, skyhook_design
from controllers.feedback.output_designs import loop_damping, noise_model
from controllers.feedback.sensor_plant import loop_matrix, sensor_plant
from isolator import load_scenario
from isolator.analysis.linear import linearise
from isolator.errors import ParameterError, ScenarioError

RATE = 2000.0


def geophone_dict(bandwidth: float | None = 200.0, quantity: str = "velocity") -> dict[str, Any]:
    """The test's active table with a sensor collocated with every actuator."""
    data = active_dict(bandwidth=bandwidth)
    data["sensors"] = [{"name": f"s-{a['name']}", "on": "table", "position": a["position"],
                        "direction": a["direction"], "quantity": quantity, "noise": 3e-8}
                       for a in data["actuators"]]
    return data


@pytest.fixture(scope="module")
def plant():
    return sensor_plant(linearise(load_scenario("paper-table-3-2-geophones")))


def test_sensor_plant_matches_the_linear_model_without_lag() -> None:
    """Without actuator lag the sensor plant's response to the actuators is the linear model's own."""
    lin = linearise(make(geophone_dict(bandwidth=None)))
    p = sensor_plant(lin)
    f = np.array([0.5, 3.0, 20.0])
    names = [f"actuator:{a.name}" for a in lin.scenario.actuators]
    ours = np.stack([np.asarray(p.system(2j * math.pi * x))[:, :len(names)] for x in f])
    theirs = lin.frequency_response(f, names, [f"s:{s.name}" for s in lin.scenario.sensors])
    np.testing.assert_allclose(ours, theirs, rtol=1e-9, atol=1e-15)


def test_sampled_plant_equals_stepping_the_continuous_one(plant) -> None:
    """The zero-order-hold plant equals the continuous plant integrated finely over a held command; with the
    delay, the command acts one sample later."""
    from scipy.integrate import solve_ivp

    a, b, c, _ = plant.matrices()
    u = np.zeros(b.shape[1])
    u[2] = 100.0  # z1 pushes 100 N
    d = plant.discrete(RATE)
    x1 = np.asarray(d.A) @ np.zeros(a.shape[0]) + np.asarray(d.B) @ u
    sol = solve_ivp(lambda t, x: a @ x + b @ u, (0, 1 / RATE), np.zeros(a.shape[0]), rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(x1, sol.y[:, -1], rtol=1e-8, atol=1e-16)
    dd = plant.discrete(RATE, delay=True)
    z1 = np.asarray(dd.B) @ u  # one sample later the command has only entered the delay states
    assert np.allclose(np.asarray(dd.C) @ z1, 0.0)
    z2 = np.asarray(dd.A) @ z1
    np.testing.assert_allclose(np.asarray(dd.C) @ z2, c @ x1, rtol=1e-9)


def test_skyhook_is_collocated_high_passed_and_damps_most(plant) -> None:
    design = skyhook_design(plant, RATE)
    # each actuator hears only its own geophone, with the opposite sign (a damper)
    static = design.C @ np.linalg.solve(np.eye(design.A.shape[0]) - design.A, design.B) + design.D
    np.testing.assert_allclose(static, 0.0, atol=1e-6 * design.settings["gain"])  # the high-pass: no DC
    hf = design.D  # at high frequency the filter passes: -c on the diagonal
    np.testing.assert_allclose(hf, -np.diag(np.diag(-hf)), atol=1e-12)
    assert np.all(np.diag(hf) < 0)
    # the gain chosen is a local optimum of the least damping of the sampled loop
    sampled = plant.discrete(RATE)
    g = design.settings["gain"]

    def zeta(factor: float) -> float:
        return loop_damping(loop_matrix(sampled, (design.A, factor * design.B, design.C, factor * design.D)),
                            RATE)[1]

    assert zeta(1.0) >= max(zeta(0.7), zeta(1.4)) - 1e-9
    assert zeta(1.0) > 0.3 > loop_damping(np.asarray(sampled.A), RATE)[1]
    assert g > 0


def test_skyhook_needs_collocated_geophones() -> None:
    data = geophone_dict()
    data["sensors"][4]["position"] = [0.0, 0.0, 0.0]
    p = sensor_plant(linearise(make(data)))
    with pytest.raises(ScenarioError, match="collocated with actuator 'y1'"):
        skyhook_design(p, RATE)


def test_skyhook_from_accelerometers_integrates() -> None:
    """Accelerometers: the loop filter is the high-pass times 1/s, so the loop still damps."""
    p = sensor_plant(linearise(make(geophone_dict(quantity="acceleration"))))
    design = skyhook_design(p, RATE)
    radius, zeta = loop_damping(loop_matrix(p.discrete(RATE), design.matrices), RATE)
    assert radius < 1
    assert zeta > 0.3


def test_lqg_obeys_the_separation_principle(plant) -> None:
    """The loop's poles are the regulator's and the filter's, computed here from the design's gains."""
    from scipy.linalg import solve_discrete_are

    design = lqg_design(plant, RATE)
    sampled = plant.discrete(RATE)
    ad, b, cy = np.asarray(sampled.A), np.asarray(sampled.B), np.asarray(sampled.C)
    bu = b[:, :12]
    n = ad.shape[0]
    cz = np.zeros((6, n))
    cz[np.arange(6), 6 + np.arange(6)] = 1.0 / 1e-2
    r = np.eye(12) / 500.0**2
    s = solve_discrete_are(ad, bu, cz.T @ cz, r)
    k = np.linalg.solve(r + bu.T @ s @ bu, bu.T @ s @ ad)
    mk = noise_model(plant, sampled).gain
    expected = np.concatenate([np.linalg.eigvals(ad - bu @ k), np.linalg.eigvals(ad - ad @ mk @ cy)])
    got = np.linalg.eigvals(loop_matrix(sampled, design.matrices))
    for z in expected:
        assert np.min(np.abs(got - z)) < 1e-6
    # the filter forgets a position estimate no slower than the washout
    rate = 2 * math.pi * design.settings["washout_hz"] / RATE
    assert np.max(np.abs(np.linalg.eigvals(ad - ad @ mk @ cy))) <= math.exp(-0.95 * rate)


def test_lqg_with_delay_stabilises_the_delayed_plant(plant) -> None:
    design = lqg_design(plant, RATE, delay=True)
    assert design.A.shape[0] == plant.discrete(RATE, True).nstates
    radius, zeta = loop_damping(loop_matrix(plant.discrete(RATE, True), design.matrices), RATE)
    assert radius < 1
    assert zeta > 0.3


@pytest.mark.parametrize("delay", [False, True])
def test_hinf_achieves_its_norm(plant, delay: bool) -> None:
    """The sampled loop's H-infinity norm from the normalised disturbances to the normalised performance
    outputs, evaluated on a frequency grid to Nyquist, is at most the design's gamma (and it is near the
    optimum: above gamma / relax)."""
    design = hinf_design(plant, RATE, delay)
    sampled = plant.discrete(RATE, delay)
    model = noise_model(plant, sampled)
    m, p = 12, 12
    ad, b, cy, d = (np.asarray(x) for x in (sampled.A, sampled.B, sampled.C, sampled.D))
    n = ad.shape[0]
    lowest = float(np.min(np.abs(plant.lin.eigenvalues)))
    noise = np.maximum(model.noise, 0.1 * 1e-2 * np.ones(p) * lowest ** 0)
    walk = np.zeros((n, 6))
    walk[np.arange(6), np.arange(6)] = model.walk
    b1 = np.hstack([b[:, m + 6:] * model.wrench, walk, np.zeros((n, p))])
    d21 = np.hstack([d[:, m + 6:] * model.wrench, np.zeros((p, 6)), np.diag(noise)])
    c1 = np.zeros((6, n))
    c1[np.arange(6), 6 + np.arange(6)] = 100.0
    ac, bc, cc, dc = design.matrices
    big = loop_matrix(sampled, design.matrices)
    e = np.linalg.inv(np.eye(m) - dc @ d[:, :m])
    # closed loop from w: u = E (Dc (Cy x + D21 w) + Cc xc)
    bw = np.vstack([b1 + b[:, :m] @ e @ dc @ d21, bc @ (d21 + d[:, :m] @ e @ dc @ d21)])
    cz = np.vstack([np.hstack([c1, np.zeros((6, ac.shape[0]))]),
                    np.diag(1 / 500.0 * np.ones(m)) @ np.hstack([e @ dc @ cy, e @ cc])])
    dz = np.vstack([np.zeros((6, bw.shape[1])), np.diag(1 / 500.0 * np.ones(m)) @ e @ dc @ d21])
    worst = 0.0
    for w in np.concatenate([np.linspace(0.0, 0.2, 400), np.linspace(0.2, math.pi, 200)]):
        h = cz @ np.linalg.solve(np.exp(1j * w) * np.eye(big.shape[0]) - big, bw) + dz
        worst = max(worst, float(np.linalg.norm(h, 2)))
    assert worst <= design.settings["gamma"] * 1.001
    assert worst >= design.settings["optimal_gamma"] * 0.9


def test_design_positions_schedule_the_heaviest_stroke() -> None:
    scenario = load_scenario("paper-table-3-2-geophones")
    points, index = design_positions(scenario, 5)
    assert index == 0  # x-stage carries 440 kg over 1.4 m; y-stage 40 kg over 0.6 m
    np.testing.assert_allclose(points[:, 0], np.linspace(-0.7, 0.7, 5))
    np.testing.assert_allclose(points[:, 1], 0.0)
    middle, _ = design_positions(scenario)
    np.testing.assert_allclose(middle, [[0.0, 0.0]])
    points, index = design_positions(scenario, 3, "y-stage")
    assert index == 1
    assert np.allclose(points[:, 1], [-0.3, 0.0, 0.3])


def test_scheduled_lqg_is_each_point_design_at_its_point() -> None:
    scenario = load_scenario("paper-table-3-2-geophones")
    ctrl = design_controller(scenario, "lqg", RATE, schedule=3, search=False)
    assert len(ctrl.schedule) == 3
    plant_end = sensor_plant(linearise(scenario, positions=[0.7, 0.0]))
    end = lqg_design(plant_end, RATE)
    for got, want in zip(ctrl.matrices([0.7, -0.3]), end.matrices, strict=True):
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12 * np.max(np.abs(want)))
    # between the points the interpolated controller still holds the loop, at the plant there
    plant_q = sensor_plant(linearise(scenario, positions=[0.35, 0.0])).discrete(RATE)
    assert loop_damping(loop_matrix(plant_q, ctrl.matrices([0.35, 0.0])), RATE)[0] < 1


def test_design_refusals() -> None:
    scenario = load_scenario("paper-table-3-2-geophones")
    with pytest.raises(ParameterError, match=r"--sample-rate.*below twice the table's highest mode"):
        design_controller(scenario, "lqg", 5.0)
    with pytest.raises(ParameterError, match=r"schedule.*H-infinity"):
        design_controller(scenario, "hinf", RATE, schedule=3)
    with pytest.raises(ParameterError, match="method: must be one of skyhook, lqg, hinf"):
        design_controller(scenario, "pid", RATE)
    with pytest.raises(ParameterError, match="lqg has no setting 'gain'"):
        design_controller(scenario, "lqg", RATE, options={"gain": 1.0})
    with pytest.raises(ParameterError, match="schedule_carriage: no carriage named 'z-stage'"):
        design_controller(scenario, "lqg", RATE, schedule=2, schedule_carriage="z-stage")
    no_sensors = make(active_dict())
    with pytest.raises(ScenarioError, match=r"sensors: the lqg design feeds back the scenario's \[\[sensors\]\]"):
        design_controller(no_sensors, "lqg", RATE)


def test_accelerometer_readings_are_the_left_limit() -> None:
    """An accelerometer beside an actuator without lag: the reading at t_k sees the command applied before
    t_k (as the simulation and a real sampler take it), one sample later than the command itself."""
    p = sensor_plant(linearise(make(geophone_dict(bandwidth=None, quantity="acceleration"))))
    for delay, lag in ((False, 1), (True, 2)):
        d = p.discrete(RATE, delay)
        a, b, c, dd = (np.asarray(x) for x in (d.A, d.B, d.C, d.D))
        assert np.all(dd[:, :12] == 0)
        u = np.zeros(b.shape[1])
        u[2] = 100.0
        z = b @ u
        readings = []
        for _ in range(3):
            readings.append(c @ z)
            z = a @ z
        assert abs(readings[lag - 1][2]) > 1e-3  # the 100 N step read lag samples after it is commanded
        assert all(np.allclose(r, 0) for r in readings[: lag - 1])


def test_lqg_from_accelerometers_without_lag_runs_as_checked() -> None:
    """The design and the check see the reading as the simulation does: the run settles within the limits
    (with the reading taken at the right limit the design was unstable in the simulation)."""
    from isolator import Simulator

    data = geophone_dict(bandwidth=None, quantity="acceleration")
    data["simulation"] = {"duration": 4.0, "sample_rate": 1000.0}
    scenario = make(data)
    ctrl = design_controller(scenario, "lqg", 1000.0, delay=True)
    run = Simulator(scenario).run(controller=ctrl)
    assert np.abs(run.actuator_forces).max() < 0.5 * 500.0
    assert run.settling_time_max is not None


def test_pneumatic_tables_get_skyhook_and_a_clear_refusal_otherwise() -> None:
    """A pneumatic table's held air (poles at zero no actuator reaches) neither sets the geophone corner nor
    counts against the loop; the model-based designs refuse it in one line."""
    from importlib.resources import files

    text = (files("isolator") / "data" / "scenarios" / "paper-table-3-2-geophones.toml").read_text()
    sensors = text[text.index("[[sensors]]"):text.index("[simulation]")]
    pneumatic = (files("isolator") / "data" / "scenarios" / "paper-table-3-2-pneumatic-active.toml").read_text()
    cut = pneumatic.index("[simulation]")
    import tomllib

    from isolator import scenario_from_dict

    scenario = scenario_from_dict(tomllib.loads(pneumatic[:cut] + sensors + pneumatic[cut:]))
    plant = sensor_plant(linearise(scenario))
    assert plant.held_air > 0
    design = skyhook_design(plant, RATE)
    assert design.settings["highpass_hz"] > 0.1
    radius, zeta = loop_damping(loop_matrix(plant.discrete(RATE), design.matrices), RATE, plant.held_air)
    assert radius < 1
    assert zeta > 0.2
    for method in ("lqg", "hinf"):
        with pytest.raises(ParameterError, match=f"method: {method} cannot be designed on a pneumatic table"):
            design_controller(scenario, method, RATE)


def test_more_refusals() -> None:
    scenario = load_scenario("paper-table-3-2-geophones")
    data = geophone_dict()
    for s in data["sensors"]:
        s["on"] = "floor"
    with pytest.raises(ScenarioError, match=r"every one of the scenario's .* is on the floor"):
        design_controller(make(data), "lqg", RATE)
    with pytest.raises(ParameterError, match=r"--sample-rate.*1234 Hz cannot be simulated with this scenario"):
        design_controller(scenario, "lqg", 1234.0)
    with pytest.raises(ParameterError, match=r"--schedule-carriage.*give --schedule N with N >= 2"):
        design_controller(scenario, "lqg", RATE, schedule_carriage="y-stage")


def test_a_schedule_is_checked_between_its_design_points() -> None:
    from controllers.feedback import check_robustness

    scenario = load_scenario("paper-table-3-2-geophones")
    ctrl = design_controller(scenario, "skyhook", RATE, schedule=3, options={"gain": 2e4})
    report = check_robustness(scenario, ctrl, margins=False)
    checked = {round(c.positions[0], 9) for c in report.cases}
    assert {-0.35, 0.35} <= checked  # halfway between -0.7, 0 and 0.7
