"""The profiles study on a sequence: the baselines by total time and throughput, the optimised sequence
written and reproduced, and an optimised file compared from where it started."""

from __future__ import annotations

import json

import pytest

from isolator import load_scenario, run_sequence
from isolator.cli.app import main

SCENARIO = "paper-table-3-2-sequence"


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("profiles-sequence")
    assert main(["study", "profiles", SCENARIO, "--quick", "--out", str(out)]) == 0
    return out, json.loads((out / "results.json").read_text())


def test_every_way_of_moving_is_measured(study):
    out, data = study
    plain = data["S-curve at the limits"]
    assert plain["total_time"] == pytest.approx(run_sequence(load_scenario(SCENARIO)).total_time, abs=1e-9)
    # ruckig's time-optimal rest-to-rest move is the S-curve at the limits
    assert data["time-optimal (ruckig)"]["total_time"] == pytest.approx(plain["total_time"], abs=1e-6)
    for name in ("ZV", "ZVD", "optimised"):
        assert data[name]["total_time"] < 0.6 * plain["total_time"]  # shaping buys the throughput
        assert data[name]["gain"] > 0.6
    assert data["optimised"]["total_time"] <= plain["total_time"]
    for name in ("throughput.png", "steps.png", "sequence.png", "report.md"):
        assert (out / name).stat().st_size > 0


def test_the_optimised_sequence_is_written_and_reproduces(study):
    out, data = study
    written = out / "scenarios" / "optimised.toml"
    assert run_sequence(load_scenario(written)).total_time == pytest.approx(data["optimised"]["total_time"], abs=1e-9)


def test_an_optimised_file_is_compared_from_the_s_curves_at_the_limits(study, tmp_path):
    out, data = study
    again = tmp_path / "again"
    assert main(["study", "profiles", str(out / "scenarios" / "optimised.toml"), "--quick", "--out", str(again)]) == 0
    rerun = json.loads((again / "results.json").read_text())
    assert rerun["S-curve at the limits"]["total_time"] == pytest.approx(data["S-curve at the limits"]["total_time"],
                                                                          abs=1e-9)
