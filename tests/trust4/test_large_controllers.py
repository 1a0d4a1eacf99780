"""Trust round 4 (issue 42), item 7: a controller too large to run is refused in one line (the file, its state
count, the limit) before any work on it, whichever command reads it; one that may run ticks in code whose size
does not grow with it (dense products instead of its n^2 entries written out)."""

from __future__ import annotations

import json
import re

import casadi as ca
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import run_command
from isolator import ParameterError, load_scenario
from isolator.simulation.controller_schema import MAX_STATES, check_controller_data
from isolator.simulation.discrete_controller import DiscreteController
from isolator.simulation.sampled_loop import _actuators, _tick

GEOPHONES = "paper-table-3-2-geophones"


@pytest.fixture(scope="module")
def names() -> dict:
    scenario = load_scenario(GEOPHONES)
    return {"sample_rate": 2000.0, "sensors": [s.name for s in scenario.sensors],
            "actuators": [a.name for a in scenario.actuators], "carriages": [c.name for c in scenario.carriages]}


@given(n=st.integers(MAX_STATES + 1, 10**6), scheduled=st.booleans())
def test_the_state_count_is_checked_before_the_matrices(names, n, scheduled):
    rows = [[0.0]] * n  # not even square: the count is refused first, without reading a row
    data = dict(names, A=rows, B=[], C=[], D=[])
    key = "controller.A"
    if scheduled:
        data = dict(names, schedule=[{"q": [0.0, 0.0], "A": rows, "B": [], "C": [], "D": []}])
        key = "controller.schedule[0].A"
    with pytest.raises(ParameterError, match=rf"^{re.escape(key)}: {n} states, more than the {MAX_STATES} a "):
        check_controller_data(data)


@given(n=st.integers(MAX_STATES + 1, MAX_STATES + 50))
@settings(max_examples=3, deadline=None)
def test_the_python_api_has_the_same_limit(names, n):
    p, m = len(names["sensors"]), len(names["actuators"])
    with pytest.raises(ParameterError, match=rf"A: {n} states, more than the {MAX_STATES}"):
        DiscreteController(2000.0, names["sensors"], names["actuators"], names["carriages"], A=np.zeros((n, n)),
                           B=np.zeros((n, p)), C=np.zeros((m, n)), D=np.zeros((m, p)))


@pytest.mark.parametrize("command", [["simulate", GEOPHONES], ["budget", "paper-table-3-2-budget"]])
def test_a_2000_state_controller_is_one_line_naming_the_file_count_and_limit(names, tmp_path, capsys, command):
    (tmp_path / "controller.json").write_text(json.dumps(dict(names, A=[[0.5]] * 2000, B=[], C=[], D=[])))
    status, _, err = run_command([*command, "--controller", str(tmp_path)], capsys)
    assert status == 2
    assert err == [f"isolator: error: --controller: '{tmp_path / 'controller.json'}': controller.A: 2000 states, "
                   f"more than the {MAX_STATES} a controller may have (each sample costs states^2 operations; "
                   "reduce the design, e.g. by balanced truncation)"]


def _evaluate(n: int, ny: int, m: int, k: int, seed: int) -> tuple[ca.Function, list, list]:
    rng = np.random.default_rng(seed)
    per = n * n + n * ny + m * n + m * ny
    packed, weights = rng.normal(size=k * per), rng.dirichlet(np.ones(k))
    xc, y, hold, pending = rng.normal(size=n), rng.normal(size=ny), rng.normal(size=m), rng.normal(size=m)
    fn = _tick((n, ny, m, k))
    got = [np.asarray(v).ravel() for v in fn(xc, hold, pending, y, 1.0, weights, packed, 0.0)]
    mixed = sum(w * packed[j * per:(j + 1) * per] for j, w in enumerate(weights))
    a = mixed[:n * n].reshape(n, n, order="F")
    b = mixed[n * n:n * n + n * ny].reshape(n, ny, order="F")
    c = mixed[n * n + n * ny:n * n + n * ny + m * n].reshape(m, n, order="F")
    d = mixed[n * n + n * ny + m * n:].reshape(m, ny, order="F")
    command = c @ xc + d @ y
    return fn, got, [a @ xc + b @ y, command, command]


@given(n=st.sampled_from([3, 70, 150]), k=st.integers(1, 3), seed=st.integers(0, 2**16))
@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_the_tick_is_the_controller_whether_written_out_or_as_products(n, k, seed):
    _, got, want = _evaluate(n, 12, 12, k, seed)
    for g, w in zip(got, want, strict=True):
        np.testing.assert_allclose(g, w, rtol=1e-10, atol=1e-10)


def test_a_large_controller_s_tick_does_not_grow_with_it():
    small, large = (_tick((n, 12, 12, 1)) for n in (200, MAX_STATES))
    assert isinstance(small, ca.Function)
    assert large.n_instructions() == small.n_instructions()


def _code_size(fn: ca.Function) -> int:
    generator = ca.CodeGenerator("size.c", {"with_header": False})
    generator.add(fn)
    return len(generator.dump())


def test_the_actuators_lag_code_grows_by_calls_not_copies_with_the_substeps():
    """A bending top's 39 RK4 substeps per sample of twelve lagged actuators: each substep calls one small lag
    function. Written out whole, the lag was 20 MB of C, which the compiler could not hold in 24 GB."""
    one, many = (_code_size(_actuators(12, substeps)) for substeps in (1, 39))
    assert many < 1_000_000
    assert many - one < 38 * 6_000  # a substep adds a few calls (~4 kB), not a copy of the formulas (~500 kB)
