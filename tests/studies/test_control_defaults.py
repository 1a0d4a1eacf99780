"""The control study shows the default sensor-based designs against the methods' own weights and the passive
table (issue 34, item 5): ``sensors-defaults.png``'s bars and the report's table carry the same numbers as the
runs, simulated again here."""

from __future__ import annotations

import math

import numpy as np
import pytest

from controllers.feedback import design_controller
from controllers.feedback.output_tuning import FORCE_SHARE
from controllers.feedforward import settling_in_band
from isolator import Band, Simulator, load_scenario
from studies import control_sensors

SCENARIO = "paper-table-3-2-geophones"


@pytest.fixture(scope="module")
def study():
    scenario = load_scenario(SCENARIO)
    passive = Simulator(scenario).run()
    band = Band.of_baseline("passive", passive.peak)
    designs, _ = control_sensors.run_sensor_designs(scenario, band, settling_in_band, 2000.0, methods=("lqg",))
    return scenario, passive, band, designs


def _slowest(scenario, ctrl, band):
    settling = Simulator(scenario).run(controller=ctrl).with_band(band).settling_time
    return max(math.inf if v is None else v for v in settling.values())


def test_the_defaults_figure_draws_passive_the_own_weights_and_the_default(study, tmp_path, monkeypatch):
    scenario, passive, band, designs = study
    kept = {}
    monkeypatch.setattr(control_sensors, "save_figure", lambda fig, path: kept.__setitem__(path.name, fig))
    control_sensors.defaults_figure(designs, passive, band, tmp_path / "sensors-defaults.png")
    settling, force = kept["sensors-defaults.png"].axes
    labels = [t.get_text() for t in settling.get_yticklabels()]
    assert labels == ["passive", "lqg, own weights", "lqg, default (searched)"]
    ratios = [bar.get_width() for bar in settling.patches]
    reference = passive.with_band(band).settling_time_max
    own = design_controller(scenario, "lqg", 2000.0, search=False)
    assert ratios[0] == pytest.approx(1.0)
    assert ratios[1] == pytest.approx(_slowest(scenario, own, band) / reference, rel=1e-6)
    assert ratios[2] == pytest.approx(_slowest(scenario, designs[0].controller, band) / reference, rel=1e-6)
    assert ratios[2] <= 0.06 < ratios[1]
    shares = [bar.get_width() for bar in force.patches]
    assert shares[0] == 0.0
    assert 0.0 < shares[2] <= FORCE_SHARE
    assert any(line.get_label().startswith("the search's limit") for line in force.get_lines())
    assert "settling" in settling.get_xlabel()
    assert "max_force" in force.get_xlabel()


def test_the_report_compares_the_default_with_the_methods_own_weights(study):
    _, _, _, designs = study
    lines = control_sensors.sensor_report(designs)
    row = next(line for line in lines if line.startswith("| lqg | max_velocity"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    d = designs[0]
    passive = d.controller.settings["search"]["passive_settling"]
    assert float(cells[2]) == pytest.approx(d.settling_time_max / passive, abs=5e-4)
    assert float(cells[3]) == pytest.approx(d.unsearched / passive, abs=5e-4)
    assert float(cells[5]) == pytest.approx(d.unsearched_share, abs=5e-3)
    assert np.isfinite(d.unsearched_share)
