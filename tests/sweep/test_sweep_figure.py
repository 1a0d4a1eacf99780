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
    ax = fig.axes[0]
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
    assert len(fig.axes) == 2
    crosses = [ln for ln in fig.axes[0].get_lines() if ln.get_marker() == "x"]
    assert len(crosses) == 1
    assert crosses[0].get_xdata()[0] == 1e3


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
