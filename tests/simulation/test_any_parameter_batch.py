"""Issue 26, item 5: designs that differ in the model's time-only part (a carriage's mass or position, the
table's mass and inertia) are stepped four to a compiled call, as designs that differ in stiffness are, and
give the single runs' numbers (the speed itself: benchmarks/bench_any_parameter.py)."""

from __future__ import annotations

import math
from collections import Counter

import numpy as np
import pytest

from isolator import Simulator, load_scenario
from isolator.numerics.dop853 import DenseStepper
from isolator.simulation.batch import LANES, run_batch


@pytest.mark.parametrize("name", ["carriages[0].mass", "carriages[0].origin.z", "table.mass", "table.inertia.x"])
def test_designs_of_another_time_only_part_share_the_lanes(name, monkeypatch):
    sim = Simulator(load_scenario("paper-table-3-2"))
    factors = np.linspace(0.9, 1.1, 8)
    column = sim.layout.names.index(name)
    params = np.repeat(sim.parameters[None], factors.size, axis=0)
    params[:, column] *= factors
    starts, ends = sim.equilibria_of(params)
    plans = Counter(sim.method_for(max(s.max_frequency, e.max_frequency)).plan_key
                    for s, e in zip(starts, ends, strict=True))
    calls = []
    original = DenseStepper.run_slots

    def counted(self, x0, *args, **kwargs):
        calls.append(np.ndim(x0))
        return original(self, x0, *args, **kwargs)

    monkeypatch.setattr(DenseStepper, "run_slots", counted)
    batch = run_batch(sim, params, workers=1)
    assert len(calls) == sum(math.ceil(n / LANES) for n in plans.values())
    monkeypatch.setattr(DenseStepper, "run_slots", original)
    single = np.array([sim.run(p=p).settling_time_max for p in params])
    assert np.allclose(batch.settling_time_max, single, rtol=0, atol=1e-9)
