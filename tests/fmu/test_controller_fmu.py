"""An exported controller as a Co-Simulation FMU (``isolator controller --fmu``): its steps equal the C's and
DiscreteController.step's; the plant's FMU and the controller's stepped by a small master in the contract's
order settle as ``isolator simulate --controller`` does."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from conftest import run_command
from fmu_master import Slave, master_loop, relative_error
from isolator import Simulator, load_scenario
from isolator.fmu import write_fmu
from isolator.simulation.settling import settling_time

pytest.importorskip("fmpy")
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from controllers.feedback import design_controller, write_controller_fmu

pytestmark = pytest.mark.skipif(shutil.which("cc") is None and shutil.which("gcc") is None, reason="no C compiler")

SCENARIO = "paper-table-3-2-geophones"




@pytest.mark.parametrize("delay", [False, True])
def test_each_step_is_the_controllers_step(tmp_path, delay):
    """Random readings and positions through the FMU and through DiscreteController.step: the same commands
    (one sample later with the delay), to rounding."""
    scenario = load_scenario(SCENARIO)
    ctrl = design_controller(scenario, "lqg", 1000.0, delay=delay, schedule=3)
    path = write_controller_fmu(ctrl, tmp_path / "controller.fmu")
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    assert md.modelExchange is None
    assert md.coSimulation is not None
    slave = Slave(path, tmp_path)
    rng = np.random.default_rng(4)
    x, previous = ctrl.reset(), np.zeros(len(ctrl.actuators))
    ys = rng.normal(size=(200, len(ctrl.sensors))) * 1e-5
    qs = rng.uniform(-0.2, 0.3, size=(200, len(ctrl.carriages)))
    for k in range(200):
        slave.set({f"y:{s}": ys[k, i] for i, s in enumerate(ctrl.sensors)}
                  | {f"q:{c}": qs[k, i] for i, c in enumerate(ctrl.carriages)})
        slave.fmu.doStep(currentCommunicationPoint=k / 1000.0, communicationStepSize=1e-3)
        x, u = ctrl.step(x, ys[k], qs[k])
        got = slave.get([f"u:{a}" for a in ctrl.actuators])
        np.testing.assert_allclose(got, previous if delay else u, rtol=1e-12, atol=1e-12 * np.max(np.abs(u)))
        previous = u
    slave.close()


@pytest.fixture(scope="module")
def plant_fmu(tmp_path_factory):
    """The table's FMU, written once for the loops below."""
    return write_fmu(load_scenario(SCENARIO), tmp_path_factory.mktemp("plant") / "table.fmu")


@pytest.mark.parametrize(("method", "delay"), [("skyhook", False), ("skyhook", True), ("lqg", False)])
def test_plant_and_controller_fmus_settle_as_simulate_controller(tmp_path, plant_fmu, method, delay):
    """Skyhook from the geophones at 2 kHz (and with one sample of delay), and LQG, the default (searched)
    designs: the master of the contract's order gives the table's signals within 1e-6 of their peaks of
    ``simulate --controller`` and its settling times. (The command's change at every tick starts a transient
    of the actuators' 200 Hz lag: before the simulator's steps resolved its rate, z was at 1.03e-6 of its peak
    with the skyhook.)"""
    scenario = load_scenario(SCENARIO)
    ctrl = design_controller(scenario, method, 2000.0, delay=delay)
    plant = Slave(plant_fmu, tmp_path, name="plant")
    controller = Slave(write_controller_fmu(ctrl, tmp_path / "controller.fmu"), tmp_path, name="controller")
    response = Simulator(scenario).run(controller=ctrl)
    h = 1.0 / ctrl.sample_rate
    steps = round(scenario.simulation.duration / h)
    signals, sensors = ["x", "y", "z", "rx", "ry", "rz"], [f"s:{s}" for s in ctrl.sensors]
    out = master_loop(plant, controller, ctrl, steps, h, signals + sensors)[:, :6]
    t = np.arange(steps + 1) * h
    for i, name in enumerate(signals):
        got = np.interp(response.t, t, out[:, i])
        assert relative_error(got, response.signals[i]) < 1e-6, name
        # the same settling time, measured by the simulator's rule on the FMUs' samples at the response's times
        rule = response.settling[name]
        time, _ = settling_time(response.t, got, float(response.final[i]), response.stop_time, rule.band)
        assert time == pytest.approx(rule.time, abs=1.5e-3), name


def test_controller_fmu_from_the_command(tmp_path, capsys):
    out = tmp_path / "ctl"
    status, text, err = run_command(["controller", SCENARIO, "--method", "skyhook", "--sample-rate", "2000", "--out",
                                     str(out), "--fmu"], capsys)
    assert status == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["controller.c", "controller.fmu", "controller.h",
                                                      "controller.json"]
    assert validate_fmu(str(out / "controller.fmu")) == []
    assert "FMU: " in text


def test_controller_fmu_without_a_compiler_writes_nothing(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("CC", "no-such-cc")
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    status, _, err = run_command(["controller", SCENARIO, "--method", "skyhook", "--sample-rate", "2000", "--out",
                                  str(tmp_path / "ctl"), "--fmu"], capsys)
    assert status == 2
    assert len(err) == 1
    assert "no C compiler" in err[0]
    assert not any((tmp_path / "ctl").glob("controller.*"))
