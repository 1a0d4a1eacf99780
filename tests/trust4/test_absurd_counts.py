"""Trust round 4 (issue 42), item 8: absurd design counts refused before a byte of them is made, naming the
option (or key) and the count, instead of the machine running out of memory."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import run_command
from isolator import ParameterError
from isolator.scenario.files import available_memory
from isolator.sweep import sweep
from isolator.sweep.designs import DESIGN_BYTES

HAVE = available_memory() or 1e12
#: a count no machine this runs on holds
HUGE = st.integers(int(HAVE / DESIGN_BYTES) * 4, 10**15)
FIXTURES = [HealthCheck.function_scoped_fixture]


@given(count=HUGE)
@settings(max_examples=5, deadline=None, suppress_health_check=FIXTURES)
def test_a_grid_count_on_the_command_line_is_refused_naming_the_option(count, capsys):
    status, _, err = run_command(["sweep", "paper-table-3-1", "--set", f"table.mass=4000:4400:{count:.6e}",
                                  "--out", "never.csv"], capsys)
    assert status == 2
    assert len(err) == 1
    assert err[0].startswith("isolator: error: --set table.mass=4000:4400:"), err
    assert " designs need about " in err[0]


@given(count=HUGE)
@settings(max_examples=5, deadline=None, suppress_health_check=FIXTURES)
def test_samples_on_the_command_line_are_refused_naming_the_option(count, capsys):
    status, _, err = run_command(["sweep", "paper-table-3-1", "--set", "table.mass=4000:4400", "--samples",
                                  str(count), "--out", "never.csv"], capsys)
    assert status == 2
    assert err == [err[0]]
    assert err[0].startswith(f"isolator: error: --samples: {count} designs need about "), err


def test_a_crossed_grid_is_counted_whole_and_named_by_its_columns(capsys):
    side = int((HAVE / DESIGN_BYTES) ** 0.5 * 2)
    status, _, err = run_command(["sweep", "paper-table-3-1", "--set", f"table.mass=4000:4400:{side}",
                                  "--scale", f"isolators[*].stiffness.z=0.5:2:{side}", "--out", "never.csv"],
                                 capsys)
    assert status == 2
    assert err[0].startswith(f"isolator: error: --set table.mass, --scale isolators[*].stiffness.z: {side * side} "
                             "designs need"), err


def test_the_api_names_its_keys():
    with pytest.raises(ParameterError, match=r"^samples: \d+ designs need about"):
        sweep("paper-table-3-1", set={"table.mass": [4000.0, 4400.0]}, samples=10**13)


def test_a_record_too_long_for_its_spectra_is_refused_naming_the_segment_and_the_count(monkeypatch):
    from isolator.calibration.spectra import h1_estimate
    from isolator.scenario import files

    monkeypatch.setattr(files, "available_memory", lambda: 10_000_000)  # a machine of 10 MB
    rng = np.random.default_rng(0)
    x, y = rng.normal(size=(3, 20_000)), rng.normal(size=(4, 20_000))
    with pytest.raises(ParameterError, match=r"^segment: 20000 samples of 7 channels in segments of 2000 need "
                                             r"about .* GB of memory, more than the 0.01 GB"):
        h1_estimate(x, y, 100.0, 20.0)
    monkeypatch.setattr(files, "available_memory", lambda: 10**12)
    assert h1_estimate(x, y, 100.0, 20.0).H.shape == (4, 3, 1001)
