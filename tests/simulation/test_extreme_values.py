"""Absurd magnitudes give one clear error, never numpy's (overflow, memory) or a silent NaN."""

from __future__ import annotations

import pytest

from conftest import base_dict, make
from isolator import ScenarioError, simulate


@pytest.mark.parametrize(
    ("where", "value", "message"),
    [
        ("mass", 1e300, r"^table\.mass: must be at most 1e\+15 in size"),
        ("stiffness", 1e30, r"^isolators\[0\]\.stiffness\[0\]: must be at most 1e\+15 in size"),
        ("damping", 1e30, r"^isolators\[0\]\.damping\[0\]: must be at most 1e\+15 in size"),
        ("damping", 1e12, r"^isolators\[0\]\.damping: the table's fastest mode .* integration steps .*: 1e\+12 "
                          r"N s/m on a table of 4800 kg, far beyond a real isolator's"),
    ],
)
def test_extreme_values_are_named(where: str, value: float, message: str):
    data = base_dict()
    if where == "mass":
        data["table"]["mass"] = value
    else:
        for iso in data["isolators"]:
            iso[where] = [value] * 3
    with pytest.raises(ScenarioError, match=message):
        simulate(make(data))
