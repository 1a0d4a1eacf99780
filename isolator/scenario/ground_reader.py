"""Reading ``[ground.spectrum]``: a floor spectrum from a file, inline, or at the limit of a VC class
(``docs/scenario-format.md``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from isolator.errors import ScenarioError
from isolator.scenario.ground import FloorSpectrum
from isolator.scenario.keys import KeyReader, number_list
from isolator.scenario.random_sources import vc_spectrum
from isolator.scenario.tables import SPECTRUM_KINDS, load_spectrum, spectrum_from_columns

__all__ = ["read_spectrum"]


def read_spectrum(r: KeyReader, base_dir: Path) -> FloorSpectrum:
    """``[ground.spectrum]``: ``kind`` with a ``file`` or inline ``frequency`` and ``x, y, z``; or ``vc`` alone."""
    if r.has("vc"):
        others = [k for k in ("kind", "file", "frequency", "x", "y", "z") if r.has(k)]
        if others:
            raise ScenarioError(f"{r.key('vc')}: a VC class is the whole spectrum; give vc or {others[0]}, not both")
        spectrum = vc_spectrum(r.raw("vc"), r.key("vc"))
        r.finish()
        return spectrum
    kind = r.string("kind")
    if kind not in SPECTRUM_KINDS:
        raise ScenarioError(f"{r.key('kind')}: must be one of {', '.join(SPECTRUM_KINDS)}, got '{kind}'")
    if r.has("file"):
        if any(r.has(k) for k in ("frequency", "x", "y", "z")):
            raise ScenarioError(f"{r.key('file')}: give either file or inline frequency and values, not both")
        spectrum = load_spectrum(base_dir / r.string("file"), kind, key=r.key("file"))
    else:
        columns = {"frequency": np.array(number_list(r, "frequency"))}
        for axis in ("x", "y", "z"):
            if r.has(axis):
                columns[axis] = np.array(number_list(r, axis))
        spectrum = spectrum_from_columns(columns, kind, r.path)
    r.used.update({"file", "frequency", "x", "y", "z", "vc"})
    r.finish()
    return spectrum
