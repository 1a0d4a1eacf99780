"""A modal file as a universal file, read with ``pyuff``: nodes from datasets 2411 (or 15), one dataset 55 per
normal mode (3 or 6 values per node), the units of a dataset 164 converted to SI.

A modal mass other than 1 scales the shape by ``1/sqrt(modal mass)`` (0, which writers put where they give
none, is taken as 1); the viscous damping ratio is the mode's damping (0: none given, as FE codes write for
undamped modes). Dataset 164's factors convert file units to SI by division: a length of ``L`` file units
is ``L / length`` m, a force ``F / force`` N, so the file's mass unit is ``length / force`` kg and a
shape in length/sqrt(mass) scales by ``1 / (length sqrt(length / force))``.
"""

from __future__ import annotations

import importlib
import math
from pathlib import Path
from typing import Any

import numpy as np

from isolator.errors import ScenarioError
from isolator.scenario.files import check_input
from isolator.scenario.flexible.raw import RawModes
from isolator.scenario.names import excerpt

__all__ = ["UFF_SUFFIXES", "pyuff_module", "read_uff_modes"]

#: file suffixes (any case) read as universal files
UFF_SUFFIXES = (".uff", ".unv")
#: memory reading a UFF file takes per byte of it (pyuff holds its text and the values)
_UFF_FACTOR = 8.0
_KINDS = (15, 55, 164, 2411)


def pyuff_module(where: str) -> Any:
    """The pyuff module, or one ScenarioError starting with ``where`` naming the extra that installs it."""
    try:
        return importlib.import_module("pyuff")
    except ImportError:
        raise ScenarioError(f"{where}: reading a universal file needs pyuff: pip install 'isolator[uff]'") from None


def _datasets(path: Path, key: str, where: str) -> list[tuple[int, dict[str, Any]]]:
    """The file's datasets 15, 55, 164 and 2411, each with its position in the file (from 1)."""
    pyuff = pyuff_module(where)
    if not check_input(path, key, factor=_UFF_FACTOR):  # a regular file, checked before pyuff opens it
        raise ScenarioError(f"{where}: is empty (a modal universal file needs datasets 2411 and 55)")
    try:
        handle = pyuff.UFF(str(path))
        kinds = [int(k) for k in handle.get_set_types()]
    except Exception as exc:  # pyuff raises bare Exceptions on malformed files
        reason = excerpt(" ".join(str(exc).split())) or type(exc).__name__
        raise ScenarioError(f"{where}: cannot be read as a universal file ({reason})") from None
    out = []
    for i, kind in enumerate(kinds):
        if kind not in _KINDS:
            continue
        try:
            dataset = handle.read_sets(i)
        except Exception as exc:
            reason = excerpt(" ".join(str(exc).split())) or type(exc).__name__
            raise ScenarioError(f"{where}: dataset {i + 1} (type {kind}) cannot be read ({reason})") from None
        out.append((i + 1, dataset))
    return out


def _nodes(datasets: list[tuple[int, dict[str, Any]]], where: str) -> dict[int, np.ndarray]:
    """Node number -> coordinates (file units), from every dataset 2411 and 15."""
    nodes: dict[int, np.ndarray] = {}
    for number, dataset in datasets:
        if dataset["type"] not in (15, 2411):
            continue
        xyz = np.column_stack([np.asarray(dataset[c], dtype=float) for c in "xyz"])
        for label, point in zip(np.asarray(dataset["node_nums"]).astype(int), xyz, strict=True):
            if int(label) in nodes:
                raise ScenarioError(f"{where}: dataset {number}: node {label} is defined twice")
            if not np.all(np.isfinite(point)):
                raise ScenarioError(f"{where}: dataset {number}: node {label} has a coordinate that is not finite")
            nodes[int(label)] = point
    if not nodes:
        raise ScenarioError(f"{where}: has no nodes (a dataset 2411 or 15 giving their coordinates)")
    return nodes


def _units(datasets: list[tuple[int, dict[str, Any]]], where: str) -> tuple[float, float]:
    """Dataset 164's length and force factors (file units per SI unit); (1, 1) without one."""
    found = [(n, d) for n, d in datasets if d["type"] == 164]
    if not found:
        return 1.0, 1.0
    number, dataset = found[-1]
    length, force = float(dataset["length"]), float(dataset["force"])
    for name, value in (("length", length), ("force", force)):
        if not (math.isfinite(value) and value > 0):
            raise ScenarioError(f"{where}: dataset {number} (units) gives the {name} factor {value:g} "
                                "(must be > 0)")
    return length, force


def read_uff_modes(path: Path, key: str, where: str) -> RawModes:
    """The modes of a universal file; every problem one :class:`ScenarioError` starting with ``where`` (the key
    and the file) and naming the dataset (its position in the file) or the node."""
    datasets = _datasets(path, key, where)
    coordinates = _nodes(datasets, where)
    length, force = _units(datasets, where)
    modes = [(n, d) for n, d in datasets if d["type"] == 55]
    if not modes:
        raise ScenarioError(f"{where}: has no modes (a dataset 55 of normal modes per mode)")
    first = modes[0][0]
    order = np.asarray(modes[0][1].get("node_nums", [])).astype(int)
    missing = [int(n) for n in order if int(n) not in coordinates]
    if missing:
        raise ScenarioError(f"{where}: dataset {first}: node {missing[0]} is not among the file's nodes "
                            "(datasets 2411 or 15)")
    frequencies: list[float] = []
    damping: list[float] = []
    shapes: list[np.ndarray] = []
    names: list[str] = []
    for number, dataset in modes:
        name = f"dataset {number} (mode {dataset.get('mode_n', '?')})"
        if int(dataset.get("analysis_type", 0)) != 2:
            raise ScenarioError(f"{where}: {name} has analysis type {dataset.get('analysis_type')}, not normal "
                                "modes (2)")
        values = int(dataset.get("n_data_per_node", 0))
        if int(dataset.get("data_type", 2)) != 2 or values not in (3, 6):
            raise ScenarioError(f"{where}: {name} gives {values} values per node of data type "
                                f"{dataset.get('data_type')}; a mode needs 3 or 6 real values per node")
        labels = np.asarray(dataset["node_nums"]).astype(int)
        index = _same_nodes(labels, order, where, name, first)
        shape = np.column_stack([np.asarray(dataset[f"r{k}"], dtype=float) for k in range(1, values + 1)])[index]
        if shapes and shape.shape[1] != shapes[0].shape[1]:
            raise ScenarioError(f"{where}: {name} gives {values} values per node, dataset {first} "
                                f"{shapes[0].shape[1]} (every mode the same)")
        modal_mass = float(dataset.get("modal_m", 0.0))
        if not math.isfinite(modal_mass) or modal_mass < 0:
            raise ScenarioError(f"{where}: {name} has the modal mass {modal_mass:g} (must be > 0, or 0: not given)")
        if not np.all(np.isfinite(shape)):
            raise ScenarioError(f"{where}: {name} has a shape value that is not finite")
        shapes.append(shape / math.sqrt(modal_mass) if modal_mass > 0 else shape)
        frequencies.append(float(dataset.get("freq", math.nan)))
        zeta = float(dataset.get("modal_damp_vis", 0.0))
        damping.append(zeta if zeta != 0.0 else math.nan)
        names.append(name)
    mass_unit = length / force  # kg per file mass unit
    stack = np.array(shapes) / math.sqrt(mass_unit)
    return RawModes(
        frequencies=np.array(frequencies),
        damping=np.array(damping),
        nodes=np.array([coordinates[int(n)] for n in order]) / length,
        translations=stack[..., :3] / length,
        rotations=stack[..., 3:] if stack.shape[-1] == 6 else None,
        mode_names=names,
        node_names=[f"node {int(n)}" for n in order],
    )


def _same_nodes(labels: np.ndarray, order: np.ndarray, where: str, name: str, first: int) -> np.ndarray:
    """Where each node of the first mode's order lies in ``labels``; a mode whose nodes differ is an error."""
    position = {int(n): i for i, n in enumerate(labels)}
    if len(position) != labels.size:
        twice = next(int(n) for n in labels if np.count_nonzero(labels == n) > 1)
        raise ScenarioError(f"{where}: {name} lists node {twice} twice")
    extra = sorted(set(position) - {int(n) for n in order})
    missing = [int(n) for n in order if int(n) not in position]
    if missing or extra:
        what = f"node {missing[0]} missing" if missing else f"node {extra[0]} added"
        raise ScenarioError(f"{where}: {name}: its nodes differ from those of dataset {first} ({what}); every "
                            "mode gives the same nodes")
    return np.array([position[int(n)] for n in order])
