"""Code for other tools rendered from template files: one mechanism, one escaping function for names.

Everything the toolkit writes in another language (the compiled loop's C++, an exported controller's C,
an FMU's C wrapper and ``modelDescription.xml``) comes from template files shipped as package data,
rendered here with Jinja2 (``{{ }}`` for values, ``{% %}`` for the little logic a template needs; undefined
names are errors, never empty text). Names from a scenario reach the output only through
:func:`escape_name`, registered as the templates' filters ``c`` (a C string literal) and ``xml`` (an XML
attribute's text); numbers through ``double`` (a C ``double`` literal that reads back exactly).
"""

from __future__ import annotations

import math
import numbers
from functools import cache
from importlib import resources
from typing import Any, Literal

import jinja2

from isolator.errors import ParameterError

__all__ = ["c_double", "escape_name", "render"]

#: bytes a C literal holds as they are: the rest become three-digit octal escapes, so that ``*/``, ``/*``,
#: quotes, backslashes, ``??`` trigraphs, newlines and non-ASCII names cannot end a comment or a literal
_C_SAFE = frozenset(b"abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789 -_.:,;+=()[]<>{}!#$%&'@^|~")

_XML = {"&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&apos;",
        "\t": "&#9;", "\n": "&#10;", "\r": "&#13;"}


def escape_name(name: str, kind: Literal["c", "xml"]) -> str:
    """A name as a C string literal (``kind="c"``) or as the text of an XML attribute (``kind="xml"``).

    Parameters
    ----------
    name : str
        Any text (UTF-8).
    kind : {"c", "xml"}
        ``"c"``: the quoted literal holding the name's UTF-8 bytes exactly, every byte outside letters,
        digits, space and ``-_.:,;+=()[]<>{}!#$%&'@^|~`` as a three-digit octal escape (safe inside a
        comment as well). ``"xml"``: the text between an attribute's quotes (``&<>"'`` and tab, newline,
        carriage return as references).

    Raises
    ------
    ParameterError
        A name XML cannot hold (a control character other than tab, newline and carriage return).
    """
    if kind == "c":
        return '"' + "".join(chr(b) if b in _C_SAFE else f"\\{b:03o}" for b in name.encode("utf-8")) + '"'
    if kind == "xml":
        bad = [c for c in name if (ord(c) < 32 and c not in "\t\n\r") or 0xD800 <= ord(c) <= 0xDFFF
               or ord(c) in (0xFFFE, 0xFFFF)]
        if bad:
            raise ParameterError(f"name {name!r}: holds {bad[0]!r}, which an XML file cannot hold")
        return "".join(_XML.get(c, c) for c in name)
    raise ParameterError(f"kind: must be 'c' or 'xml', got {kind!r}")


def c_double(value: float) -> str:
    """A finite number as a C ``double`` literal that reads back to the same double."""
    if not (isinstance(value, numbers.Real) and math.isfinite(value)):
        raise ParameterError(f"value: a C literal needs a finite number, got {value!r}")
    return repr(float(value))


@cache
def _environment(package: str) -> jinja2.Environment:
    def load(name: str) -> str:
        return resources.files(package).joinpath(name).read_text(encoding="utf-8")

    env = jinja2.Environment(loader=jinja2.FunctionLoader(load), undefined=jinja2.StrictUndefined,
                             keep_trailing_newline=True, trim_blocks=True, lstrip_blocks=True, autoescape=False)
    env.filters["c"] = lambda name: escape_name(name, "c")
    env.filters["xml"] = lambda name: escape_name(name, "xml")
    env.filters["double"] = c_double
    return env


def render(package: str, template: str, **context: Any) -> str:
    """The text of a template file shipped in ``package``, with ``context``.

    Parameters
    ----------
    package : str
        The package holding the file (``"isolator.numerics"``).
    template : str
        Its path inside the package (``"cpp/dop853_driver.cpp.j2"``); a template may include others of the
        same package by their paths.
    **context
        The template's values.
    """
    return _environment(package).get_template(template).render(**context)
