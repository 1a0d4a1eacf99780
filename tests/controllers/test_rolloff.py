"""A design judged on the bending top (controllers.feedback.rolloff): a stiff skyhook that is stable on the
rigid geophones table and unstable on its bending top (the bundled top's six lowest elastic modes) is rolled
off above the isolation band, recorded in its settings, and then passes the check on the full plant."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from controllers.check_command import loop_report
from controllers.feedback.output_feedback import design_controller
from controllers.feedback.rolloff import BAND_FACTOR, MIN_DISK_MARGIN, lowpass, with_lowpass
from isolator import load_scenario
from isolator.analysis.closed_loop import check_controller
from isolator.scenario.definitions import Scenario

SCENARIOS = Path(__file__).parents[2] / "isolator" / "data" / "scenarios"


def _bending(tmp_path: Path) -> Scenario:
    text = (SCENARIOS / "paper-table-3-2-geophones.toml").read_text()
    modes = (SCENARIOS / "paper-table-3-2-top-modes.csv").as_posix()
    path = tmp_path / "bending.toml"
    path.write_text(text.replace("\n[[isolators]]", f'\n[table.flexible]\nmodes = "{modes}"\ncount = 6\n'
                                 "damping = 0.01\n\n[[isolators]]", 1))
    return load_scenario(path)


def test_a_rigid_tops_design_is_not_rolled_off() -> None:
    rigid = design_controller(load_scenario("paper-table-3-2-geophones"), "skyhook", 2000.0, delay=True,
                              options={"gain": 6e4})
    assert "rolloff" not in rigid.settings


def test_a_design_unstable_on_the_bending_top_is_rolled_off_and_then_stable(tmp_path: Path) -> None:
    rigid_scenario, bending = load_scenario("paper-table-3-2-geophones"), _bending(tmp_path)
    rigid = design_controller(rigid_scenario, "skyhook", 2000.0, delay=True, options={"gain": 6e4})
    assert check_controller(rigid_scenario, rigid).stable
    assert not check_controller(bending, rigid).stable  # the rigid design pumps a mode of the bending top
    rolled = design_controller(bending, "skyhook", 2000.0, delay=True, options={"gain": 6e4})
    record = rolled.settings["rolloff"]
    assert record["kind"] == "low-pass"
    assert "insufficient" not in record
    assert "unstable" in record["reason"]
    assert record["spectral_radius_before"] > 1.0
    assert BAND_FACTOR * 6.0 < record["corner_hz"] < 0.5 * record["lowest_elastic_mode_hz"] + 1e-9
    assert rolled.states == rigid.states + 2 * len(rolled.actuators)  # one second-order filter per command
    report = loop_report(check_controller(bending, rolled), tuple(a.name for a in bending.actuators))
    assert report["stable"]
    assert report["disk_margin"] >= MIN_DISK_MARGIN


@settings(max_examples=10, deadline=None)
@given(st.floats(5.0, 400.0), st.sampled_from([1000.0, 2000.0, 5000.0]), st.integers(1, 3))
def test_the_lowpass_has_unit_gain_at_dc_and_half_power_at_its_corner(corner: float, rate: float, m: int) -> None:
    a, b, c, d = lowpass(corner, rate, m)

    def response(f: float) -> np.ndarray:
        z = np.exp(2j * math.pi * f / rate)
        return c @ np.linalg.solve(z * np.eye(a.shape[0]) - a, b) + d

    assert np.allclose(response(0.0), np.eye(m), atol=1e-9)
    assert np.allclose(np.abs(response(corner)), np.eye(m) / math.sqrt(2), atol=1e-6)
    assert np.max(np.abs(response(min(10 * corner, 0.49 * rate)))) < 0.5 / math.sqrt(2)  # rolled off above


def test_the_filtered_controller_is_the_controller_then_the_filter() -> None:
    """With_lowpass's series connection: K(z) F(z) at a frequency, against the product of the two."""
    sc = load_scenario("paper-table-3-2-geophones")
    ctl = design_controller(sc, "lqg", 2000.0, options={"max_velocity": 0.01}, search=False)
    filtered = with_lowpass(ctl, 50.0, {"kind": "low-pass"})
    assert filtered.settings["rolloff"] == {"kind": "low-pass"}

    def response(matrices: tuple[np.ndarray, ...], f: float) -> np.ndarray:
        a, b, c, d = matrices
        z = np.exp(2j * math.pi * f / 2000.0)
        return c @ np.linalg.solve(z * np.eye(a.shape[0]) - a, b) + d

    for f in (1.0, 30.0, 300.0):
        expected = response(lowpass(50.0, 2000.0, len(sc.actuators)), f) @ response(ctl.matrices(), f)
        assert response(filtered.matrices(), f) == pytest.approx(expected, rel=1e-6, abs=1e-9)


def test_the_robustness_check_judges_the_full_plant_and_names_the_growing_mode(tmp_path: Path) -> None:
    from controllers.feedback.robustness import check_robustness
    from isolator.errors import UnstableClosedLoopError

    bending = _bending(tmp_path)
    rigid = design_controller(load_scenario("paper-table-3-2-geophones"), "skyhook", 2000.0, delay=True,
                              options={"gain": 6e4})
    report = check_robustness(bending, rigid, positions=[{}], margins=False)
    loop = check_controller(bending, rigid)
    assert report.worst.spectral_radius == loop.spectral_radius
    with pytest.raises(UnstableClosedLoopError) as error:
        report.raise_if_unstable()
    name, f_mode = loop.growing_mode()
    assert f"an oscillation at {loop.frequency_hz:.4g} Hz grows, from the open-loop mode '{name}'" in str(error.value)
    assert f_mode > 150.0  # an elastic mode, not a rigid-body one
