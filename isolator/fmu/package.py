"""An FMI 2.0 FMU from rendered sources: ``modelDescription.xml``, the binary for this platform, the sources.

Shared by the plant's FMU (:mod:`isolator.fmu.plant`) and an exported controller's
(:mod:`controllers.feedback.fmu`). The FMI 2.0 headers (``fmi2Functions.h``, ``fmi2FunctionTypes.h``,
``fmi2TypesPlatform.h``; Modelica Association, 2-clause BSD licence, in their text) are shipped with this
package in ``templates/`` and go into every FMU's ``sources/``, so that the FMU compiles anywhere. The
archive is written to a temporary file beside the target and moved into place once complete: a failure
writes nothing.
"""

from __future__ import annotations

import functools
import hashlib
import os
import platform
import re
import shlex
import shutil
import subprocess
import tempfile
import unicodedata
import uuid
import zipfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from isolator.errors import ParameterError
from isolator.fmu.units import unit_definitions
from isolator.numerics.native import find_compiler
from isolator.numerics.rendering import render

__all__ = ["FMI_HEADERS", "FmuVariable", "build_fmu", "c_compiler", "fmi_platform", "model_identifier",
           "valid_identifier"]

#: the FMI 2.0 headers shipped in ``templates/``
FMI_HEADERS = ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")
#: the compiler's flags for the FMU's binary (the sources also compile with -std=c99 -Wall -Wextra -Werror
#: -pedantic, which the tests check)
FLAGS = ("-std=c99", "-O2", "-fPIC", "-shared")
#: the longest model identifier (its binary's and sources' names stay short on every file system)
IDENTIFIER_LENGTH = 48
_IDENTIFIER = re.compile(r"[A-Za-z][A-Za-z0-9]*(?:_[A-Za-z0-9]+)*")
_C_KEYWORDS = frozenset({
    "auto", "break", "case", "char", "const", "continue", "default", "do", "double", "else", "enum", "extern",
    "float", "for", "goto", "if", "inline", "int", "long", "register", "restrict", "return", "short", "signed",
    "sizeof", "static", "struct", "switch", "typedef", "union", "unsigned", "void", "volatile", "while"})
#: letters NFKD does not take apart
_TRANSLITERATION = {"ß": "ss", "æ": "ae", "Æ": "AE", "ø": "o", "Ø": "O", "œ": "oe", "Œ": "OE", "ł": "l", "Ł": "L",
                    "đ": "d", "Đ": "D", "þ": "th", "Þ": "Th"}


@dataclass(frozen=True)
class FmuVariable:
    """One scalar variable of ``modelDescription.xml`` (all Real).

    Attributes
    ----------
    name : str
    vr : int
        Value reference.
    causality : {"output", "input", "parameter", "local", "independent"}
    variability : {"continuous", "fixed", "discrete"}
    description : str
    initial : str or None
    start, nominal : float or None
    derivative : int or None
        The 1-based index of the state this variable is the derivative of.
    unit : str or None
        Its SI unit, a name of :data:`isolator.fmu.units.BASE_UNITS` (None: unknown).
    """

    name: str
    vr: int
    causality: str
    variability: str = "continuous"
    description: str = ""
    initial: str | None = None
    start: float | None = None
    nominal: float | None = None
    derivative: int | None = None
    unit: str | None = None


@dataclass(frozen=True)
class FmuDescription:
    """What ``modelDescription.xml`` says besides its variables (see :func:`build_fmu`)."""

    identifier: str
    name: str
    description: str
    guid: str
    me: bool
    cs: bool
    sources: tuple[str, ...]
    stop_time: float | None
    step: float
    interpolates: bool
    tool: str = field(default="isolator")


def fmi_platform() -> str:
    """The FMI 2.0 platform folder of this machine: ``linux64``, ``darwin64``, ``win64`` (32-bit: ``...32``)."""
    system = {"Linux": "linux", "Darwin": "darwin", "Windows": "win"}.get(platform.system(), platform.system().lower())
    bits = "64" if platform.architecture()[0] == "64bit" else "32"
    return system + bits


def c_compiler() -> tuple[str, ...]:
    """The C compiler command an FMU's binary is built with: ``$CC`` when set (split as a shell splits it, so
    that it may carry flags of its own), else the first of ``cc``, ``gcc``, ``clang`` on the path (as the
    native build finds one).

    Raises
    ------
    ParameterError
        ``$CC`` set to a command that is not found, or that does not compile a line of C (naming CC and its
        value); no compiler found, naming the ones looked for.
    """
    chosen = os.environ.get("CC", "").strip()
    if chosen:
        try:
            command = tuple(shlex.split(chosen))
        except ValueError:
            command = ()
        if not command or shutil.which(command[0]) is None:
            raise ParameterError(f"CC: {chosen!r} is not found, so there is no C compiler to build the FMU's "
                                 "binary with: set CC to a C compiler, or unset it to use cc, gcc or clang")
        _probe(command)
        return command
    compiler = find_compiler("c")
    if compiler is None:
        raise ParameterError("no C compiler found (looked for $CC, cc, gcc, clang): an FMU carries a binary "
                             "compiled here; install one or set CC")
    return (compiler,)


@functools.lru_cache(maxsize=8)
def _probe(command: tuple[str, ...]) -> None:
    """Compile a line of C with ``command`` as an FMU's binary is compiled; a :class:`ParameterError` naming CC
    if it fails (once per command and process when it works)."""
    with tempfile.TemporaryDirectory(prefix="isolator-cc-") as tmp:
        source = Path(tmp, "probe.c")
        source.write_text("int isolator_probe(void) { return 0; }\n", encoding="utf-8")
        try:
            done = subprocess.run([*command, *FLAGS, "-o", str(Path(tmp, "probe.so")), str(source)],
                                  capture_output=True, text=True, cwd=tmp)
        except OSError as exc:
            raise ParameterError(f"CC: {' '.join(command)!r} cannot be run ({exc.strerror or exc})") from None
    if done.returncode != 0:
        raise ParameterError(f"CC: {' '.join(command)!r} does not compile C: {_first_error(done)}")


def _first_error(done: subprocess.CompletedProcess[str]) -> str:
    """A failed compiler's first error line (its exit status when it printed none)."""
    lines = done.stderr.splitlines()
    first = ([ln for ln in lines if "error" in ln] or lines or [""])[0].strip()
    return first or f"exit status {done.returncode}"


def model_identifier(name: str) -> str:
    """A model identifier made from a name (an FMU file's stem): the name itself when it is one, else an ASCII
    form of it with 8 hex digits of the name's SHA-256 added, so that two names never share one.

    A model identifier is a C identifier and the name of the FMU's binary; casadi's generated functions take it
    as their prefix. So it starts with a letter, holds letters and digits joined by single underscores, is no C
    keyword and at most :data:`IDENTIFIER_LENGTH` characters.

    Examples
    --------
    >>> model_identifier("table")
    'table'
    >>> model_identifier("tabelle-größe")
    'tabelle_grosse_41ec7599'
    """
    if valid_identifier(name):
        return name
    spelled = unicodedata.normalize("NFKD", "".join(_TRANSLITERATION.get(c, c) for c in name))
    letters = "".join(c for c in spelled if not unicodedata.combining(c))
    stem = re.sub(r"[^A-Za-z0-9]+", "_", letters).strip("_")
    if not stem[:1].isalpha():
        stem = f"fmu_{stem}"
    stem = stem[: IDENTIFIER_LENGTH - 9].rstrip("_")
    return f"{stem}_{hashlib.sha256(name.encode('utf-8', 'surrogatepass')).hexdigest()[:8]}"


def valid_identifier(name: str) -> bool:
    """Whether ``name`` is a model identifier as :func:`model_identifier` makes them."""
    return (len(name) <= IDENTIFIER_LENGTH and _IDENTIFIER.fullmatch(name) is not None
            and name not in _C_KEYWORDS)


def _guid(text: str) -> str:
    return "{" + str(uuid.UUID(hashlib.sha256(text.encode()).hexdigest()[:32])) + "}"


def build_fmu(out: Path, identifier: str, name: str, description: str, variables: Sequence[FmuVariable],
              sources: Mapping[str, str], *, me: bool, cs: bool, step: float, stop_time: float | None = None,
              interpolates: bool = False, key: str = "out") -> Path:
    """Compile ``sources`` for this platform and zip the FMU at ``out``.

    Parameters
    ----------
    out : Path
        The ``.fmu`` file (replaced when complete).
    identifier : str
        The model identifier: a C identifier, the binary's name (:func:`model_identifier` makes one).
    name, description : str
        The model's name and description (escaped into the XML).
    variables : sequence of FmuVariable
        In ``ModelVariables`` order; outputs, derivatives and initial unknowns are taken from them.
    sources : mapping of str to str
        File name -> text (C sources and headers besides the FMI headers); the ``.c`` files are compiled and
        listed in ``SourceFiles``. Each text holds the GUID placeholder ``@GUID@``, replaced by the FMU's GUID.
    me, cs : bool
        Model Exchange, Co-Simulation.
    step : float
        The default experiment's step [s].
    stop_time : float, optional
        The default experiment's stop time [s].
    interpolates : bool
        Co-Simulation: ``canInterpolateInputs``.
    key : str
        How errors name ``out``.

    Raises
    ------
    ParameterError
        No C compiler (naming the ones looked for), or it failed; ``out`` not writable.
    """
    compiler = c_compiler()
    if not valid_identifier(identifier):
        raise ValueError(f"build_fmu: {identifier!r} is no model identifier (model_identifier makes one)")
    if sorted(v.vr for v in variables) != list(range(len(variables))):
        raise ValueError("build_fmu: the variables' value references must be 0, 1, ... (each once)")
    texts = dict(sources)
    guid = _guid("".join(texts[k] for k in sorted(texts)) + identifier)
    texts = {k: v.replace("@GUID@", guid) for k, v in texts.items()}
    c_files = tuple(k for k in texts if k.endswith(".c"))
    fmu = FmuDescription(identifier, name, description, guid, me, cs, c_files, stop_time, step, interpolates)
    derivatives = [i + 1 for i, v in enumerate(variables) if v.derivative is not None]
    states = [v.derivative for v in variables if v.derivative is not None]
    outputs = [i + 1 for i, v in enumerate(variables) if v.causality == "output"]
    calculated = [i for i in outputs if variables[i - 1].initial != "exact"]
    context: dict[str, Any] = {"fmu": fmu, "variables": variables, "outputs": outputs, "derivatives": derivatives,
                               "initial_unknowns": sorted({*calculated, *derivatives, *states}),
                               "units": unit_definitions(v.unit for v in variables)}
    xml = render("isolator.fmu", "templates/modelDescription.xml.j2", **context)
    headers = {h: resources.files("isolator.fmu").joinpath("templates", h).read_text() for h in FMI_HEADERS}
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        _write(out.absolute(), identifier, xml, {**texts, **headers}, c_files, compiler)
    except OSError as exc:
        raise ParameterError(f"{key}: cannot write '{out}' ({exc.strerror or exc})") from None
    return out


def _write(out: Path, identifier: str, xml: str, files: Mapping[str, str], c_files: Sequence[str],
           compiler: Sequence[str]) -> None:
    """Compile and zip into a temporary folder beside ``out``, then move the archive into place."""
    with tempfile.TemporaryDirectory(dir=out.parent, prefix=".fmu-") as tmp:
        folder = Path(tmp)
        for file, text in files.items():
            (folder / file).write_text(text, encoding="utf-8")
        suffix = ".dll" if os.name == "nt" else ".dylib" if platform.system() == "Darwin" else ".so"
        binary = folder / f"{identifier}{suffix}"
        done = subprocess.run([*compiler, *FLAGS, "-o", str(binary), *[str(folder / f) for f in c_files], "-lm"],
                              capture_output=True, text=True, cwd=folder)
        if done.returncode != 0:
            who = f"CC ({' '.join(compiler)})" if os.environ.get("CC", "").strip() else compiler[0]
            raise ParameterError(f"{who} failed on the FMU's sources: {_first_error(done)}")
        archive = folder / "fmu.zip"
        with zipfile.ZipFile(archive, "w", zipfile.ZIP_DEFLATED) as zf:
            zf.writestr("modelDescription.xml", xml)
            zf.write(binary, f"binaries/{fmi_platform()}/{binary.name}")
            for file in sorted(files):
                zf.write(folder / file, f"sources/{file}")
        os.replace(archive, out)
