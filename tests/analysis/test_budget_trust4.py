"""The error budget's checks of trust round 4 (issue 42): implausible magnitudes refused by their key (a floor
spectrum in um/s given as m/s, a disturbance placed in mm or far away, a PSD whose RMS overflows), a closed loop
worse than the passive table said, carriages parked beyond their travel refused, every band either refused or
answered with finite numbers, and the sources with nothing in the band named."""

from __future__ import annotations

import itertools
import json
import math
import re
import sys

import numpy as np
import pytest
from analysis.test_budget import heave_dict
from analysis.test_budget_loop import GAIN, sensed_table, skyhook
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from conftest import make
from isolator import linearise, load_scenario
from isolator.analysis.budget import error_budget
from isolator.analysis.travel import check_travel
from isolator.errors import ParameterError, ScenarioError
from isolator.scenario.tables import MAX_FLOOR_VELOCITY, spectrum_from_columns

#: one-third-octave band centres [Hz], 1 to 79.4 Hz
CENTRES = 10.0 ** (np.arange(20) / 10)
SLOW = settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def floor_columns(kind: str, values: np.ndarray, frequency: np.ndarray) -> dict[str, np.ndarray]:
    return {"frequency": np.asarray(frequency, dtype=float), "z": np.asarray(values, dtype=float)}


@given(level=st.floats(1e-9, 1e300), band=st.integers(0, 19))
@settings(max_examples=60, deadline=None)
def test_a_third_octave_floor_above_1_mm_per_s_is_refused_with_its_band_and_likely_unit(level, band):
    """A one-third-octave value [m/s] above 1 mm/s in any band is refused naming ground.spectrum, the band, the
    value and the unit that brings it below (um/s given as m/s for VC-D's 6.25 typed as m/s); below, accepted."""
    values = np.full(CENTRES.size, 1e-6)
    values[band] = level
    if level <= MAX_FLOOR_VELOCITY:
        spectrum_from_columns(floor_columns("third-octave", values, CENTRES), "third-octave", "ground.spectrum")
        return
    with pytest.raises(ScenarioError) as caught:
        spectrum_from_columns(floor_columns("third-octave", values, CENTRES), "third-octave", "ground.spectrum")
    message = str(caught.value)
    assert message.startswith("ground.spectrum: ")
    assert f"band at {CENTRES[band]:.3g} Hz is {level:.3g} m/s on z" in message
    factors = [(1e3, "mm/s"), (1e6, "um/s"), (1e9, "nm/s")]
    likely = next((unit for factor, unit in factors if level / factor <= MAX_FLOOR_VELOCITY), None)
    if likely is None:
        assert "look like" not in message
    else:
        assert f"the numbers look like {likely} given as m/s" in message


def test_vc_d_typed_in_um_per_s_is_named_as_such():
    with pytest.raises(ScenarioError, match=r"ground.spectrum: .* 6.25 m/s on z.* look like um/s given as m/s"):
        make(heave_dict(ground={"spectrum": {"kind": "third-octave", "frequency": list(CENTRES[:4]),
                                             "z": [6.25, 6.25, 6.25, 6.25]}}))


@given(psd=st.floats(1e-14, 1e300))
@settings(max_examples=40, deadline=None)
def test_a_flat_velocity_psd_is_refused_exactly_when_a_band_exceeds_1_mm_per_s(psd):
    """A flat velocity PSD S over 1 to 100 Hz: its largest band is 70.8 to 89.1 Hz (centre 79.4 Hz), RMS
    sqrt(S * 18.3 Hz), computed here independently."""
    width = 10 ** 1.95 - 10 ** 1.85
    rms = math.sqrt(psd * width)
    if abs(rms / MAX_FLOOR_VELOCITY - 1) < 1e-2:
        return  # too close to the limit to tell the quadrature from the rule
    columns = floor_columns("psd", np.array([psd, psd]), np.array([1.0, 100.0]))
    if rms < MAX_FLOOR_VELOCITY:
        spectrum_from_columns(columns, "psd", "ground.spectrum")
        return
    with pytest.raises(ScenarioError, match=r"^ground.spectrum: the floor's RMS velocity in the one-third-octave "
                                            r"band at 79.4 Hz is") as caught:
        spectrum_from_columns(columns, "psd", "ground.spectrum")
    shown = float(re.search(r"Hz is (\S+) m/s", str(caught.value)).group(1))  # type: ignore[union-attr]
    assert shown == pytest.approx(rms, rel=5e-3)  # printed to 3 digits


def with_disturbance(position: list[float], psd: float = 1e-2) -> dict:
    """The heave table (2 x 1 x 0.2 m) with one random force."""
    return heave_dict(disturbances=[{"name": "push", "position": position, "direction": [0.0, 0.0, 1.0],
                                     "psd": psd}])


@given(y=st.floats(-1e7, 1e7))
@settings(max_examples=60, deadline=None)
def test_a_disturbance_is_placed_within_the_tables_reach_as_points_are(y):
    """Along y the table reaches 0.5 m, plus twice its largest dimension (4 m) for parts under a frame."""
    reach = 0.5 + 4.0
    if abs(abs(y) - reach) < 1e-6:
        return
    if abs(y) < reach:
        make(with_disturbance([0.0, y, 0.1]))
        return
    with pytest.raises(ScenarioError, match=r"^disturbances\[0\].position: .* beyond what the table reaches along y"):
        make(with_disturbance([0.0, y, 0.1]))


def test_a_disturbance_in_mm_is_named_and_far_ones_refused():
    with pytest.raises(ScenarioError, match=r"disturbances\[0\].position: .*\(a position in mm\?"):
        make(with_disturbance([300.0, 100.0, 150.0]))
    for far in ([0.0, 5.0, 0.0], [1e6, 0.0, 0.0]):
        with pytest.raises(ScenarioError, match=r"disturbances\[0\].position"):
            make(with_disturbance(far))


@given(exponent=st.floats(-30.0, 308.0))
@example(exponent=308.0)
@example(exponent=305.5)
@SLOW
def test_a_force_psd_either_scales_the_budget_by_its_root_or_is_refused_by_its_key(exponent):
    """The budget is linear in the sources' PSD: RMS ~ sqrt(S). A PSD whose own variance over the band
    (0.1 to 1000 Hz) overflows is refused naming disturbances[0].psd, never a finite-looking 1e146 m."""
    psd = 10.0**exponent
    overflows = psd * 999.9 / sys.float_info.max
    if abs(overflows - 1) < 1e-2:
        return  # at the edge of the floating-point range: either answer
    reference = error_budget(make(with_disturbance([0.3, 0.2, 0.1], 1.0)), quantity="velocity")
    try:
        budget, refused = error_budget(make(with_disturbance([0.3, 0.2, 0.1], psd)), quantity="velocity"), ""
    except ScenarioError as exc:
        budget, refused = None, str(exc)
    assert (budget is None) == (overflows > 1), (psd, refused)  # refused exactly where the variance overflows
    if budget is None:
        assert refused.startswith("disturbances[0].psd: "), refused
        return
    assert np.all(np.isfinite(budget.rms))
    np.testing.assert_allclose(budget.rms, reference.rms * math.sqrt(psd), rtol=1e-9)


def test_a_psd_of_1e308_is_refused_by_its_key():
    with pytest.raises(ScenarioError, match=r"^disturbances\[0\].psd: the source force:push's RMS .* not a finite"):
        error_budget(make(with_disturbance([0.3, 0.2, 0.1], 1e308)))


# -- bands ---------------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def heave_lin():
    ground = {"spectrum": {"vc": "VC-D"}}
    return linearise(make(with_disturbance([0.3, 0.2, 0.1]) | {"ground": ground}))


def strict_json(data: dict) -> dict:
    """``data`` through JSON that refuses NaN and infinity."""
    return json.loads(json.dumps(data, allow_nan=False))


@given(low=st.floats(-300.0, 308.0), decades=st.floats(0.01, 300.0),
       quantity=st.sampled_from(["displacement", "velocity", "acceleration"]))
@SLOW
def test_every_band_is_refused_naming_band_or_answered_with_finite_numbers(heave_lin, low, decades, quantity):
    lo, hi = 10.0**low, 10.0 ** min(low + decades, 308.0)
    if not lo < hi:
        return
    try:
        budget, refused = error_budget(heave_lin, quantity=quantity, band=(lo, hi)), ""
    except ParameterError as exc:
        budget, refused = None, str(exc)
    if budget is None:
        assert refused.startswith("band: "), refused
        assert hi > 1e6
        return
    data = strict_json(budget.to_dict())  # no NaN anywhere
    assert data["band"] == [lo, hi]
    assert not any("nan" in line for line in budget.summary_lines())
    assert budget.summary_lines()[0] == f"band {lo:g}-{hi:g} Hz"


def test_a_band_reaching_below_everything_gives_the_budget_of_its_sources(heave_lin):
    """1e-300 Hz as the low edge: the floor (VC-D, from 0.89 Hz) and the force's quasi-static part are what
    they are from 0.01 Hz; no 0/0 from the floor's velocity over (2 pi f)^2."""
    tiny = error_budget(heave_lin, band=(1e-300, 10.0))
    usual = error_budget(heave_lin, band=(1e-2, 10.0))
    np.testing.assert_allclose(tiny.rms, usual.rms, rtol=2e-3)
    assert np.all(np.isfinite(tiny.psd))


def test_a_band_without_sources_says_so_and_notes_each_silent_source(heave_lin):
    budget = error_budget(heave_lin, band=(200.0, 300.0))
    lines = budget.summary_lines()
    assert lines[0] == "band 200-300 Hz"
    assert budget.silent == ("floor:x", "floor:y", "floor:z")
    assert [line for line in lines if line.startswith("note:")] == [
        f"note: floor:{a} has nothing inside the band" for a in "xyz"]
    assert not any("nan" in line for line in lines)
    floor_only = linearise(make(heave_dict(ground={"spectrum": {"vc": "VC-D"}})))
    empty = error_budget(floor_only, band=(200.0, 300.0))
    assert np.all(empty.rms == 0.0)
    assert all("0 nm RMS (no source moves it inside the band)" in line for line in empty.summary_lines()[1:4])
    assert not any("nan" in line for line in empty.summary_lines())


# -- the closed loop against the passive table ---------------------------------------------------------------------


def test_a_loop_with_sensor_noise_a_million_times_too_large_is_worse_than_passive_and_says_so():
    noisy = make(sensed_table(noise_psd=1e-8))  # (m/s)^2/Hz: 1e6 times a geophone's 1e-14
    lin = linearise(noisy)
    closed = error_budget(lin, skyhook(noisy, GAIN, 1000.0))
    passive = error_budget(lin, band=closed.band)
    worse = closed.worse_than_passive()
    assert [(w["point"], w["axis"]) for w in worse] == [("probe", "x"), ("probe", "y"), ("probe", "z")]
    for w in worse:
        assert w["passive"] == pytest.approx(passive.value("probe", w["axis"]), rel=1e-3)
        assert w["closed"] == closed.value("probe", w["axis"])
        assert w["closed"] > w["passive"]
        parts = {s: closed.value("probe", w["axis"], s) for s in closed.sources}
        assert w["largest"] == max(parts, key=parts.__getitem__)
        assert w["largest"].startswith("sensor:")
    assert strict_json(closed.to_dict())["worse_than_passive"] == worse
    lines = closed.worse_lines()
    assert len(lines) == 3
    assert lines[2].startswith("probe:z: the closed loop's ")
    assert f"passive table's {passive.value('probe', 'z') * 1e9:.4g} nm" in lines[2]


def test_a_loop_that_helps_is_not_worse_than_passive():
    quiet = make(sensed_table(noise_psd=1e-14))
    budget = error_budget(linearise(quiet), skyhook(quiet, GAIN, 1000.0))
    assert budget.worse_than_passive() == []
    assert budget.to_dict()["worse_than_passive"] == []
    assert error_budget(linearise(quiet)).to_dict()["worse_than_passive"] == []  # passive: nothing to compare


# -- carriages' travel ---------------------------------------------------------------------------------------------


@given(x=st.floats(-0.85, 0.85), y=st.floats(-0.45, 0.45))
@settings(max_examples=60, deadline=None)
def test_positions_beyond_a_carriages_profile_range_are_refused_naming_it_and_its_travel(x, y):
    scenario = load_scenario("paper-table-3-2-budget")  # x-stage -0.7 .. 0.7 m, y-stage -0.3 .. 0.3 m
    np.testing.assert_allclose(scenario.travel(), [[-0.7, 0.7], [-0.3, 0.3]], atol=1e-12)
    inside = {"x-stage": abs(x) <= 0.7, "y-stage": abs(y) <= 0.3}
    if all(inside.values()):
        check_travel(scenario, np.array([x, y]))
        return
    first = next(n for n, ok in inside.items() if not ok)
    travel = "-0.7 to 0.7 m" if first == "x-stage" else "-0.3 to 0.3 m"
    with pytest.raises(ParameterError, match=rf"^positions.{first}: \S+ m is beyond the carriage's travel, "
                                             rf"{travel} \(its profile's range\)$"):
        check_travel(scenario, np.array([x, y]))


def test_a_sequences_travel_is_its_start_and_targets_and_the_budget_checks_positions():
    scenario = load_scenario("paper-table-3-2-sequence")
    names = [c.name for c in scenario.carriages]
    q = scenario.sequence.configurations(names)  # type: ignore[union-attr]
    np.testing.assert_allclose(scenario.travel(), np.column_stack([q.min(axis=0), q.max(axis=0)]))
    with pytest.raises(ParameterError, match=r"the \[sequence\]'s start and targets"):
        check_travel(scenario, q.max(axis=0) + 0.01)
    with pytest.raises(ParameterError, match=r"^positions.x-stage: 0.75 m is beyond the carriage's travel"):
        error_budget(load_scenario("paper-table-3-2-budget"), positions={"x-stage": 0.75})


# -- the figure ----------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def probe_figure():
    import matplotlib

    matplotlib.use("Agg")
    budget = error_budget(load_scenario("paper-table-3-2-budget"), points=["probe"])
    figure = budget.plot()
    yield budget, figure
    import matplotlib.pyplot as plt

    plt.close(figure)


def test_the_figures_legend_is_readable_and_finished(probe_figure):
    budget, figure = probe_figure
    panel, twin = figure.axes[0], figure.axes[3]  # probe:x and its cumulative axis
    labels = [t.get_text() for t in twin.get_legend().get_texts()]
    assert labels[0] == "total (2624 nm RMS)"  # not 2.62e+03
    assert not any("e+" in label for label in labels)
    parts = sorted(budget.source_rms[0, 0] * 1e9, reverse=True)
    assert f"floor:x ({parts[0]:.0f} nm)" in labels
    smaller = [label for label in labels if "smaller" in label]
    assert smaller == [f"4 smaller sources, each at most {parts[6]:.1f} nm"]
    lines = {line.get_label(): line for line in panel.get_lines()}
    total, dominant = lines["total (2624 nm RMS)"], lines[f"floor:x ({parts[0]:.0f} nm)"]
    assert dominant.get_zorder() > total.get_zorder()  # the source that makes the total shows on top of it
    cumulative = next(line for line in twin.get_lines() if line.get_label() == "cumulative RMS")
    colours = {matplotlib_colour(line.get_color()) for line in panel.get_lines() if line is not total}
    assert matplotlib_colour(cumulative.get_color()) not in colours


def matplotlib_colour(colour: object) -> tuple[float, ...]:
    from matplotlib.colors import to_rgba

    return tuple(round(c, 6) for c in to_rgba(colour))  # type: ignore[arg-type]


@given(low=st.floats(-3.0, 5.0), decades=st.floats(0.005, 6.0), width=st.sampled_from([5.0, 3.0]))
@settings(max_examples=25, deadline=None)
def test_frequency_tick_labels_never_overlap(low, decades, width):
    import matplotlib.pyplot as plt

    from isolator.analysis.budget.figure import _frequency_ticks

    lo, hi = 10.0**low, 10.0 ** (low + decades)
    fig, ax = plt.subplots(figsize=(width, 3.0))
    try:
        ax.loglog([lo, hi], [1.0, 2.0])
        ax.set_xlim(lo, hi)
        _frequency_ticks(ax, lo, hi)
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
        shown = [t for t in ax.get_xticklabels(which="both") if t.get_visible() and t.get_text()
                 and lo * (1 - 1e-9) <= t.get_position()[0] <= hi * (1 + 1e-9)]
        boxes = sorted((t.get_window_extent(renderer) for t in shown), key=lambda b: b.x0)
        assert len(boxes) >= 2, (lo, hi)
        for a, b in itertools.pairwise(boxes):
            assert a.x1 <= b.x0, (lo, hi)
    finally:
        plt.close(fig)
