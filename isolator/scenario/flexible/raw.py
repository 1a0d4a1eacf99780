"""A modal file's content as read, before the checks that do not depend on its format."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["RawModes"]


@dataclass
class RawModes:
    """Every mode of a modal file in SI units, as the file lists them.

    Attributes
    ----------
    frequencies : ndarray, shape (M,)
        [Hz]
    damping : ndarray, shape (M,)
        Viscous damping ratios, NaN where the file gives none.
    nodes : ndarray, shape (N, 3)
        In the file's frame [m].
    translations : ndarray, shape (M, N, 3)
        Mass-normalised [m/sqrt(kg)].
    rotations : ndarray, shape (M, N, 3) or None
        [rad/sqrt(kg)]
    mode_names : list of str
        Where each mode is in the file, for messages (``mode 3 (line 205)``, ``dataset 7 (mode 3)``).
    node_names : list of str
        Each node's name in messages (``node 4 (line 5)``, ``node 1204``).
    """

    frequencies: np.ndarray
    damping: np.ndarray
    nodes: np.ndarray
    translations: np.ndarray
    rotations: np.ndarray | None
    mode_names: list[str]
    node_names: list[str]
