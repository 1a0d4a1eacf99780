"""The trade-off figure's marker size has a scale: a legend of stiffness factors, each marker sized as the
designs' markers of that stiffness are."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.legend import Legend

import studies.tradeoff_report as report
from isolator import load_scenario
from studies.tradeoff import run_tradeoff_study


@pytest.fixture(scope="module")
def figures(tmp_path_factory):
    kept = {}
    patch = pytest.MonkeyPatch()
    patch.setattr(report, "save_figure", lambda fig, path, dpi=120: kept.__setitem__(path.name, fig))
    try:
        study = run_tradeoff_study(tmp_path_factory.mktemp("tradeoff"), load_scenario("paper-table-3-2"),
                                   stiffness=[0.5, 1.0, 2.0], damping=[1.0, 2.0], progress=False)
    finally:
        patch.undo()
    return study, kept


def test_the_marker_size_has_a_scale(figures):
    study, kept = figures
    ax = kept["tradeoff.png"].axes[0]
    scales = [a for a in ax.get_children() if isinstance(a, Legend) and a is not ax.get_legend()]
    assert len(scales) == 1
    scale = scales[0]
    assert scale.get_title().get_text() == "stiffness scale\n(x the scenario's)"
    assert [t.get_text() for t in scale.get_texts()] == ["x0.5", "x1", "x2"]
    assert list(study.stiffness) == [0.5, 1.0, 2.0]
    # each marker of the scale is as large as the designs' markers of that stiffness
    designs = ax.collections[0]
    sizes = designs.get_sizes()  # points^2, one per design drawn, stiffness-major
    drawn = {round(float(s), 9) for s in sizes}
    for handle in scale.legend_handles:
        assert round(handle.get_markersize() ** 2, 9) in drawn
    assert np.all(np.diff([h.get_markersize() for h in scale.legend_handles]) > 0)
    assert "design (size: stiffness)" in [t.get_text() for t in ax.get_legend().get_texts()]
