"""Swept names ([*], vectors), and the designs: grid order, zip, samples, set against scale."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from isolator import Simulator, load_scenario
from isolator.errors import ParameterError
from isolator.sweep import build_designs, chunk_size_for, resolve
from isolator.sweep.sweep import MAX_CHUNK

SIM = Simulator(load_scenario("paper-table-3-2"))
LAYOUT, BASE = SIM.layout, SIM.parameters


def names_of(name: str) -> list[str]:
    return [LAYOUT.names[i] for i in resolve(LAYOUT, name, "set").entries]


def test_a_name_a_wildcard_and_a_vector():
    assert names_of("isolators[2].stiffness.z") == ["isolators[2].stiffness.z"]
    assert names_of("isolators[*].stiffness.z") == [f"isolators[{i}].stiffness.z" for i in range(4)]
    assert names_of("isolators[0].stiffness") == [f"isolators[0].stiffness.{a}" for a in "xyz"]
    assert names_of("isolators[*].damping") == [f"isolators[{i}].damping.{a}" for i in range(4) for a in "xyz"]
    assert names_of("carriages[*].mass") == ["carriages[0].mass", "carriages[1].mass"]
    assert names_of("table.mass") == ["table.mass"]


@pytest.mark.parametrize(("name", "message"), [
    ("isolators[*].stifness.z", r"not a parameter of this scenario; did you mean 'isolators\[\*\]\.stiffness\.z'"),
    ("table[*].mass", r"'\[\*\]' after 'table', which has no elements"),
    ("isolators[9].stiffness.z", "not a parameter of this scenario"),
    ("isolators[*].stiff", "not a parameter"),  # a name stops at a dot, not inside a word
])
def test_bad_names_are_one_clear_error(name, message):
    with pytest.raises(ParameterError, match=message):
        resolve(LAYOUT, name, "set")


def test_two_names_driving_one_entry_are_refused():
    with pytest.raises(ParameterError, match="drives isolators\\[0\\]\\.damping\\.x, which 'isolators"):
        build_designs(LAYOUT, BASE, set={"isolators[*].damping": [1e3]}, scale={"isolators[0].damping.x": [2.0]})


def test_the_grid_crosses_the_lists_first_name_outermost():
    a, b, c = [1e5, 2e5], [1.0, 2.0, 3.0], [100.0, 200.0]
    designs = build_designs(LAYOUT, BASE, set={"isolators[*].stiffness.z": a, "table.mass": [4000, 5000]},
                            scale={"isolators[*].damping": b})
    assert designs.names == ("isolators[*].stiffness.z", "table.mass", "isolators[*].damping")
    assert designs.values.tolist() == [list(row) for row in itertools.product(a, [4000.0, 5000.0], b)]
    del c


def test_set_is_absolute_and_scale_multiplies_the_scenarios_values():
    designs = build_designs(LAYOUT, BASE, set={"isolators[*].stiffness.z": [3e5]},
                            scale={"isolators[*].damping": [2.0]})
    p = designs.parameters(0, 1)[0]
    changes = {f"isolators[{i}].stiffness.z": 3e5 for i in range(4)}
    changes |= {f"isolators[{i}].damping.{a}": 2.0 * BASE[LAYOUT.names.index(f"isolators[{i}].damping.{a}")]
                for i in range(4) for a in "xyz"}
    assert np.array_equal(p, SIM.parameter_vector(changes))


def test_zip_pairs_lists_of_one_length():
    designs = build_designs(LAYOUT, BASE, zip=True,
                            scale={"isolators[*].stiffness": [1, 2, 3], "isolators[*].damping": [4, 5, 6]})
    assert designs.values.tolist() == [[1, 4], [2, 5], [3, 6]]
    with pytest.raises(ParameterError, match=r"zip: the zipped lists must have one length, got .*: 3, .*: 2"):
        build_designs(LAYOUT, BASE, scale={"isolators[*].stiffness": [1, 2, 3], "isolators[*].damping": [4, 5]},
                      zip=True)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"set": {"isolators[*].stiffness.z": [-1.0, 2e5]}}, r"set\['isolators\[\*\]\.stiffness\.z'\] = -1: must be >= 0"),
    ({"scale": {"isolators[*].damping": [-0.5]}}, "must be >= 0"),
    ({"set": {"table.mass": []}}, "non-empty list"),
    ({"set": {"table.mass": "heavy"}}, "must be a list of numbers"),
    ({"set": {"table.mass": [1.0, float("nan")]}}, "must be finite"),
    ({}, "give at least one parameter"),
    ({"set": {"table.mass": [1e3, 2e3]}, "samples": 0}, "samples: must be a whole number >= 1"),
    ({"set": {"table.mass": [1e3, 2e3]}, "samples": 4, "method": "grid"}, "method: must be one of sobol, lhs"),
    ({"set": {"table.mass": [2e3, 1e3]}, "samples": 4}, "a range \\(low, high\\) with low < high"),
    ({"set": {"table.mass": [1e3, 2e3]}, "samples": 4, "zip": True}, "zip: not with samples"),
])
def test_bad_values_are_one_clear_error(kwargs, message):
    with pytest.raises(ParameterError, match=message):
        build_designs(LAYOUT, BASE, **kwargs)


@pytest.mark.parametrize("method", ["sobol", "lhs"])
def test_samples_are_reproducible_by_seed_and_inside_the_ranges(method):
    ranges = {"isolators[*].stiffness.z": [2e5, 8e5], "carriages[0].mass": [100.0, 400.0]}
    one = build_designs(LAYOUT, BASE, set=ranges, samples=50, method=method, seed=3)
    two = build_designs(LAYOUT, BASE, set=ranges, samples=50, method=method, seed=3)
    other = build_designs(LAYOUT, BASE, set=ranges, samples=50, method=method, seed=4)
    assert np.array_equal(one.values, two.values)
    assert not np.array_equal(one.values, other.values)
    assert one.values.shape == (50, 2)
    assert np.all((one.values >= [2e5, 100.0]) & (one.values <= [8e5, 400.0]))
    # space-filling: each tenth of each range holds about a tenth of the samples
    counts = np.histogram(one.values[:, 0], bins=10, range=(2e5, 8e5))[0]
    assert counts.min() >= 2


lists = st.lists(st.floats(0.5, 2.0), min_size=1, max_size=4)


@given(a=lists, b=lists, c=lists)
def test_grid_size_and_order_are_those_of_itertools_product(a, b, c):
    designs = build_designs(LAYOUT, BASE, scale={"isolators[*].stiffness": a, "table.mass": b,
                                                  "isolators[*].damping": c})
    assert designs.count == len(a) * len(b) * len(c)
    assert designs.values.tolist() == [list(r) for r in itertools.product(a, b, c)]


@given(rows=st.lists(st.tuples(st.floats(0.5, 2.0), st.floats(0.0, 3.0)), min_size=1, max_size=8))
def test_zip_keeps_the_rows_and_parameters_follow_them(rows):
    k, c = [r[0] for r in rows], [r[1] for r in rows]
    designs = build_designs(LAYOUT, BASE, scale={"isolators[*].stiffness": k, "isolators[*].damping": c}, zip=True)
    assert designs.values.tolist() == [list(r) for r in rows]
    assert np.allclose(designs.parameters(0, designs.count), SIM.scaled_parameter_sets(k, c), rtol=1e-15, atol=0)


@given(n=st.integers(1, 40), seed=st.integers(0, 2**16))
def test_samples_count_and_bounds(n, seed):
    designs = build_designs(LAYOUT, BASE, scale={"isolators[*].stiffness": [0.5, 2.0]}, samples=n, seed=seed,
                            method="lhs")
    assert designs.count == n
    assert np.all((designs.values >= 0.5) & (designs.values <= 2.0))


@given(designs=st.integers(1, 5000), workers=st.integers(1, 64))
def test_every_worker_gets_a_chunk_when_there_are_enough_designs(designs, workers):
    size = chunk_size_for(designs, workers)
    assert 1 <= size <= MAX_CHUNK
    assert -(-designs // size) >= min(designs, workers)
