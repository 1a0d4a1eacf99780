"""Templates rendered for other tools: names escaped for C and XML read back exactly, undefined values refused,
no C left in Python strings."""

from __future__ import annotations

import ast
import ctypes
import shutil
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import jinja2
import pytest
from hypothesis import given
from hypothesis import strategies as st

from isolator import ParameterError
from isolator.numerics.rendering import c_double, escape_name, render

ROOT = Path(__file__).resolve().parents[2]
HOSTILE = ['a"b', "x*/y/*z", "back\\slash", "tri??/graph", "new\nline", "tab\there", "ünï€ode", "<&'>", "%s{{x}}"]


@given(st.text(alphabet=st.characters(blacklist_categories=("Cs", "Cc")), max_size=30))
def test_xml_attribute_reads_back(name):
    element = ET.fromstring(f'<v name="{escape_name(name, "xml")}"/>')
    assert element.get("name") == name


@pytest.mark.parametrize("name", HOSTILE)
def test_xml_attribute_reads_back_hostile_names(name):
    assert ET.fromstring(f"<v name='{escape_name(name, 'xml')}'/>").get("name") == name


def test_xml_refuses_what_xml_cannot_hold():
    with pytest.raises(ParameterError, match="XML"):
        escape_name("bell\x07", "xml")
    with pytest.raises(ParameterError, match="kind"):
        escape_name("x", "json")  # type: ignore[arg-type]


@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler")
def test_c_literals_hold_the_names_bytes(tmp_path):
    names = [*HOSTILE, ""]
    body = ",\n".join(f"/* {escape_name(n, 'c')} */ {escape_name(n, 'c')}" for n in names)
    (tmp_path / "names.c").write_text(f"const char *const names[] = {{\n{body}\n}};\n")
    lib = tmp_path / "names.so"
    subprocess.run(["cc", "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-trigraphs", "-shared", "-fPIC",
                    "-o", str(lib), str(tmp_path / "names.c")], check=True, capture_output=True)
    table = (ctypes.c_char_p * len(names)).in_dll(ctypes.CDLL(str(lib)), "names")
    assert [table[i].decode() for i in range(len(names))] == names


def test_doubles_read_back_exactly():
    for value in (0.1, -1e-300, 5e-324, 1.7976931348623157e308, 3.0):
        assert float(c_double(value)) == value
    with pytest.raises(ParameterError, match="finite"):
        c_double(float("nan"))


def test_an_undefined_value_is_an_error_not_empty_text():
    with pytest.raises(jinja2.UndefinedError):
        render("controllers.feedback", "templates/controller.h.j2")


def test_no_c_in_python_strings():
    """Every #include / #define / extern "C" of the three packages lives in a template file."""
    found = []
    for path in [p for pkg in ("isolator", "controllers", "studies") for p in (ROOT / pkg).rglob("*.py")]:
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and any(
                    key in node.value for key in ("#include", "#define", 'extern "C"')):
                found.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert found == []


def test_templates_are_package_data():
    """pyproject's package-data globs cover every template file."""
    import tomllib

    data = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]
    for pkg in ("isolator", "controllers"):
        for path in (ROOT / pkg).rglob("*.j2"):
            rel = path.relative_to(ROOT / pkg)
            assert any(rel.match(glob) for glob in data.get(pkg, ())), rel
