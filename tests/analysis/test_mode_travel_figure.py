"""The modes-over-travel figure names each mode by its dominant motion, as the table knows it."""

from __future__ import annotations

from itertools import groupby

from isolator import linearise, load_scenario, modes, modes_over_travel


def test_each_curve_is_named_by_its_dominant_motion():
    scenario = load_scenario("paper-table-3-2")
    travel = modes_over_travel(scenario, samples=3)
    fig = travel.plot()
    for j, name in enumerate(travel.carriages):
        top = fig.axes[j]
        legend = top.get_legend()
        assert legend.get_title().get_text() == "dominant motion"
        texts = [t.get_text() for t in legend.get_texts()]
        assert not [t for t in texts if t.startswith("mode")]
        # each label: the dominant motions of that mode at the positions swept, as modes() names them there
        for k, text in enumerate(texts):
            at = [modes(linearise(scenario, positions={name: q})).dominant[k] for q in travel.positions[j]]
            assert text.split(" → ") == [motion for motion, _ in groupby(at)]
        assert [ln.get_label() for ln in top.get_lines()] == texts
    assert fig.axes[0].get_legend().get_texts()[0].get_text() == "y"  # the lowest mode: sway along y
