"""The pneumatic model against hand physics: air-spring stiffness, conservation of air, statics.

Every reference here is written in the test from the contract's equations
(``docs/scenario-format.md``, "Pneumatic isolators and leveling"), with numpy
and scipy, independently of the casadi model.
"""

from __future__ import annotations

import numpy as np
import pytest
from pneumatic_cases import pneumatic_dict, three_springs_dict
from scipy.integrate import cumulative_trapezoid
from scipy.optimize import root
from scipy.spatial.transform import Rotation

from isolator import scenario_from_dict, simulate
from isolator.model.cache import get_model
from isolator.model.equilibrium import static_equilibrium
from isolator.model.parameters import ParameterLayout
from isolator.scenario.definitions import Scenario
from isolator.simulation.response import Response


def _rotations(states: np.ndarray) -> np.ndarray:
    """Rotation matrices (N, 3, 3) of the exact model's quaternions (w, x, y, z)."""
    q = states[:, 3:7]
    return Rotation.from_quat(np.column_stack([q[:, 1:], q[:, :1]])).as_matrix()


def _stretch_z(s: Scenario, states: np.ndarray) -> np.ndarray:
    """Vertical displacement of every attachment point from the initial equilibrium (N, isolators) [m]."""
    rot = _rotations(states)
    pts = np.array([iso.position for iso in s.isolators])
    return states[:, 2:3] + np.einsum("nj,kj->nk", rot[:, 2, :], pts) - pts[:, 2]


def _chambers(s: Scenario, states: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Spring pressures and volumes, damping pressures and volumes (N, isolators) [Pa], [m^3]."""
    m = len(s.isolators)
    p1 = states[:, 13 : 13 + m]
    v1 = np.array([iso.volume for iso in s.isolators]) + np.array([iso.area for iso in s.isolators]) * _stretch_z(
        s, states
    )
    damped = [k for k, iso in enumerate(s.isolators) if iso.damping_volume > 0]
    p2 = np.zeros_like(p1)
    p2[:, damped] = states[:, 13 + m : 13 + m + len(damped)]
    v2 = np.array([iso.damping_volume for iso in s.isolators])
    return p1, v1, p2, v2


def _heights(s: Scenario, states: np.ndarray) -> np.ndarray:
    """Each group's sensor height (N, groups) [m]."""
    rot = _rotations(states)
    pts = np.array([[g.sensor[0], g.sensor[1], 0.0] for g in s.leveling])
    return states[:, 2:3] + np.einsum("nj,gj->ng", rot[:, 2, :], pts)


def test_plain_air_spring_has_the_textbook_stiffness():
    """No damping chamber: heave at sqrt(sum n p0 A^2 / V1r / M), p0 absolute, undamped (exact)."""
    s = scenario_from_dict(three_springs_dict(damping_volume=0.0))
    layout = ParameterLayout.of(s)
    model = get_model(layout)
    eq = static_equilibrium(model, layout.pack(s), s.initial_positions())
    air = s.air
    assert air is not None
    p0 = eq.state[13:16]
    np.testing.assert_allclose(p0, p0[0], rtol=1e-12)  # the symmetric sizing puts all three at one pressure
    k = sum(air.polytropic * p * iso.area**2 / iso.volume for p, iso in zip(p0, s.isolators, strict=True))
    omega = np.sqrt(k / s.total_mass)
    heave = eq.eigenvalues[np.argmin(np.abs(np.abs(eq.eigenvalues) - omega))]
    assert heave.real == pytest.approx(0.0, abs=1e-9 * omega)
    assert abs(heave.imag) == pytest.approx(omega, rel=1e-10)


def test_air_mass_is_conserved_with_the_valves_closed():
    """Isothermal: a group's air mass sum p V / (R T) stays put while the carriage moves (no valves)."""
    s, _, mass, p1 = _isothermal_run(valves=False, duration=3.0)
    for g in s.leveling:
        group = mass[:, list(g.isolators)].sum(axis=1)
        assert np.ptp(p1[:, list(g.isolators)]) > 1e3  # the pressures did change [Pa]
        np.testing.assert_allclose(group, group[0], rtol=1e-9)


def _isothermal_run(valves: bool, duration: float) -> tuple[Scenario, Response, np.ndarray, np.ndarray]:
    """A run at polytropic = 1, its air mass per isolator (spring + damping chamber, kg) and spring pressures."""
    s = scenario_from_dict(pneumatic_dict(valves=valves, polytropic=1.0, duration=duration))
    r = simulate(s)
    p1, v1, p2, v2 = _chambers(s, r.states)
    air = s.air
    assert air is not None
    return s, r, (p1 * v1 + p2 * v2) / (air.gas_constant * air.temperature), p1


def test_air_mass_changes_by_the_integrated_valve_flow():
    """With valves: a group's air mass changes by the time integral of the contract's valve flow."""
    s, r, mass, p1 = _isothermal_run(valves=True, duration=8.0)
    air = s.air
    assert air is not None
    h = _heights(s, r.states)
    for j, g in enumerate(s.leveling):
        valve = g.valve
        assert valve is not None
        e = -h[:, j]
        demand = valve.gain * np.sign(e) * np.maximum(np.abs(e) - valve.deadband, 0.0)
        flow = np.clip(demand, -valve.max_flow, valve.max_flow)
        members = p1[:, list(g.isolators)]
        flow = np.where(members.max(axis=1) >= air.atmosphere + g.supply, np.minimum(flow, 0.0), flow)
        flow = np.where(members.min(axis=1) <= air.atmosphere, np.maximum(flow, 0.0), flow)
        added = cumulative_trapezoid(flow, r.t, initial=0.0)
        change = mass[:, list(g.isolators)].sum(axis=1) - mass[0, list(g.isolators)].sum()
        assert np.max(np.abs(added)) > 1e-5  # the valve did work
        np.testing.assert_allclose(change, added, atol=2e-3 * np.max(np.abs(added)))


def _hand_rest_pressures(s: Scenario, q: np.ndarray) -> np.ndarray:
    """Gauge pressures of the three groups holding the level table: force and two moments."""
    a = np.zeros((3, 3))
    for j, g in enumerate(s.leveling):
        for k in g.isolators:
            x, y, _ = s.isolators[k].position
            a[:, j] += s.isolators[k].area * np.array([1.0, y, x])
    c = s.carriage_positions(q)
    m = np.array([cr.mass for cr in s.carriages])
    b = s.gravity * np.array([s.total_mass, m @ c[:, 1], m @ c[:, 0]])
    return np.linalg.solve(a, b)


def test_valves_relevel_to_the_statically_determinate_pressures():
    s = scenario_from_dict(pneumatic_dict(valves=True, stroke=0.8, duration=30.0))
    r = simulate(s)
    final = r.states[-1]
    expected = _hand_rest_pressures(s, s.final_positions())
    group_of = [next(j for j, g in enumerate(s.leveling) if k in g.isolators) for k in range(len(s.isolators))]
    gauge = final[13:17] - 101325.0
    np.testing.assert_allclose(gauge, expected[group_of], rtol=2e-4)
    before = _hand_rest_pressures(s, s.initial_positions())
    assert np.max(np.abs(expected - before)) > 100 * np.max(np.abs(gauge - expected[group_of]))
    h = _heights(s, r.states[-1:])[0]
    deadband = s.leveling[0].valve.deadband  # type: ignore[union-attr]
    assert np.all(np.abs(h) <= deadband * 1.0001)


def _closed_rest(s: Scenario, q: np.ndarray, p_rest: np.ndarray) -> np.ndarray:
    """The table at rest with each group's air fixed (isothermal), exact rotation: pose (x, y, z, rotvec)."""
    air = s.air
    assert air is not None
    pts = np.array([iso.position for iso in s.isolators])
    area = np.array([iso.area for iso in s.isolators])
    v_rest = np.array([iso.volume + iso.damping_volume for iso in s.isolators])
    kh = np.array([iso.horizontal_stiffness for iso in s.isolators])
    c = s.carriage_positions(q)
    masses = np.array([cr.mass for cr in s.carriages])

    def balance(u: np.ndarray) -> np.ndarray:
        pos, rot = u[:3], Rotation.from_rotvec(u[3:]).as_matrix()
        where = pos + pts @ rot.T
        stretch = where - pts
        force, moment = np.zeros(3), np.zeros(3)
        for g, p_g in zip(s.leveling, p_rest, strict=True):
            k = list(g.isolators)
            content = (p_g + air.atmosphere) * v_rest[k].sum()
            p_abs = content / (v_rest[k] + area[k] * stretch[k, 2]).sum()
            for i in k:
                f = np.array([-kh[i, 0] * stretch[i, 0], -kh[i, 1] * stretch[i, 1], (p_abs - air.atmosphere) * area[i]])
                force += f
                moment += np.cross(where[i], f)
        for mass_point, m in ((pos, s.table.mass), *zip(pos + c @ rot.T, masses, strict=True)):
            weight = np.array([0.0, 0.0, -m * s.gravity])
            force += weight
            moment += np.cross(mass_point, weight)
        return np.concatenate([force, moment]) / (s.gravity * s.total_mass)

    solution = root(balance, np.zeros(6), method="hybr", tol=1e-13)
    assert np.max(np.abs(balance(solution.x))) < 1e-9  # of the weight
    return np.asarray(solution.x)


def test_without_valves_the_table_rests_tilted_by_the_hand_solved_amount():
    """Isothermal, air fixed per group: the end of the run sits where the exact-rotation statics put it."""
    s = scenario_from_dict(pneumatic_dict(valves=False, polytropic=1.0, stroke=0.8, duration=12.0))
    r = simulate(s)
    expected = _closed_rest(s, s.final_positions(), _hand_rest_pressures(s, s.initial_positions()))
    end = r.signals[:, -1]
    assert abs(expected[4]) > 1e-4  # a real tilt, pitching about y
    np.testing.assert_allclose(end, expected, atol=2e-3 * np.max(np.abs(expected)))
