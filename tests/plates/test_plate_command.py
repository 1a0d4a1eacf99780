"""Issue 40, items 4 and 6: ``isolator plate-modes`` (files written, bad options refused in one line with
nothing written), the mode-shape figure, and the bundled modal file of the paper's table 3.2 top."""

from __future__ import annotations

import tomllib

import matplotlib
import numpy as np
import pytest

from isolator import ParameterError, bundled_scenarios, plate_modes, plot_mode_shapes
from isolator.cli.app import main

matplotlib.use("Agg")

TOP = ["--size", "2,1,0.3", "--mass", "4400", "--young", "50e9", "--poisson", "0.25"]
#: how the bundled file was made: isolator plate-modes ... --young 50e9 --poisson 0.25 --count 20 --model solid
BUNDLED = {"young": 50e9, "poisson": 0.25, "count": 20, "model": "solid"}


def test_the_command_writes_the_modal_file_and_the_figure(tmp_path, capsys):
    out, plot = tmp_path / "new" / "top.csv", tmp_path / "new" / "modes.png"
    assert main(["plate-modes", str(out), *TOP, "--count", "4", "--plot", str(plot)]) == 0
    text = capsys.readouterr().out
    assert "4 elastic modes, 193.2 to 517.3 Hz, and 6 rigid ones at 325 nodes" in text
    assert f"modes: {out}" in text
    assert f"figure: {plot}" in text
    api = plate_modes((2.0, 1.0, 0.3), 4400.0, 50e9, 0.25, count=4).to_csv(tmp_path / "api.csv")
    assert out.read_text() == api.read_text()
    assert plot.read_bytes()[:4] == b"\x89PNG"
    assert sorted(p.name for p in out.parent.iterdir()) == ["modes.png", "top.csv"]  # no temporary left


def test_the_solid_model_writes_two_faces_without_rotations(tmp_path):
    out = tmp_path / "solid.csv"
    assert main(["plate-modes", str(out), *TOP, "--count", "2", "--model", "solid"]) == 0
    lines = out.read_text().splitlines()
    assert lines[0] == "mode,frequency_hz,damping,x,y,z,ux,uy,uz"
    z = {float(line.split(",")[5]) for line in lines[1:]}
    assert z == {-0.15, 0.15}


BAD_OPTIONS = [
    (["--mass", "0"], "--mass: must be positive"),
    (["--mass", "-4400"], "--mass: must be positive"),
    (["--poisson", "0.5"], "--poisson: must lie between -1 and 0.5"),
    (["--poisson", "-1"], "--poisson: must lie between -1 and 0.5"),
    (["--size", "2,-1,0.3"], "--size: every entry must be positive"),
    (["--size", "2,1,0"], "--size: every entry must be positive"),
    (["--size", "2,1"], "--size: expected LX,LY,T"),
    (["--count", "0"], "--count: must be a whole number >= 1"),
    (["--young", "nan"], "--young: must be finite"),
    (["--elements", "1"], "--elements: must be a whole number >= 2"),
    (["--face-thickness", "0.2"], "--face-thickness: a face sheet must be thinner"),
    (["--max-frequency", "50"], "--max-frequency: no elastic mode up to 50 Hz"),
]


@pytest.mark.parametrize(("change", "message"), BAD_OPTIONS, ids=[" ".join(c) for c, _ in BAD_OPTIONS])
def test_bad_options_are_one_line_naming_the_option_and_nothing_is_written(change, message, tmp_path, capsys):
    arguments = list(TOP)
    for option, value in zip(change[::2], change[1::2], strict=True):
        if option in arguments:
            arguments[arguments.index(option) + 1] = value
        else:
            arguments += [option, value]
    out = tmp_path / "sub" / "top.csv"
    assert main(["plate-modes", str(out), *arguments, "--plot", str(tmp_path / "sub" / "m.png")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"isolator: error: {message}"), err
    assert err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


def test_an_output_of_another_kind_is_refused_before_any_work(tmp_path, capsys):
    assert main(["plate-modes", str(tmp_path / "top.txt"), *TOP]) == 2
    assert "OUT.csv: " in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_the_figure_shows_each_elastic_mode_with_its_frequency_and_the_marks():
    top = plate_modes((2.0, 1.0, 0.3), 4400.0, 50e9, 0.25, count=14, grid=(9, 5))
    corners = [[1.0, 0.5], [-1.0, 0.5], [-1.0, -0.5], [1.0, -0.5]]
    fig = plot_mode_shapes(top.nodes, top.translations, top.frequency_hz, isolators=corners,
                           feet=[[0.3, 0.1, 0.15]], title="table 3.2")
    panels = [ax for ax in fig.axes if ax.get_visible() and ax.get_title()]
    assert len(panels) == 12  # rigid modes skipped, at most twelve
    assert panels[0].get_title() == "elastic mode 1: 193.2 Hz"
    assert panels[0].get_xlabel() == ""
    assert panels[-1].get_xlabel() == "x [m]"
    marks = {line.get_label(): line.get_xydata() for line in panels[0].get_lines()}
    np.testing.assert_allclose(marks["isolators"], corners)
    np.testing.assert_allclose(marks["feet"], [[0.3, 0.1]])
    assert fig._suptitle.get_text() == "table 3.2"
    assert any(ax.get_ylabel().startswith("vertical translation") for ax in fig.axes)  # the colourbar
    with pytest.raises(ParameterError, match=r"^translations: must be an \(n, 45, 3\) array"):
        plot_mode_shapes(top.nodes, top.translations[:, :10], top.frequency_hz)
    with pytest.raises(ParameterError, match=r"^frequencies: no elastic mode"):
        plot_mode_shapes(top.nodes, top.translations[:6], top.frequency_hz[:6])
    import matplotlib.pyplot as plt

    plt.close("all")


def test_the_bundled_top_modes_are_the_generators_for_the_scenarios_top():
    """``paper-table-3-2-top-modes.csv``: the 3-D solid model of the scenario's table (its size and mass)."""
    scenario = bundled_scenarios()["paper-table-3-2"]
    path = scenario.with_name("paper-table-3-2-top-modes.csv")
    table = tomllib.loads(scenario.read_text())["table"]
    assert path.stat().st_size < 700_000
    data = np.genfromtxt(path, delimiter=",", names=True)
    top = plate_modes(table["size"], table["mass"], **BUNDLED)
    frequency = data["frequency_hz"].reshape(26, -1)
    assert np.all(frequency == frequency[:, :1])
    np.testing.assert_allclose(frequency[:, 0], top.frequency_hz, rtol=1e-6, atol=1e-6)
    shapes = np.stack([data[k] for k in ("ux", "uy", "uz")], axis=-1).reshape(26, -1, 3)
    np.testing.assert_allclose(shapes, top.translations, atol=1e-5 * np.abs(top.translations).max())
    nodes = np.stack([data[k] for k in "xyz"], axis=-1).reshape(26, -1, 3)
    np.testing.assert_allclose(nodes[0], top.nodes, atol=1e-6)
