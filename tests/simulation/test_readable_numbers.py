"""Issue 26, item 6: numbers as people read them: times computed from the inputs as the inputs give them,
rounding dust printed as 0, windows in a unit that suits them."""

from __future__ import annotations

import dataclasses
import json

import numpy as np

from isolator import linearise, load_scenario, modes, simulate
from isolator.cli.app import main
from isolator.scenario.windows import Window
from isolator.simulation.window_settling import WindowResult


def test_json_times_are_the_inputs_own(capsys):
    assert main(["simulate", "paper-table-3-2", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["stop_time"] == 7.9  # 0.5 s + the profile's phases: 7.8999999999999995 before
    assert data["move_time"] == 7.4


def test_a_final_value_at_rounding_level_prints_as_zero():
    run = simulate(load_scenario("paper-table-3-2"))
    final = np.array(run.final)
    final[5] = -2.647e-23  # rz: 1e-17 of its peak
    table = dataclasses.replace(run, final=final).summary()
    row = next(line for line in table.splitlines() if line.strip().startswith("rz "))
    assert "e-" not in row
    assert " 0 µrad" in row


def test_a_one_metre_window_prints_in_metres():
    result = WindowResult((Window("tool", 1.0), Window("tool", 2e-9)), (0.5, 0.25), ("", ""), np.zeros(1),
                          (np.zeros((3, 1)), np.zeros((3, 1))))
    lines = result.summary_lines()
    assert "±1 m on x,y,z" in lines[0]
    assert "±2 nm on x,y,z" in lines[1]
    assert "nm" not in lines[0]


def test_mode_shapes_have_no_rounding_dust():
    shapes = modes(linearise(load_scenario("paper-table-3-2"))).shapes
    tiny = np.abs(shapes)[(shapes != 0.0)]
    assert tiny.min() > 1e-12
