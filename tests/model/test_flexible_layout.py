"""What a bending top's model refuses, in one line naming why: moving what stands on the top (its shapes were
taken there), the paper's small-angle model, and pneumatic isolators (not modelled yet); what it allows."""

from __future__ import annotations

import pytest
from synthetic_top import with_synthetic_top

from isolator import Simulator
from isolator.errors import IsolatorError, ParameterError
from isolator.model.cache import get_model
from isolator.model.parameters import ParameterLayout


@pytest.mark.parametrize("name", ["isolators[0].position.x", "carriages[0].origin.y", "carriages[1].axis.x"])
def test_moving_what_stands_on_the_top_is_refused(name):
    layout = ParameterLayout.of(with_synthetic_top())
    with pytest.raises(ParameterError, match=r"the top bends"):
        layout.with_changes(layout.pack(with_synthetic_top()), {name: 0.1})


def test_its_numbers_may_change_and_a_rigid_top_moves_freely():
    scenario = with_synthetic_top()
    layout = ParameterLayout.of(scenario)
    p = layout.with_changes(layout.pack(scenario), {"isolators[0].stiffness.z": 6e5, "carriages[0].mass": 300.0})
    assert p[layout.names.index("carriages[0].mass")] == 300.0
    rigid = ParameterLayout.of(Simulator("paper-table-3-2").scenario)
    rigid.with_changes(rigid.pack(Simulator("paper-table-3-2").scenario), {"isolators[0].position.x": 0.9})


def test_the_papers_model_and_pneumatic_isolators_are_refused():
    with pytest.raises(ParameterError, match="paper's model has a rigid top"):
        get_model(ParameterLayout.of(with_synthetic_top()), "paper")
    with pytest.raises(IsolatorError, match=r"table\.flexible"):
        ParameterLayout.of(with_synthetic_top("paper-table-3-2-pneumatic"))


def test_the_compiled_models_name_holds_the_tops_digest():
    flexible = get_model(ParameterLayout.of(with_synthetic_top()))
    other = get_model(ParameterLayout.of(with_synthetic_top(frequencies=(151.0, 220.0, 310.0))))
    assert "_fl3_" in flexible.tag
    assert flexible.tag != other.tag
    assert flexible.n_states == 13 + 2 * 3
