"""The sweep's figure: a grid as lines per outer value, samples as dots per swept name, failures marked."""

from __future__ import annotations

import numpy as np

from isolator.cli.app import main
from isolator.sweep import sweep
from isolator.sweep.figure import plot_sweep


def test_a_grid_is_drawn_as_lines_per_outer_value():
    result = sweep("paper-table-3-2", scale={"isolators[*].stiffness": [0.5, 1.0],
                                             "isolators[*].damping": [0.5, 1.0, 2.0]}, workers=1)
    fig = plot_sweep(result)
    ax = fig.axes[-1]  # below the strip of designs without a settling time
    lines = [ln for ln in ax.get_lines() if ln.get_linestyle() == "-"]
    assert len(lines) == 2  # one per stiffness factor
    for line in lines:
        assert np.all(np.isin(line.get_xdata(), [0.5, 1.0, 2.0]))
    assert "settling time" in ax.get_ylabel()


def test_samples_get_a_panel_per_name_and_failures_are_marked():
    # the softest vertical stiffness lets the table tip: those designs are crosses along the top
    result = sweep("paper-table-3-2", set={"isolators[*].stiffness.z": [1e3, 5.7e5], "carriages[0].mass": [300, 500]},
                   zip=True, workers=1)
    fig = plot_sweep(result)
    strips, panels = fig.axes[:2], fig.axes[2:]
    assert len(panels) == 2
    assert [ax.get_xlabel() for ax in panels] == ["isolators[*].stiffness.z [N/m]", "carriages[0].mass [kg]"]
    crosses = strips[0].collections[0].get_offsets()
    assert crosses.shape == (1, 2)
    assert crosses[0, 0] == 1e3
    # no cross on the seconds axis: every point drawn there is a design with a settling time
    for ax in panels:
        assert not [ln for ln in ax.get_lines() if ln.get_marker() == "x"]
        assert np.all(np.isfinite(np.concatenate([ln.get_ydata() for ln in ax.get_lines()])))
    legend = [text.get_text() for text in panels[0].get_legend().get_texts()]
    assert legend == ["designs", "no settling time within the run (strip above)"]
    assert strips[0].get_ylabel() == "no settling time"


def test_a_grid_marks_its_unsettled_designs_in_a_strip_row_per_outer_value():
    result = sweep("paper-table-3-2", scale={"isolators[*].stiffness": [0.5, 1.0],
                                             "isolators[*].damping": [0.05, 1.0]}, workers=1)
    bad = ~np.isfinite(result["settling_time_max"])
    assert bad.any()
    fig = plot_sweep(result)
    strip, ax = fig.axes
    crosses = strip.collections[0].get_offsets()
    np.testing.assert_array_equal(crosses[:, 0], result["isolators[*].damping"][bad])
    np.testing.assert_array_equal(crosses[:, 1], np.searchsorted([0.5, 1.0], result["isolators[*].stiffness"][bad]))
    assert ax.get_xlabel() == "isolators[*].damping: factor on the scenario's value [-]"
    legend = ax.get_legend()
    assert legend.get_title().get_text() == "isolators[*].stiffness: factor on the scenario's value [-]"
    assert [t.get_text() for t in legend.get_texts()][-1].startswith("no settling time within the run")


def test_a_sequence_is_drawn_by_its_total_time():
    # a sequence's 5 % settling columns are NaN by design: its designs are not "without a settling time"
    result = sweep("paper-table-3-2-sequence", scale={"isolators[*].damping": [0.5, 1.0, 2.0]}, workers=1)
    fig = plot_sweep(result)
    ax = fig.axes[0]
    assert ax.get_ylabel() == "total time of the sequence [s]"
    assert [ln for ln in ax.get_lines() if ln.get_marker() == "x"] == []
    dots = [ln for ln in ax.get_lines() if ln.get_marker() == "o"]
    np.testing.assert_array_equal(dots[0].get_ydata(), result["total_time"])
    assert fig.get_suptitle() == "3 designs, 0 without a total time (none)"


def test_sweep_command_writes_the_figure(tmp_path, capsys):
    png = tmp_path / "sweep.png"
    assert main(["sweep", "paper-table-3-2", "--scale", "isolators[*].damping=0.5:2:3", "--workers", "1",
                 "--out", str(tmp_path / "rows.csv"), "--plot", str(png)]) == 0
    assert png.stat().st_size > 10_000
    assert f"figure: {png}" in capsys.readouterr().out


def test_sweep_command_refuses_a_bad_figure_path_before_running(tmp_path, capsys):
    assert main(["sweep", "paper-table-3-2", "--scale", "isolators[*].damping=0.5:2:3", "--workers", "1",
                 "--out", str(tmp_path / "rows.csv"), "--plot", str(tmp_path / "sweep.xyz")]) == 2
    assert "--plot" in capsys.readouterr().err
    assert not (tmp_path / "rows.csv").exists()
