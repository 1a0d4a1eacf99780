"""The built-model cache: one :class:`~isolator.model.variants.Model` per structure and variant, built once.

Every consumer (simulation, linearisation, stability, optimisation) gets its model here, so a structure's
casadi functions are built once per process.
"""

from __future__ import annotations

from isolator.model.parameters import ParameterLayout
from isolator.model.variants import EXACT, Model, ModelVariant, model_variant
from isolator.scenario.arguments import check_public

__all__ = ["get_model"]

_MODELS: dict[tuple[ParameterLayout, ModelVariant], Model] = {}


def get_model(layout: ParameterLayout, variant: str | ModelVariant = EXACT) -> Model:
    """The (cached) model of a structure.

    Parameters
    ----------
    layout : ParameterLayout
        The scenario's structure.
    variant : ModelVariant or {"exact", "paper"}
        Which equations; a bad name is a :class:`~isolator.errors.ParameterError` naming ``model``.

    Returns
    -------
    Model
        The casadi functions of the structure's equations of motion, built once per structure and variant
        (and compiled, when a C compiler is there) and cached.
    """
    chosen = model_variant(variant)
    key = (layout, chosen)
    if key not in _MODELS:
        _MODELS[key] = chosen.build(layout)
    return _MODELS[key]


check_public(globals(), ("get_model"))
