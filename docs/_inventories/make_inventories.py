"""Write the intersphinx inventories (``objects.inv``) of numpy, scipy, python-control, matplotlib and Python.

The documentation builds offline (CI reaches no documentation site), so ``docs/conf.py`` reads these
vendored files instead of downloading the projects' own. The projects' inventories could not be
downloaded where this was written, so this script makes equivalent ones from the installed packages:
each public function, class and method gets the address its project's API reference gives it (the
layouts of numpy's, scipy's, python-control's and matplotlib's Sphinx sites); for Python itself, the
builtins, glossary terms and standard-library names the docstrings use (numpydoc links ``bool``,
``sequence``, ``array_like`` to them). Regenerate after a
major version of one of them::

    python docs/_inventories/make_inventories.py

Replacing a file here by the project's real ``objects.inv`` (same name) works just as well.
"""

from __future__ import annotations

import importlib
import inspect
import sys
import zlib
from collections.abc import Callable, Iterable
from pathlib import Path

HERE = Path(__file__).resolve().parent

#: scipy's subpackages whose public names are linked
SCIPY_SUBPACKAGES = ("fft", "integrate", "interpolate", "linalg", "optimize", "signal", "sparse", "spatial", "stats")


def _public(module: object) -> list[tuple[str, object]]:
    names = getattr(module, "__all__", None) or [n for n in dir(module) if not n.startswith("_")]
    found = []
    for name in sorted(set(names)):
        try:
            found.append((name, getattr(module, name)))
        except AttributeError:
            continue
    return found


def _role(obj: object) -> str | None:
    if inspect.isclass(obj):
        return "py:class"
    if callable(obj):
        return "py:function"
    return None


def _methods(cls: type) -> list[str]:
    return sorted(n for n, v in vars(cls).items() if not n.startswith("_") and callable(v))


def _module_entries(
    dotted: str, page: Callable[[str], str], module_page: str, *, methods: Callable[[str], str] | None = None
) -> Iterable[tuple[str, str, str]]:
    """``(name, role, uri)`` for a module, its public functions and classes (and the classes' methods)."""
    module = importlib.import_module(dotted)
    yield dotted, "py:module", f"{module_page}#module-{dotted}"
    for name, obj in _public(module):
        role = _role(obj)
        if role is None or inspect.ismodule(obj):
            continue
        full = f"{dotted}.{name}"
        yield full, role, f"{page(full)}#{full}"
        if role == "py:class" and methods is not None:
            for method in _methods(obj):  # type: ignore[arg-type]
                yield f"{full}.{method}", "py:method", f"{methods(f'{full}.{method}')}#{full}.{method}"


def write_inventory(path: Path, project: str, version: str, entries: Iterable[tuple[str, str, str]]) -> int:
    """Write a version-2 inventory; returns the number of entries."""
    lines = sorted({f"{name} {role} {-1 if role == 'std:label' else 1} {uri} -" for name, role, uri in entries})
    header = (
        f"# Sphinx inventory version 2\n# Project: {project}\n# Version: {version}\n"
        "# The remainder of this file is compressed using zlib.\n"
    )
    path.write_bytes(header.encode() + zlib.compress(("\n".join(lines) + "\n").encode()))
    return len(lines)


def numpy_entries() -> Iterable[tuple[str, str, str]]:
    def generated(full: str) -> str:
        return f"reference/generated/{full}.html"

    yield from _module_entries("numpy", generated, "reference/index.html")
    for method in _methods(importlib.import_module("numpy").ndarray):
        yield f"numpy.ndarray.{method}", "py:method", f"reference/generated/numpy.ndarray.{method}.html#$"
    for sub in ("linalg", "fft"):
        yield from _module_entries(f"numpy.{sub}", generated, f"reference/routines.{sub}.html")
    yield "numpy.random", "py:module", "reference/random/index.html#module-numpy.random"
    yield "numpy.random.default_rng", "py:function", "reference/random/generator.html#$"
    yield "numpy.random.Generator", "py:class", "reference/random/generator.html#$"
    for method in _methods(importlib.import_module("numpy.random").Generator):
        yield (f"numpy.random.Generator.{method}", "py:method",
               f"reference/random/generated/numpy.random.Generator.{method}.html#$")
    for name in ("ArrayLike", "NDArray", "DTypeLike"):
        yield f"numpy.typing.{name}", "py:data", "reference/typing.html#$"
    yield "array_like", "std:term", "glossary.html#term-array_like"
    yield "arrays.scalars", "std:label", "reference/arrays.scalars.html#arrays-scalars"


def scipy_entries() -> Iterable[tuple[str, str, str]]:
    for sub in SCIPY_SUBPACKAGES:
        yield from _module_entries(f"scipy.{sub}", lambda full: f"reference/generated/{full}.html",
                                   f"reference/{sub}.html")


def control_entries() -> Iterable[tuple[str, str, str]]:
    yield from _module_entries("control", lambda full: f"generated/{full}.html", "index.html",
                               methods=lambda full: f"generated/{full.rsplit('.', 1)[0]}.html")


def matplotlib_entries() -> Iterable[tuple[str, str, str]]:
    def as_gen(full: str) -> str:
        return f"api/_as_gen/{full}.html"

    yield from _module_entries("matplotlib.pyplot", as_gen, "api/pyplot_summary.html")
    yield "matplotlib.figure", "py:module", "api/figure_api.html#module-matplotlib.figure"
    for cls in ("Figure", "SubFigure"):
        yield from _class("matplotlib.figure", cls, as_gen)
    yield "matplotlib.axes", "py:module", "api/axes_api.html#module-matplotlib.axes"
    yield "matplotlib.axes.Axes", "py:class", "api/axes_api.html#$"
    for method in _methods(importlib.import_module("matplotlib.axes").Axes):
        yield f"matplotlib.axes.Axes.{method}", "py:method", f"api/_as_gen/matplotlib.axes.Axes.{method}.html#$"


#: Python's builtins and the standard-library names the docstrings use: (name, role, page)
PYTHON_NAMES = (
    *((n, "py:class", "library/functions.html") for n in ("int", "float", "bool", "complex", "object", "type")),
    *((n, "py:class", "library/stdtypes.html") for n in ("str", "bytes", "list", "tuple", "dict", "set",
                                                          "frozenset", "range")),
    *((n, "py:data", "library/constants.html") for n in ("None", "True", "False", "Ellipsis")),
    *((n, "py:function", "library/functions.html") for n in ("callable", "len", "open", "print", "round")),
    *((f"collections.abc.{n}", "py:class", "library/collections.abc.html")
      for n in ("Callable", "Iterable", "Iterator", "Mapping", "MutableMapping", "Sequence", "Generator")),
    ("collections.namedtuple", "py:function", "library/collections.html"),
    ("contextlib.contextmanager", "py:function", "library/contextlib.html"),
    ("pathlib.Path", "py:class", "library/pathlib.html"),
    ("concurrent.futures.Executor", "py:class", "library/concurrent.futures.html"),
    ("concurrent.futures.ProcessPoolExecutor", "py:class", "library/concurrent.futures.html"),
    ("dataclasses.dataclass", "py:function", "library/dataclasses.html"),
    ("dataclasses.replace", "py:function", "library/dataclasses.html"),
    ("argparse.ArgumentParser", "py:class", "library/argparse.html"),
    ("tempfile.mkdtemp", "py:function", "library/tempfile.html"),
)


def python_entries() -> Iterable[tuple[str, str, str]]:
    for name, role, page in PYTHON_NAMES:
        yield name, role, f"{page}#$"
    for term in ("iterable", "sequence", "generator", "mapping", "callable"):
        yield term, "std:term", f"glossary.html#term-{term}"
    yield "bltin-boolean-values", "std:label", "library/stdtypes.html#boolean-type"


def _class(module: str, name: str, page: Callable[[str], str]) -> Iterable[tuple[str, str, str]]:
    full = f"{module}.{name}"
    cls = getattr(importlib.import_module(module), name)
    yield full, "py:class", f"{page(full)}#$"
    for method in _methods(cls):
        yield f"{full}.{method}", "py:method", f"{page(f'{full}.{method}')}#$"


def main() -> None:
    import control
    import matplotlib
    import numpy
    import scipy

    for filename, project, version, entries in (
        ("numpy.inv", "NumPy", numpy.__version__, numpy_entries()),
        ("scipy.inv", "SciPy", scipy.__version__, scipy_entries()),
        ("control.inv", "Python Control Systems Library", control.__version__, control_entries()),
        ("matplotlib.inv", "Matplotlib", matplotlib.__version__, matplotlib_entries()),
        ("python.inv", "Python", f"{sys.version_info.major}.{sys.version_info.minor}", python_entries()),
    ):
        count = write_inventory(HERE / filename, project, version, entries)
        print(f"{filename}: {count} entries ({project} {version})")


if __name__ == "__main__":
    main()
