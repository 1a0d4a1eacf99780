"""The pneumatic run's figure keeps every pressure curve in view: the two isolators of one leveling group
carry the same pressure, and a line style each keeps the one drawn last from hiding the other."""

from __future__ import annotations

import itertools

import numpy as np

from isolator import load_scenario, simulate


def test_coinciding_pressure_curves_are_told_apart_by_their_style():
    run = simulate(load_scenario("paper-table-3-2-pneumatic"))
    fig = run.plot_leveling()
    top = fig.axes[0]
    curves = [line for line in top.get_lines() if line.get_label().startswith("p:")]
    assert [line.get_label() for line in curves] == [f"p:{name}" for name in run.pneumatic.isolator_names]
    span = np.ptp(np.concatenate([line.get_ydata() for line in curves]))
    coinciding = 0
    for a, b in itertools.combinations(curves, 2):
        if np.max(np.abs(a.get_ydata() - b.get_ydata())) < 0.01 * span:  # one group's pair: the same curve
            coinciding += 1
            assert a.get_linestyle() != b.get_linestyle(), (a.get_label(), b.get_label())
    assert coinciding >= 1  # the front pair shares one valve
    legend = {text.get_text() for text in top.get_legend().get_texts()}
    assert legend == {line.get_label() for line in curves}
