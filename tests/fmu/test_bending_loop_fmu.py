"""The controller FMU's loop on a bending top (issue 41, "everything closed-loop sees the modes"): the plant FMU of a
scenario with ``[table.flexible]`` (``isolator fmu``) and an exported controller's FMU (``isolator controller
--fmu``), stepped by a master in the contract's order, run the loop with the top's elastic modes:

* a default design equals ``simulate --controller`` on the same bending scenario within 1e-6 of the peaks;
* a stiff skyhook made on the rigid top, which ``check-controller`` refuses on the bending one (its growing mode a
  plate mode at 441 Hz), grows in the FMUs' loop at the check's rate and frequency, and decays in the rigid
  top's FMU: a loop that ignored the modes would not grow.
"""

from __future__ import annotations

import math
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from controllers.feedback import design_controller, write_controller_fmu
from isolator import Simulator, load_scenario
from isolator.analysis.closed_loop import check_controller
from isolator.fmu import write_fmu

pytest.importorskip("fmpy")
from fmpy import read_model_description

from fmu_master import Slave, master_loop, relative_error

pytestmark = pytest.mark.skipif(shutil.which("cc") is None and shutil.which("gcc") is None, reason="no C compiler")

SCENARIOS = Path(__file__).parents[2] / "isolator" / "data" / "scenarios"
RATE = 2000.0


def _scenario(folder: Path, bending: bool):
    """The geophones table (rigid, or on the bundled top's six lowest elastic modes), a short move of both
    carriages, a 0.4 s run, actuators that do not clip (a growing oscillation stays linear)."""
    text = (SCENARIOS / "paper-table-3-2-geophones.toml").read_text()
    text = text.replace("stroke = 1.4, velocity = 0.2, acceleration = 0.5, t0 = 0.5",
                        "stroke = 0.005, velocity = 0.2, acceleration = 0.5, t0 = 0.02")
    text = text.replace("stroke = 0.6, velocity = 0.083, acceleration = 0.5, t0 = 0.5",
                        "stroke = 0.002, velocity = 0.083, acceleration = 0.5, t0 = 0.02")
    text = re.sub(r"^duration = .*$", "duration = 0.4", text, count=1, flags=re.M)
    text = re.sub(r"^sample_rate = .*$", "sample_rate = 8000.0", text, count=1, flags=re.M)
    text = text.replace("max_force = 500.0", "max_force = 1.0e9")
    if bending:
        modes = (SCENARIOS / "paper-table-3-2-top-modes.csv").as_posix()
        text = text.replace("\n[[isolators]]", f'\n[table.flexible]\nmodes = "{modes}"\ncount = 6\ndamping = 0.01\n'
                            "\n[[isolators]]", 1)
    path = folder / f"geophones-{'bending' if bending else 'rigid'}.toml"
    path.write_text(text)
    return load_scenario(path)


@pytest.fixture(scope="module")
def tables(tmp_path_factory):
    """Each top's scenario and plant FMU."""
    folder = tmp_path_factory.mktemp("tables")
    out = {}
    for bending in (False, True):
        scenario = _scenario(folder, bending)
        out[bending] = scenario, write_fmu(scenario, folder / f"{'bending' if bending else 'rigid'}.fmu")
    return out


def _loop(plant_fmu: Path, ctrl, duration: float, tmp: Path) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """The plant's and the controller's FMUs in the contract's master order at the controller's rate: times,
    outputs (the six table signals, then the sensors) and their names."""
    plant = Slave(plant_fmu, tmp, name="plant")
    controller = Slave(write_controller_fmu(ctrl, tmp / "controller.fmu"), tmp, name="controller")
    h = 1.0 / ctrl.sample_rate
    steps = round(duration / h)
    names = ["x", "y", "z", "rx", "ry", "rz", *(f"s:{s}" for s in ctrl.sensors)]
    out = master_loop(plant, controller, ctrl, steps, h, names)
    return np.arange(steps + 1) * h, out, names


def _envelope(t: np.ndarray, y: np.ndarray, f: float, window: float) -> tuple[np.ndarray, np.ndarray]:
    """Complex demodulation at ``f`` [Hz], averaged over ``window`` s: the oscillation's complex amplitude."""
    n = max(1, round(window / (t[1] - t[0])))
    kernel = np.ones(n) / n
    return np.convolve(t, kernel, mode="valid"), np.convolve(y * np.exp(-2j * math.pi * f * t), kernel, mode="valid")


def test_the_fmus_loop_on_the_bending_top_equals_simulate_controller(tables, tmp_path):
    scenario, plant = tables[True]
    rigid, rigid_plant = tables[False]
    states = [read_model_description(str(p)).numberOfContinuousStates for p in (rigid_plant, plant)]
    assert states[1] == states[0] + 2 * 6  # the six modes' coordinates and rates
    ctrl = design_controller(scenario, "skyhook", RATE, search=False)  # made on the rigid-body model, judged here
    assert check_controller(scenario, ctrl).stable
    t, out, names = _loop(plant, ctrl, scenario.simulation.duration, tmp_path)
    response = Simulator(scenario).run(controller=ctrl)
    reference = {**{n: response.signals[i] for i, n in enumerate(response.signal_names)},
                 **{f"s:{s}": response.sensor(s) for s in response.sensor_names}}
    on_rigid = Simulator(rigid).run(controller=ctrl)
    for j, name in enumerate(names):  # at the communication points, which are output samples of the run
        assert relative_error(out[:, j], np.interp(t, response.t, reference[name])) < 1e-6, name
    # the modes are in what was compared: the rigid top's readings differ by far more than the tolerance
    z1 = names.index("s:v-z1")
    assert relative_error(out[:, z1], np.interp(t, on_rigid.t, on_rigid.sensor("v-z1"))) > 1e-3


def test_a_loop_the_check_refuses_grows_in_the_fmus_at_the_checks_rate_and_frequency(tables, tmp_path):
    scenario, plant = tables[True]
    rigid, rigid_plant = tables[False]
    ctrl = design_controller(rigid, "skyhook", RATE, delay=True, options={"gain": 6e4})  # the rigid top's design
    loop = check_controller(scenario, ctrl)
    assert check_controller(rigid, ctrl).stable
    assert not loop.stable
    name, f_mode = loop.growing_mode()
    assert name == "plate 1"
    f = loop.frequency_hz
    assert f == pytest.approx(f_mode, rel=0.02)
    t, out, names = _loop(plant, ctrl, scenario.simulation.duration, tmp_path / "bending")
    y = out[:, names.index("s:v-z1")]
    response = Simulator(scenario).run(controller=ctrl)  # as simulate --allow-unstable runs it
    assert relative_error(y, np.interp(t, response.t, response.sensor("v-z1"))) < 1e-4
    late = t >= 0.2  # the other closed-loop poles have decayed
    ts, amp = _envelope(t[late], y[late], f, 30.0 / f)
    slope = np.polyfit(ts, np.log(np.abs(amp)), 1)[0]
    drift = np.polyfit(ts, np.unwrap(np.angle(amp)), 1)[0] / (2 * math.pi)
    assert slope == pytest.approx(RATE * math.log(loop.spectral_radius), rel=0.01)  # the check's growth ...
    assert abs(drift) < 0.5  # Hz: ... at the check's frequency (441 Hz)
    (tmp_path / "rigid").mkdir()
    t, out, names = _loop(rigid_plant, ctrl, rigid.simulation.duration, tmp_path / "rigid")
    y = out[:, names.index("s:v-z1")]
    _, amp = _envelope(t[late], y[late], f, 30.0 / f)
    assert abs(amp[-1]) < abs(amp[0])  # on the rigid top's FMU the same loop does not grow there
