"""A top that bends against plate theory: the modes of ``isolator plate-modes`` (a Kirchhoff plate by scikit-fem)
read as ``[table.flexible]``, on isolators.

- on isolators that soften, the table's elastic modes tend to the top's free-free frequencies;
- on stiff supports along its four edges, the sag under a load at its centre is Navier's series for a simply
  supported plate, within the modal truncation error, which falls as modes are added;
- the compliance of a rigid top has no peak above its six modes; with the modes, its peaks sit at the coupled
  modes' frequencies of ``isolator modes``.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from isolator import linearise, load_scenario, modes
from isolator.analysis.point_compliance import point_compliance
from isolator.model.cache import get_model
from isolator.model.parameters import ParameterLayout
from isolator.plates import plate_modes
from isolator.scenario.definitions import Carriage, Isolator, Point, Scenario, Table
from isolator.scenario.flexible import load_flexible
from isolator.scenario.profiles import PiecewisePolynomialProfile

A, T, MASS, E, NU = 1.0, 0.01, 78.5, 2.0e11, 0.3  # a 1 m square steel plate, 10 mm thick
RIGIDITY = E * T**3 / (12 * (1 - NU**2))


@pytest.fixture(scope="module")
def plate_file(tmp_path_factory):
    def make(count: int) -> str:
        path = tmp_path_factory.mktemp("plate") / f"plate-{count}.csv"
        plate_modes((A, A, T), MASS, E, NU, count=count).to_csv(path)
        return str(path)
    return make


def _parked(q: float = 0.0):
    return PiecewisePolynomialProfile(knots=(0.0, 1.0), coefficients=((q,),))


def _scenario(modes_file: str, isolators: tuple[Isolator, ...], carriages: tuple[Carriage, ...] = (),
              gravity: float = 9.81) -> Scenario:
    inertia = (MASS * (A**2 + T**2) / 12, MASS * (A**2 + T**2) / 12, MASS * 2 * A**2 / 12)
    top = load_flexible(modes_file, thickness=T, damping=0.02)
    base = load_scenario("paper-table-3-1")
    return dataclasses.replace(base, name="plate", table=Table(MASS, inertia, (A, A, T), flexible=top),
                               isolators=isolators, carriages=carriages, gravity=gravity, points=(),
                               sensors=(), actuators=(), windows=(), disturbances=(), sequence=None)


def _corners(k: float, c: float = 0.0) -> tuple[Isolator, ...]:
    return tuple(Isolator((sx * A / 2, sy * A / 2, -T / 2), (k, k, k), (c, c, c))
                 for sx, sy in ((1, 1), (-1, 1), (-1, -1), (1, -1)))


def test_elastic_modes_tend_to_the_free_free_ones_as_the_isolators_soften(plate_file):
    path = plate_file(6)
    top = load_flexible(path, thickness=T)
    free = np.asarray(top.data.frequencies)
    errors = []
    for k in (1e4, 1e3, 1e2):
        m = modes(linearise(_scenario(path, _corners(k))))
        elastic = np.sort(m.frequencies_hz)[6:]
        errors.append(np.max(np.abs(elastic - free) / free))
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 1e-3
    assert errors[1] / errors[2] == pytest.approx(10.0, rel=0.2)  # the isolators' share falls as their stiffness


def _navier_centre(load: float) -> float:
    m = np.arange(1, 400, 2)
    total = np.sum(1.0 / (m[:, None] ** 2 + m[None, :] ** 2) ** 2)
    return 4 * load * A**2 / (np.pi**4 * RIGIDITY) * total


def _static_sag(path: str, load_mass: float) -> float:
    """Centre minus edge deflection of the plate on stiff supports along its edges with a carriage of
    ``load_mass`` parked at its centre, from the model's own static residual (Newton in numpy)."""
    edge = np.linspace(-A / 2, A / 2, 9)
    supports = {(float(x), float(y)) for x in edge for y in (-A / 2, A / 2)} | \
        {(float(x), float(y)) for x in (-A / 2, A / 2) for y in edge}
    isolators = tuple(Isolator((x, y, -T / 2), (1e6, 1e6, 1e10), (0.0, 0.0, 0.0)) for x, y in sorted(supports))
    carriage = Carriage("load", load_mass, "table", (1.0, 0.0, 0.0), (0.0, 0.0, T / 2), _parked())
    scenario = _scenario(path, isolators, (carriage,))
    layout = ParameterLayout.of(scenario)
    model = get_model(layout)
    p, c = layout.pack(scenario), layout.rest_inputs(np.zeros(1))
    z = np.zeros(model.n_static)
    for _ in range(6):
        r, jac = (np.asarray(v) for v in model.static_residual(z, c, p))
        z = z - np.linalg.solve(jac, r.ravel())
    eta = z[6:]
    data = scenario.table.flexible.data
    centre = data.point_translation((0.0, 0.0, T / 2), None, "centre")[:, 2] @ eta  # (modes, 3): vertical
    edges = np.mean([data.point_translation((x, y, T / 2), None, "edge")[:, 2] @ eta for x, y in supports])
    return float(edges - centre)


def test_the_sag_under_a_central_load_on_simply_supported_edges_is_naviers(plate_file):
    load = 100.0
    want = _navier_centre(load * 9.81)
    errors = []
    for count in (30, 60):  # measured: 12 modes -99 %, 30 -38 %, 60 -3.6 %, 100 -1.3 %
        path = plate_file(count)
        sag = _static_sag(path, load) - _static_sag(path, 1e-6)  # the load's part (the plate's own weight apart)
        errors.append((want - sag) / want)
    assert 0 < errors[1] < errors[0]  # a truncated free-free basis is too stiff: the sag converges from below
    assert errors[1] < 0.05


def test_compliance_peaks_sit_at_the_coupled_modes(plate_file):
    path = plate_file(6)
    scenario = dataclasses.replace(_scenario(path, _corners(2e5, 200.0)),
                                   points=(Point("corner", (0.45, 0.45, T / 2)),))
    lin = linearise(scenario)
    f = np.geomspace(1.0, 1000.0, 6000)
    c = point_compliance(lin, "corner", "z", frequency_hz=f)
    mag = c.magnitude
    peaks = f[1:-1][(mag[1:-1] > mag[:-2]) & (mag[1:-1] > mag[2:])]
    coupled = np.sort(modes(lin).frequencies_hz)[6:]
    seen = [fk for fk in coupled if np.min(np.abs(peaks - fk) / fk) < 0.01]
    assert len(seen) >= 3  # the corner sees the twist and bending modes (a node line passes others)
    rigid_top = dataclasses.replace(scenario, table=Table(MASS, scenario.table.inertia, (A, A, T)))
    c0 = point_compliance(linearise(rigid_top), "corner", "z", frequency_hz=f)
    above = f > 2 * np.max(modes(linearise(rigid_top)).frequencies_hz)
    assert np.all(np.diff(c0.magnitude[above]) < 0)  # the rigid top: the mass line, no peak
    assert np.all(mag[above][:10] != c0.magnitude[above][:10])
