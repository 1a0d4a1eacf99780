"""The code base keeps its checks: ruff clean, mypy clean, the import contracts, short modules, and
no imports of another library's private modules (see docs/ARCHITECTURE.md, "Checks that keep it so")."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: the packages whose modules the size and import rules cover
PACKAGES = ("isolator", "controllers", "studies")
#: the most lines a module of those packages may have
MAX_LINES = 400
#: an ``import a.b`` or ``from a.b import c`` line (its dotted module path in group 1 or 2)
_IMPORT = re.compile(r"^\s*(?:from\s+([\w.]+)\s+import\b|import\s+([\w.]+(?:\s*,\s*[\w.]+)*))", re.MULTILINE)


def _tool(name: str) -> str:
    """The tool's executable (next to this Python first, then on PATH), or skip the test."""
    local = Path(sys.executable).with_name(name)
    found = str(local) if local.exists() else shutil.which(name)
    if found is None:
        pytest.skip(f"{name} is not installed")
    return found


def _modules() -> list[Path]:
    return sorted(path for package in PACKAGES for path in (ROOT / package).rglob("*.py"))


def private_imports(source: str) -> list[str]:
    """The dotted module paths imported in ``source`` that reach into another library's private
    module: a component after the first that starts with ``_`` (``scipy.integrate._ivp``), in a
    package that is not ours. Relative imports, ``__future__`` and dunder modules (``__main__``) pass."""
    found = []
    for match in _IMPORT.finditer(source):
        paths = [match[1]] if match[1] else [p.strip() for p in match[2].split(",")]
        for path in paths:
            parts = path.split(".")
            if path.startswith(".") or parts[0] in PACKAGES or parts[0] == "__future__":
                continue
            if any(p.startswith("_") and not (p.startswith("__") and p.endswith("__")) for p in parts[1:]):
                found.append(path)
    return found


def test_ruff_clean():
    proc = subprocess.run([_tool("ruff"), "check", str(ROOT)], capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_mypy_clean():
    """``mypy`` with the configuration in pyproject.toml (its ``files``: the three packages)."""
    pytest.importorskip("mypy")
    proc = subprocess.run(
        [sys.executable, "-m", "mypy", "--no-error-summary"], capture_output=True, text=True, cwd=ROOT
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_import_contracts_kept():
    """The import-linter contracts in pyproject.toml: package layers, layers inside the plant, no cycles."""
    proc = subprocess.run([_tool("lint-imports")], capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr


def test_no_module_is_too_long():
    long = {
        str(path.relative_to(ROOT)): n
        for path in _modules()
        if (n := len(path.read_text().splitlines())) > MAX_LINES
    }
    assert not long, f"modules over {MAX_LINES} lines: {long}"


def test_no_import_of_another_librarys_private_module():
    """In the packages (a test may compare with a private module, e.g. scipy's DOP853 coefficients)."""
    found = {str(path.relative_to(ROOT)): bad for path in _modules() if (bad := private_imports(path.read_text()))}
    assert not found, f"imports of private modules: {found}"


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        ("from scipy.integrate._ivp import dop853_coefficients\n", ["scipy.integrate._ivp"]),
        ("import scipy.integrate._ivp.rk as rk\n", ["scipy.integrate._ivp.rk"]),
        ("import os, numpy._core\n", ["numpy._core"]),
        ("    from casadi._casadi import SX  # indented, in a function\n", ["casadi._casadi"]),
        ("from __future__ import annotations\n", []),
        ("from isolator.numerics._private import x\n", []),
        ("from . import _helpers\nfrom ._x import y\n", []),
        ("import numpy as np\nfrom scipy.integrate import solve_ivp\n", []),
        ("from importlib import __main__\n", []),
        ("x = 'from scipy._lib import y'\n", []),
    ],
)
def test_the_private_import_rule(source, expected):
    assert private_imports(source) == expected
