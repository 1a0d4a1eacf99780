"""Issue 26, item 3: every public name, given arguments of the wrong type, raises one ParameterError naming
an argument (never an AttributeError from deep inside). The names are walked, so names added later are
covered too: ``isolator.__all__``, the ``__all__`` of ``controllers``' sub-packages and of every module of
``studies``."""

from __future__ import annotations

import importlib
import inspect
import pkgutil
from pathlib import Path

import pytest

import controllers
import isolator
import studies
from isolator import ParameterError, SimulationSettings, Simulator, load_scenario


class _Wrong:
    """An argument no public function takes."""


def _public() -> list[tuple[str, object]]:
    out = [(f"isolator.{n}", getattr(isolator, n)) for n in isolator.__all__]
    for package in (controllers, studies):
        for info in pkgutil.walk_packages(package.__path__, package.__name__ + "."):
            if info.name.endswith(".cli"):  # the command line's entry points (argparse's subparsers)
                continue
            module = importlib.import_module(info.name)
            out += [(f"{info.name}.{n}", getattr(module, n)) for n in getattr(module, "__all__", ())]
    return out


def _callables() -> list[tuple[str, object]]:
    seen, out = set(), []
    for name, obj in _public():
        if id(obj) in seen or not callable(obj) or (inspect.isclass(obj) and issubclass(obj, BaseException)):
            continue
        if inspect.isclass(obj) and getattr(obj, "_is_protocol", False):
            continue
        seen.add(id(obj))
        out.append((name, obj))
    return out


def _arguments(obj: object) -> tuple[list[str], dict[str, object]]:
    """Every parameter without a default given a wrong value (the first one when all have defaults)."""
    parameters = [p for p in inspect.signature(obj).parameters.values()
                  if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]
    required = [p for p in parameters if p.default is p.empty] or parameters[:1]
    return [p.name for p in required], {p.name: _Wrong() for p in required}


@pytest.mark.parametrize(("name", "obj"), _callables(), ids=[n for n, _ in _callables()])
def test_a_wrong_type_is_a_parameter_error_naming_the_argument(name, obj):
    names, kwargs = _arguments(obj)
    if not names:
        pytest.skip(f"{name} takes no arguments")
    with pytest.raises(ParameterError) as caught:
        obj(**kwargs)
    message = str(caught.value)
    assert message.split(":")[0] in names, message
    assert "\n" not in message


@pytest.mark.parametrize("function", [isolator.simulate, isolator.stability, isolator.modes_over_travel,
                                      isolator.run_sequence, Simulator])
def test_functions_taking_a_scenario_take_its_bundled_name_or_its_path(function):
    name = "paper-table-3-2-sequence" if function is isolator.run_sequence else "paper-table-3-2"
    path = isolator.bundled_scenarios()[name]
    by_name, by_path = function(name), function(Path(path))
    assert type(by_name) is type(by_path)


def test_the_issues_examples_name_their_argument():
    for call, argument in [(lambda: isolator.modes(None), "lin"), (lambda: isolator.transmissibility("x"), "lin"),
                           (lambda: isolator.compliance(42), "lin"), (lambda: isolator.run_sequence(42), "scenario"),
                           (lambda: Simulator(3.5), "scenario")]:
        with pytest.raises(ParameterError, match=f"^{argument}: must be "):
            call()


def test_dataclasses_refuse_bad_values_when_built():
    with pytest.raises(ParameterError, match=r"^SimulationSettings.duration: must be > 0, got -1"):
        SimulationSettings(duration=-1)
    with pytest.raises(ParameterError, match=r"^Table.mass: must be > 0"):
        isolator.Table(mass=-3.0, inertia=(1.0, 1.0, 1.0))


def test_run_changes_take_the_names_a_sweep_takes():
    sim = Simulator(load_scenario("paper-table-3-2"))
    star = sim.parameter_vector({"isolators[*].damping": 5e4})
    each = sim.parameter_vector({f"isolators[{i}].damping.{a}": 5e4 for i in range(4) for a in "xyz"})
    assert (star == each).all()
    with pytest.raises(ParameterError, match=r"^changes\['isolators\[\*\].dampin'\]: not a parameter"):
        sim.parameter_vector({"isolators[*].dampin": 1.0})
