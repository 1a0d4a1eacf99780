"""The bending top's transient against the linear model and the static model:

- carriages parked, a small force bump at an actuator: the exact transient (the modal coordinates among its
  states) equals the linear model's prediction (python-control's forced response of ``linearise``'s system),
  at the point's elastic translation and the table's motion;
- a carriage moving slowly over the top: the top's deflection follows the static influence line, the static
  equilibrium with the carriage where it is at each instant.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from synthetic_top import with_synthetic_top

from isolator import Simulator, linearise, load_scenario
from isolator.model.cache import get_model
from isolator.model.equilibrium import static_equilibrium
from isolator.model.parameters import ParameterLayout
from isolator.scenario.definitions import Point
from isolator.scenario.profile_shapes import trapezoid
from isolator.scenario.profiles import PiecewisePolynomialProfile
from isolator.simulation.actuation import ForceHistory


def _parked(q: float) -> PiecewisePolynomialProfile:
    return PiecewisePolynomialProfile(knots=(0.0, 0.1), coefficients=((q,),))


def test_a_force_bump_with_the_carriages_parked_is_the_linear_models_response():
    base = with_synthetic_top(load_scenario("paper-table-3-2-active"), frequencies=(60.0, 90.0, 120.0))
    carriages = tuple(dataclasses.replace(c, profile=_parked(c.profile.position(0.0))) for c in base.carriages)
    scenario = dataclasses.replace(base, carriages=carriages, points=(Point("corner", (0.9, 0.4, 0.15)),),
                                   simulation=dataclasses.replace(base.simulation, duration=1.0,
                                                                  sample_rate=5000.0))
    t = np.linspace(0.0, 1.0, 5001)
    bump = np.where((t > 0.1) & (t < 0.14), 50.0 * np.sin(np.pi * (t - 0.1) / 0.04) ** 2, 0.0)  # N, smooth
    names = tuple(a.name for a in scenario.actuators)
    forces = np.zeros((len(names), t.size))
    forces[names.index("z1")] = bump
    r = Simulator(scenario).run(forces=ForceHistory(t, forces, names))

    import control

    lin = linearise(scenario)
    sys = lin.system
    inputs = np.zeros((len(lin.input_names), t.size))
    inputs[lin.input_names.index("actuator:z1")] = bump
    y = control.forced_response(sys, T=t, U=inputs).outputs
    for name, got in (("corner:ez", r.point("corner", elastic=True)[2]), ("z", r.signal("z")),
                      ("rx", r.signal("rx"))):
        want = y[lin.output_names.index(name)]
        assert np.max(np.abs(np.interp(t, r.t, got) - want)) < 2e-3 * np.max(np.abs(want)), name
    assert np.max(np.abs(r.point("corner", elastic=True)[2])) > 1e-3 * np.max(np.abs(r.point("corner")[2]))


def test_a_slow_carriage_bends_the_top_along_its_static_influence_line():
    base = with_synthetic_top(frequencies=(40.0, 60.0, 75.0))
    x, y = base.carriages
    slow = dataclasses.replace(x, profile=trapezoid(start=-0.7, stroke=1.4, velocity=0.05, acceleration=0.05, t0=0.5))
    scenario = dataclasses.replace(base, carriages=(slow, dataclasses.replace(y, profile=_parked(0.0))),
                                   simulation=dataclasses.replace(base.simulation, duration=32.0, sample_rate=50.0))
    r = Simulator(scenario).run()
    layout = ParameterLayout.of(scenario)
    model, p = get_model(layout), layout.pack(scenario)
    nm = 3
    shape = layout.flexible.carriages[0]
    checked = 0
    for k in np.nonzero((r.t > 5.0) & (r.t < 27.0))[0][::100]:
        q = np.array([slow.profile.position(float(r.t[k])), 0.0])
        rest = static_equilibrium(model, p, q).state[13:13 + nm]
        under = shape.values(q[:1], nm)[0]  # the carriage's feet's translation per modal coordinate
        moving, static = under @ r.states[k, 13:13 + nm], under @ rest
        assert np.max(np.abs(moving - static)) < 0.02 * np.max(np.abs(static)), r.t[k]
        checked += 1
    assert checked >= 8
