"""Write the API reference pages from the packages' ``__all__``, so that no public name goes undocumented.

Each page lists its names in autosummary tables (one generated page per name, from the templates in
``_templates/autosummary``), grouped by the subpackage that defines them. The pages are rewritten at every
build (``docs/conf.py``) and not kept in git.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
from pathlib import Path

#: (page, module, title, intro) of every page written from a module's ``__all__``
PAGES = (
    ("isolator", "isolator", "The plant: ``isolator``",
     "Scenarios, models, simulation, settling, linear analysis, calibration: everything ``import isolator`` gives."),
    ("sweep", "isolator.sweep", "Sweeps: ``isolator.sweep``",
     "Many designs of one scenario, locally or on any executor (Dask, MPI)."),
    ("profiles", "controllers.profiles", "Motion profiles: ``controllers.profiles``",
     "Moves that leave the table quiet: move design, input shaping, time-optimal moves, profile optimisation."),
    ("feedforward", "controllers.feedforward", "Feedforward: ``controllers.feedforward``",
     "Cancelling the carriages' reaction from the planned motion, by allocation or optimisation."),
    ("feedback", "controllers.feedback", "Feedback: ``controllers.feedback``",
     "Feedback designs on the linearised plant, closed loops, sampled laws and exported controllers."),
)

#: the subpackages of ``isolator`` in the order its page shows them, with a heading each
ISOLATOR_GROUPS = (
    ("isolator.scenario", "Scenarios"),
    ("isolator.model", "Models"),
    ("isolator.simulation", "Simulation and settling"),
    ("isolator.analysis", "Linear analysis"),
    ("isolator.calibration", "Calibration"),
    ("isolator.sweep", "Sweeps"),
    ("isolator.errors", "Errors"),
)



def _defining_module(obj: object, fallback: str) -> str:
    module = getattr(obj, "__module__", None)
    return module if isinstance(module, str) and not inspect.ismodule(obj) else fallback


def _table(module: str, names: list[str]) -> list[str]:
    return ["", f".. currentmodule:: {module}", "", ".. autosummary::", "   :toctree: generated/", "",
            *(f"   {name}" for name in names), ""]


def _heading(text: str, char: str) -> list[str]:
    return [text, char * len(text)]


def module_page(module_name: str, title: str, intro: str) -> str:
    module = importlib.import_module(module_name)
    names = list(module.__all__)
    lines = [*_heading(title, "="), "", intro, "", f".. automodule:: {module_name}", "   :no-members:", ""]
    if module_name == "isolator":  # a name another page documents (the sweep's result) is linked, not repeated
        sweep = importlib.import_module("isolator.sweep")
        shared = [n for n in names if n in sweep.__all__ and getattr(sweep, n) is getattr(module, n)]
        names = [n for n in names if n not in shared]
    if module_name == "isolator":
        grouped: dict[str, list[str]] = {prefix: [] for prefix, _ in ISOLATOR_GROUPS}
        for name in names:
            where = _defining_module(getattr(module, name), "isolator.scenario")
            prefix = next((p for p, _ in ISOLATOR_GROUPS if where.startswith(p)), "isolator.scenario")
            if isinstance(getattr(module, name), (str, tuple, dict, frozenset)) and name.isupper():
                prefix = {"SIGNALS": "isolator.scenario", "VC_CLASSES": "isolator.analysis"}.get(name, "isolator.model")
            grouped[prefix].append(name)
        for prefix, heading in ISOLATOR_GROUPS:
            if grouped[prefix]:
                lines += ["", *_heading(heading, "-"), *_table(module_name, grouped[prefix])]
            if prefix == "isolator.sweep" and shared:
                lines += ["", *_heading(heading, "-"), "",
                          *(f"``isolator.{n}`` is :class:`isolator.sweep.{n}`." for n in shared), ""]
    else:
        lines += _table(module_name, names)
    return "\n".join(lines) + "\n"


def studies_page() -> str:
    lines = [*_heading("Studies: ``studies``", "="), "",
             "Reproducible studies built on the public API; each writes figures, tables and ``report.md``",
             "into a folder (``isolator study NAME --out DIR`` runs the same).", ""]
    entries = []
    package = importlib.import_module("studies")
    for info in sorted(pkgutil.iter_modules(package.__path__), key=lambda m: m.name):  # every study, by itself
        module = importlib.import_module(f"studies.{info.name}")
        entries += [f"studies.{info.name}.{n}" for n, f in vars(module).items()
                    if n.startswith("run_") and n.endswith("_study") and inspect.isfunction(f)
                    and f.__module__ == module.__name__]
    lines += ["", ".. autosummary::", "   :toctree: generated/", "", *(f"   {e}" for e in entries), ""]
    return "\n".join(lines)


def write_api_pages(folder: Path) -> None:
    """Write one ``.rst`` page per entry of :data:`PAGES` and the studies' page into ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    pages = {f"{page}.rst": module_page(module, title, intro) for page, module, title, intro in PAGES}
    pages["studies.rst"] = studies_page()
    for filename, text in pages.items():
        path = folder / filename
        if not path.exists() or path.read_text(encoding="utf-8") != text:  # unchanged pages keep Sphinx's cache
            path.write_text(text, encoding="utf-8")
