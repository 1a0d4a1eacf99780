"""Points and windows in the transient: point motion (exact rotation of the lever arm), the window rule, the
window settling time read on the dense output whatever the sample rate, and its CSV/JSON/plot."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from conftest import asymmetric_3d_dict, base_dict, make
from isolator import simulate
from isolator.simulation.window_settling import window_exit

POINTS = [{"name": "probe", "position": [0.3, 0.0, 0.45]}, {"name": "corner", "position": [-1.1, 0.7, 0.15]}]


@pytest.fixture(scope="module")
def asymmetric():
    data = asymmetric_3d_dict(duration=2.0)
    data["points"] = POINTS
    data["simulation"]["sample_rate"] = 200.0
    sc = make(data)
    return sc, simulate(sc)


def test_point_motion_is_mass_centre_plus_rotated_lever_arm(asymmetric):
    """Independent of the module: scipy's Rotation of the states' quaternions applied to the lever arm."""
    sc, r = asymmetric
    states = r.states
    rot = Rotation.from_quat(states[:, [4, 5, 6, 3]])  # scipy: (x, y, z, w)
    for pt in sc.points:
        arm = np.asarray(pt.position)
        world = states[:, 0:3] + rot.apply(arm)
        expected = (world - world[0]).T
        np.testing.assert_allclose(r.point(pt.name), expected, rtol=0, atol=1e-15)
    # the rotation is not negligible against the mass centre's motion: the check is not vacuous
    assert np.max(np.abs(r.point("corner") - r.signals[0:3])) > 1e-6


def test_point_motion_matches_mujoco_sites(asymmetric):
    pytest.importorskip("mujoco")
    from isolator.validation.multibody import MujocoTable

    sc, r = asymmetric
    table = MujocoTable(sc)
    # the same states through MuJoCo's kinematics: equal to rounding
    sites = table.point_positions(r.states)
    for i, name in enumerate(r.point_names):
        np.testing.assert_allclose(r.point(name), sites[i] - sites[i][:, :1], rtol=0, atol=1e-14)
    # MuJoCo's own run: the same point motion to the integrators' tolerance
    mb = table.simulate()
    theirs = table.point_positions(mb.states)
    for i, name in enumerate(r.point_names):
        mine, ref = r.point(name), theirs[i] - theirs[i][:, :1]
        assert np.sqrt(np.mean((mine - ref) ** 2)) < 1e-6 * np.sqrt(np.mean(ref**2)), name


def test_point_columns_and_peaks(asymmetric, tmp_path):
    _sc, r = asymmetric
    path = r.to_csv(tmp_path / "r.csv")
    with open(path) as handle:
        rows = list(csv.reader(handle))
    header = rows[0]
    cols = ["probe:x", "probe:y", "probe:z", "corner:x", "corner:y", "corner:z"]
    assert header[header.index("probe:x"):header.index("probe:x") + 6] == cols
    values = np.array(rows[1:], dtype=float)
    np.testing.assert_allclose(values[:, header.index("corner:z")], r.point("corner")[2], rtol=1e-9, atol=1e-18)
    summary = json.loads(json.dumps(r.to_dict()))
    assert summary["point_peak"]["corner"]["z"] == pytest.approx(np.max(np.abs(r.point("corner")[2])))
    assert "window_settling_time" not in summary
    assert r.windows is None
    assert r.window_settling_time == []
    with pytest.raises(KeyError, match="unknown 'lens'"):
        r.point("lens")


# -- the rule on hand-made signals ------------------------------------------------------------------------


def test_window_rule_on_known_crossings():
    """Piecewise linear: enters at 1.5, leaves at 2.5, re-enters at 3.25 (exact under linear interpolation)."""
    t = np.linspace(0.0, 10.0, 1001)
    knots = ([0.0, 1.0, 2.0, 3.0, 3.5, 10.0], [3.0, 2.0, 0.0, 2.0, 0.0, 0.0])
    d = np.interp(t, *knots)
    st, why = window_exit(t, d[None, :], 1.0, stop_time=1.0)
    assert why == ""
    assert st == pytest.approx(3.25 - 1.0, abs=1e-12)
    # on a coarse grid, the exit is refined between the two grid times around it
    coarse = np.array([0.0, 1.0, 3.0, 3.5, 10.0])
    st, _ = window_exit(coarse, np.interp(coarse, *knots)[None, :], 1.0, stop_time=1.0)
    assert st == pytest.approx(2.25, abs=1e-12)
    # the negative edge, and the latest of several axes
    other = np.interp(t, [0.0, 4.0, 4.5, 10.0], [0.0, 0.0, -1.5, 0.0])
    st, _ = window_exit(t, np.vstack([d, other]), 1.0, stop_time=1.0)
    assert st == pytest.approx(4.5 + 5.5 / 3 - 1.0, abs=1e-12)  # -1.5 at 4.5 back to 0 at 10: -1 at 4.5 + 5.5/3


def test_window_rule_edge_cases():
    t = np.linspace(0.0, 5.0, 501)
    inside = 0.5 * np.sin(7 * t)
    assert window_exit(t, inside[None, :], 1.0, 1.0) == (0.0, "")
    # outside before the stop only: 0
    before = np.where(t < 0.9, 3.0, 0.2)
    assert window_exit(t, before[None, :], 1.0, 1.0) == (0.0, "")
    st, why = window_exit(t, np.full((1, t.size), 2.0), 1.0, 1.0)
    assert st is None
    assert "end of the run" in why
    st, why = window_exit(t, inside[None, :], 1.0, 6.0)
    assert st is None
    assert "before the carriages stop" in why
    st, why = window_exit(t, inside[None, :], 1.0, float("inf"))
    assert st is None
    assert "never stop" in why
    late = np.interp(t, [0.0, 4.5, 4.8, 5.0], [0.0, 0.0, 2.0, 0.0])
    st, why = window_exit(t, late[None, :], 1.0, 1.0, hold=1.0)
    assert st is None
    assert "slowest period" in why


# -- window settling of a run -----------------------------------------------------------------------------


def _windowed(rate: float, model: str = "exact"):
    data = base_dict(points=POINTS[:1], windows=[
        {"point": "probe", "translation": 4e-7},
        {"point": "probe", "translation": 1.5e-7, "axes": ["z"]},
    ])
    data["simulation"] = {"duration": 6.0, "sample_rate": rate}
    return simulate(make(data), model=model)


@pytest.fixture(scope="module")
def by_rate():
    return {rate: _windowed(rate) for rate in (5.0, 50.0, 1000.0)}


def test_window_settling_does_not_depend_on_the_sample_rate(by_rate):
    times = np.array([r.window_settling_time for r in by_rate.values()], dtype=float)
    assert np.all(times > 0.1), times  # the windows really are left after the stop
    np.testing.assert_allclose(times, np.broadcast_to(times[-1], times.shape), rtol=0, atol=1e-6)
    r = by_rate[1000.0]
    assert r.window_settling_time_max == max(r.window_settling_time)


def test_window_settling_agrees_with_the_samples_at_1khz(by_rate):
    """Read again on the 1 kHz output samples with the settled position: the same exit."""
    r = by_rate[1000.0]
    settled = r.point_set.settled[0]
    for w, st in zip(r.windows.windows, r.window_settling_time, strict=True):
        dev = r.point("probe")[list(w.axis_indices)] - settled[list(w.axis_indices), None]
        again, _ = window_exit(r.t, dev, w.translation, r.stop_time)
        assert again == pytest.approx(st, abs=1e-9)


def test_window_settling_json_summary_and_plot(by_rate, tmp_path):
    r = by_rate[50.0]
    summary = json.loads(json.dumps(r.to_dict()))
    assert summary["window_settling_time"] == pytest.approx(r.window_settling_time)
    assert summary["window_settling_time_max"] == pytest.approx(max(r.window_settling_time))
    text = r.summary()
    assert "window 0 (probe, ±400 nm on x,y,z):" in text
    assert "window 1 (probe, ±150 nm on z):" in text
    fig = r.plot_windows()
    assert len(fig.axes) == 2
    ax = fig.axes[0]
    assert ax.get_xlabel() == ""
    assert fig.axes[1].get_xlabel() == "time [s]"
    assert "[nm]" in ax.get_ylabel()
    assert ax.get_legend() is not None
    assert fig._suptitle is not None
    fig.savefig(tmp_path / "w.png")


def test_paper_model_window_settling():
    r = _windowed(50.0, model="paper")
    assert all(st is not None and st > 0.1 for st in r.window_settling_time)


def test_short_run_says_so():
    data = base_dict(points=POINTS[:1], windows=[{"point": "probe", "translation": 1e-9}])
    data["simulation"] = {"duration": 3.0, "sample_rate": 100.0}
    r = simulate(make(data))
    assert r.window_settling_time == [None]
    assert r.window_settling_time_max is None
    assert "outside the window when the run ends" in r.windows.reasons[0]
    assert "not available" in r.summary()


def test_cli_writes_the_windows_figure_and_json(tmp_path, capsys):
    from isolator.cli.app import main
    from isolator.scenario.reader import bundled_scenarios

    text = bundled_scenarios()["paper-table-3-2"].read_text()
    text += '\n[[points]]\nname = "probe"\nposition = [0.3, 0.0, 0.45]\n\n[[windows]]\npoint = "probe"\n'
    text += "translation = 5.0e-7\n"
    scenario = tmp_path / "probe.toml"
    scenario.write_text(text)
    plot = tmp_path / "X.png"
    assert main(["simulate", str(scenario), "--plot", str(plot)]) == 0
    assert "settling windows:" in capsys.readouterr().out
    assert (tmp_path / "X-windows.png").stat().st_size > 10_000
    assert main(["simulate", str(scenario), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert len(data["window_settling_time"]) == 1
    assert data["window_settling_time_max"] == pytest.approx(data["window_settling_time"][0])
    assert data["window_settling_time_max"] > 0.5
