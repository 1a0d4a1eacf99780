"""An FMI 2.0 FMU from rendered sources: ``modelDescription.xml``, the binary for this platform, the sources.

Shared by the plant's FMU (:mod:`isolator.fmu.plant`) and an exported controller's
(:mod:`controllers.feedback.fmu`). The FMI 2.0 headers (``fmi2Functions.h``, ``fmi2FunctionTypes.h``,
``fmi2TypesPlatform.h``; Modelica Association, 2-clause BSD licence, in their text) are shipped with this
package in ``templates/`` and go into every FMU's ``sources/``, so that the FMU compiles anywhere. The
archive is written to a temporary file beside the target and moved into place once complete: a failure
writes nothing.
"""

from __future__ import annotations

import hashlib
import os
import platform
import subprocess
import tempfile
import uuid
import zipfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from isolator.errors import ParameterError
from isolator.numerics.native import find_compiler
from isolator.numerics.rendering import render

__all__ = ["FMI_HEADERS", "FmuVariable", "build_fmu", "c_compiler", "fmi_platform"]

#: the FMI 2.0 headers shipped in ``templates/``
FMI_HEADERS = ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")
#: the compiler's flags for the FMU's binary (the sources also compile with -std=c99 -Wall -Wextra -Werror
#: -pedantic, which the tests check)
FLAGS = ("-std=c99", "-O2", "-fPIC", "-shared")


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


def c_compiler() -> str:
    """The C compiler an FMU's binary is built with (as the native build finds it: ``$CC``, ``cc``, ``gcc``,
    ``clang``).

    Raises
    ------
    ParameterError
        None found, naming the ones looked for.
    """
    compiler = find_compiler("c")
    if compiler is None:
        looked = "$CC, cc, gcc, clang" if not os.environ.get("CC") else f"$CC ({os.environ['CC']}), cc, gcc, clang"
        raise ParameterError(f"no C compiler found (looked for {looked}): an FMU carries a binary compiled here; "
                             "install one or set CC")
    return compiler


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
        The model identifier: a C identifier, the binary's name.
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
                               "initial_unknowns": sorted({*calculated, *derivatives, *states})}
    xml = render("isolator.fmu", "templates/modelDescription.xml.j2", **context)
    headers = {h: resources.files("isolator.fmu").joinpath("templates", h).read_text() for h in FMI_HEADERS}
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        _write(out.absolute(), identifier, xml, {**texts, **headers}, c_files, compiler)
    except OSError as exc:
        raise ParameterError(f"{key}: cannot write '{out}' ({exc.strerror or exc})") from None
    return out


def _write(out: Path, identifier: str, xml: str, files: Mapping[str, str], c_files: Sequence[str], compiler: str
           ) -> None:
    """Compile and zip into a temporary folder beside ``out``, then move the archive into place."""
    with tempfile.TemporaryDirectory(dir=out.parent, prefix=".fmu-") as tmp:
        folder = Path(tmp)
        for file, text in files.items():
            (folder / file).write_text(text, encoding="utf-8")
        suffix = ".dll" if os.name == "nt" else ".dylib" if platform.system() == "Darwin" else ".so"
        binary = folder / f"{identifier}{suffix}"
        done = subprocess.run([compiler, *FLAGS, "-o", str(binary), *[str(folder / f) for f in c_files], "-lm"],
                              capture_output=True, text=True, cwd=folder)
        if done.returncode != 0:
            lines = done.stderr.splitlines()
            first = ([ln for ln in lines if "error" in ln] or lines or [""])[0].strip()
            raise ParameterError(f"{compiler} failed on the FMU's sources: {first}")
        archive = folder / "fmu.zip"
        with zipfile.ZipFile(archive, "w", zipfile.ZIP_DEFLATED) as zf:
            zf.writestr("modelDescription.xml", xml)
            zf.write(binary, f"binaries/{fmi_platform()}/{binary.name}")
            for file in sorted(files):
                zf.write(folder / file, f"sources/{file}")
        os.replace(archive, out)
