"""Every public function and class has a complete numpydoc docstring, checked by numpydoc's own validation.

Public: the names in ``__all__`` of the packages the API reference documents (``isolator``,
``isolator.sweep``, ``controllers.profiles``, ``controllers.feedforward``, ``controllers.feedback``) and
every ``run_*_study`` of the ``studies`` modules. Enforced (numpydoc.validate's codes):

- GL08: there is a docstring;
- PR01 / PR02: every parameter is documented, and nothing documented that the signature does not take;
- PR07: every documented parameter is described;
- RT01 / RT03: a function that returns something has a Returns section, described.

A class documents its constructor's parameters in Parameters or, for the dataclasses whose fields are
their attributes, in Attributes (numpydoc's PR01 only looks at Parameters, so the classes are checked by
numpydoc's parsed sections against the signature). The docstrings' Examples run as doctests
(``--doctest-modules``); there are at least 20.
"""

from __future__ import annotations

import doctest
import importlib
import inspect
import pkgutil
import sys
from collections.abc import Callable

import pytest
from numpydoc.docscrape import ClassDoc
from numpydoc.validate import validate

import controllers
import isolator
import studies

MODULES = ("isolator", "isolator.sweep", "controllers.profiles", "controllers.feedforward", "controllers.feedback")
FUNCTION_CODES = {"GL08", "PR01", "PR02", "PR07", "RT01", "RT03"}
CLASS_CODES = {"GL08", "PR02", "PR07"}


def _public() -> dict[str, object]:
    """Each public function and class once, by the name the reference shows it under."""
    found: dict[str, object] = {}
    seen: set[int] = set()
    for module_name in MODULES:
        module = importlib.import_module(module_name)
        for name in module.__all__:
            obj = getattr(module, name)
            if (inspect.isfunction(obj) or inspect.isclass(obj)) and id(obj) not in seen:
                seen.add(id(obj))
                found[f"{module_name}.{name}"] = obj
    for info in pkgutil.iter_modules(studies.__path__):
        module = importlib.import_module(f"studies.{info.name}")
        for name in getattr(module, "__all__", ()):
            if name.startswith("run_") and name.endswith("_study"):
                found[f"studies.{info.name}.{name}"] = getattr(module, name)
    return found


PUBLIC = _public()
#: docstrings not complete yet, each with why; the test fails when one is completed (then remove it here)
KNOWN_GAPS: dict[str, str] = {}


def _class_undocumented(cls: type) -> list[str]:
    """The constructor's parameters documented neither in Parameters nor in Attributes."""
    doc = ClassDoc(cls, config={"show_class_members": False})
    documented = {part.strip().lstrip("*") for section in ("Parameters", "Attributes", "Other Parameters")
                  for entry in doc[section] for part in entry.name.split(",")}
    try:
        parameters = inspect.signature(cls).parameters
    except (TypeError, ValueError):  # no Python signature (a C extension's class)
        return []
    return [name for name, parameter in parameters.items() if not name.startswith("_")
            and parameter.kind not in (parameter.VAR_POSITIONAL, parameter.VAR_KEYWORD) and name not in documented]


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.xfail(reason=KNOWN_GAPS[n], strict=True))
                                  if n in KNOWN_GAPS else n for n in sorted(PUBLIC)])
def test_the_docstring_is_complete(name: str):
    obj = PUBLIC[name]
    codes = CLASS_CODES if inspect.isclass(obj) else FUNCTION_CODES
    errors = [f"{code}: {message}" for code, message in validate(name)["errors"] if code in codes]
    if inspect.isclass(obj):
        errors += [f"parameter {p!r} documented neither in Parameters nor in Attributes"
                   for p in _class_undocumented(obj)]
    assert not errors, f"{name}:\n" + "\n".join(errors)


def test_the_check_finds_what_is_missing():
    """The validation fails a docstring without its sections (a test that cannot fail checks nothing)."""

    def undocumented(scenario: object, model: str = "exact") -> float:
        """One line, as ``isolator.simulate`` had."""
        return 0.0

    module = type(inspect)("docstring_probe")
    module.undocumented = undocumented  # type: ignore[attr-defined]
    undocumented.__module__ = "docstring_probe"
    sys.modules["docstring_probe"] = module
    try:
        codes = {code for code, _ in validate("docstring_probe.undocumented")["errors"]}
    finally:
        del sys.modules["docstring_probe"]
    assert {"PR01", "RT01"} <= codes


def test_the_public_names_are_many():
    assert len(PUBLIC) >= 150


def _examples(package: object) -> list[str]:
    finder = doctest.DocTestFinder()
    names = []
    for info in pkgutil.walk_packages(package.__path__, package.__name__ + "."):  # type: ignore[attr-defined]
        if info.name.endswith("__main__"):
            continue
        module = importlib.import_module(info.name)
        names += [test.name for test in finder.find(module) if test.examples and test.name.startswith(info.name)]
    return names


def test_at_least_twenty_docstrings_have_examples_that_run():
    """``--doctest-modules`` runs them (pyproject's ``addopts``); here: that there are enough of them."""
    names = _examples(isolator) + _examples(controllers) + _examples(studies)
    assert len(set(names)) >= 20, sorted(set(names))


def test_load_scenario_names_every_bundled_scenario():
    text: Callable[..., object] = isolator.load_scenario
    for name in isolator.bundled_scenarios():
        assert f"``{name}``" in (text.__doc__ or ""), name
