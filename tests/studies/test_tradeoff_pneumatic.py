"""The isolation-against-settling study on a pneumatic table."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from isolator import Simulator, load_scenario
from studies.tradeoff import run_tradeoff_study


def test_tradeoff_on_a_pneumatic_table_uses_the_settling_about_the_leveling_table(tmp_path):
    scenario = load_scenario("paper-table-3-2-pneumatic")
    study = run_tradeoff_study(tmp_path, scenario, stiffness=[0.7, 1.0], damping=[0.5, 2.0], progress=False)
    sim = Simulator(scenario.with_changes(simulation=replace(scenario.simulation, duration=study.duration)))
    for i, k in enumerate(study.stiffness):
        for j, c in enumerate(study.damping):
            run = sim.run(p=sim.scaled_parameters(k, c))
            assert study.settling_time[i, j] == pytest.approx(run.dynamic_settling_time_max, abs=1e-9)
            assert run.dynamic_settling_time_max < run.settling_time_max  # the leveling is left out
    assert np.all(np.isfinite(study.transmissibility))
    report = (tmp_path / "report.md").read_text()
    assert "Pneumatic isolators: the stiffness scale divides both chambers' volumes" in report
