"""The FMU of a table whose top bends: its states hold the modal coordinates, its outputs add each point's
elastic translation ``<point>:ex, :ey, :ez``, and every output equals ``isolator simulate``'s within 1e-6 of its
peak (FMPy, Co-Simulation at 1 ms)."""

from __future__ import annotations

import dataclasses
import shutil

import numpy as np
import pytest
from synthetic_top import with_synthetic_top

from isolator import Simulator
from isolator.fmu import write_fmu
from isolator.scenario.definitions import Point

fmpy = pytest.importorskip("fmpy")
from fmpy import read_model_description  # noqa: E402

from fmu_master import relative_error, run  # noqa: E402

pytestmark = pytest.mark.skipif(shutil.which("cc") is None and shutil.which("gcc") is None, reason="no C compiler")


def test_the_bending_tops_fmu_equals_simulate(tmp_path):
    base = with_synthetic_top(frequencies=(40.0, 60.0, 75.0))
    scenario = dataclasses.replace(base, points=(Point("corner", (0.9, 0.4, 0.15)), Point("centre", (0.0, 0.0, 0.15))),
                                   simulation=dataclasses.replace(base.simulation, duration=9.0))
    path = write_fmu(scenario, tmp_path / "bending.fmu")
    md = read_model_description(str(path))
    outputs = [v.name for v in md.modelVariables if v.causality == "output" and not v.name.startswith("q:")]
    assert {"corner:ex", "corner:ey", "corner:ez", "centre:ez"} <= set(outputs)
    assert md.numberOfContinuousStates == 13 + 2 * 3
    r = Simulator(scenario, elastic="dynamic").run()
    t, values = run(path, tmp_path, outputs, 9.0)
    reference = {n: r.signals[i] for i, n in enumerate(r.signal_names)}
    for i, n in enumerate(r.point_names):
        reference |= {f"{n}:{a}": r.point_signals[i, k] for k, a in enumerate("xyz")}
        reference |= {f"{n}:e{a}": r.point(n, elastic=True)[k] for k, a in enumerate("xyz")}
    assert set(outputs) == set(reference)
    for j, name in enumerate(outputs):
        if not np.any(reference[name]):
            assert np.max(np.abs(values[:, j])) < 1e-12, name
            continue
        got = np.interp(r.t, t, values[:, j])
        assert relative_error(got, reference[name]) < 1e-6, name
