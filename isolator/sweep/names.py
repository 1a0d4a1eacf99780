"""Swept names (``[*]``, vectors and tables): moved to :mod:`isolator.model.names`, below the simulator, whose
``run(changes=...)`` takes the same names; re-exported here."""

from __future__ import annotations

from isolator.model.names import Column, expand_changes, joint_entries, resolve

__all__ = ["Column", "expand_changes", "joint_entries", "resolve"]
