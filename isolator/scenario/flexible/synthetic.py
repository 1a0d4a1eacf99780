"""Synthetic modal data of a box-shaped top, for tests and examples: its six rigid modes exactly, and smooth
plate-like elastic shapes (not a finite-element solution: ``isolator plate-modes`` computes those).

The elastic shapes follow Kirchhoff's kinematics of a plate's transverse deflection ``w(x, y)``: rotations
``theta = (dw/dy, -dw/dx, 0)`` and, at the height ``z`` above the mid-surface, in-plane translations
``(-z dw/dx, -z dw/dy)``, so that a solid's two faces and the mid-surface with rotations describe the same
motion.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["SyntheticTop", "box_rigid_modes", "synthetic_top"]


@dataclass(frozen=True, eq=False)
class SyntheticTop:
    """Modes of a synthetic top, rigid ones first, in the frame whose origin is the file's.

    Attributes
    ----------
    frequencies : ndarray, shape (M,)
        [Hz]
    nodes : ndarray, shape (N, 3)
        [m]
    translations, rotations : ndarray, shape (M, N, 3)
        [m/sqrt(kg)], [rad/sqrt(kg)]
    """

    frequencies: np.ndarray
    nodes: np.ndarray
    translations: np.ndarray
    rotations: np.ndarray


def box_rigid_modes(nodes: np.ndarray, mass: float, inertia: np.ndarray, centre: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
    """The six mass-normalised rigid modes of a body: translations ``e_k / sqrt(m)``, rotations about the
    principal axes through ``centre`` ``w = e_k / sqrt(I_k)``, ``u = w x (p - c)``.

    Parameters
    ----------
    nodes : ndarray, shape (N, 3)
        [m]
    mass : float
        [kg]
    inertia : ndarray, shape (3,)
        Principal moments along x, y, z about the centre [kg m^2].
    centre : ndarray, shape (3,)
        The mass centre [m].

    Returns
    -------
    translations, rotations : ndarray, shape (6, N, 3)
    """
    p = np.asarray(nodes, dtype=float) - np.asarray(centre, dtype=float)
    u = np.zeros((6, len(p), 3))
    r = np.zeros((6, len(p), 3))
    for k in range(3):
        u[k, :, k] = 1.0 / np.sqrt(mass)
        w = np.eye(3)[k] / np.sqrt(inertia[k])
        r[3 + k] = w
        u[3 + k] = np.cross(w, p)
    return u, r


def synthetic_top(size: tuple[float, float, float] = (2.0, 1.0, 0.2), mass: float = 1000.0, *,
                  grid: tuple[int, int] = (9, 5), frequencies: tuple[float, ...] = (120.0, 180.0, 250.0, 330.0),
                  layer: str = "faces", centre: tuple[float, float, float] = (0.0, 0.0, 0.0),
                  rigid: bool = True) -> SyntheticTop:
    """A box-shaped top's modes on a grid of nodes.

    Parameters
    ----------
    size : tuple of float
        Length, width, thickness [m]; the box is centred on ``centre``.
    mass : float
        [kg]
    grid : tuple of int
        Nodes along x and y on each face.
    frequencies : tuple of float
        The elastic modes' frequencies [Hz]; mode ``i`` has the deflection ``cos(a x + b) cos(c y + d)``
        scaled to ``1/sqrt(mass)`` in size, with wave numbers growing with ``i``.
    layer : {"faces", "mid"}
        Nodes on the top and bottom faces, or one layer at mid-height.
    centre : tuple of float
        Where the box's centre (its mass centre) lies in the file's frame [m].
    rigid : bool
        Include the six rigid modes (at 0 Hz, first).

    Returns
    -------
    SyntheticTop
    """
    lx, ly, t = size
    x, y = np.meshgrid(np.linspace(-lx / 2, lx / 2, grid[0]), np.linspace(-ly / 2, ly / 2, grid[1]), indexing="ij")
    heights = (t / 2, -t / 2) if layer == "faces" else (0.0,)
    local = np.vstack([np.column_stack([x.ravel(), y.ravel(), np.full(x.size, h)]) for h in heights])
    nodes = local + np.asarray(centre, dtype=float)
    shapes_u, shapes_r = [], []
    for i, _ in enumerate(frequencies):
        a, c = np.pi * (1 + i % 3) / lx, np.pi * (1 + i // 3) / ly
        b, d = 0.3 * i, -0.2 * i
        w = np.cos(a * local[:, 0] + b) * np.cos(c * local[:, 1] + d) / np.sqrt(mass)
        dwdx = -a * np.sin(a * local[:, 0] + b) * np.cos(c * local[:, 1] + d) / np.sqrt(mass)
        dwdy = -c * np.cos(a * local[:, 0] + b) * np.sin(c * local[:, 1] + d) / np.sqrt(mass)
        z = local[:, 2]
        shapes_u.append(np.column_stack([-z * dwdx, -z * dwdy, w]))
        shapes_r.append(np.column_stack([dwdy, -dwdx, np.zeros_like(w)]))
    u = np.array(shapes_u).reshape(-1, len(nodes), 3)
    r = np.array(shapes_r).reshape(-1, len(nodes), 3)
    f = np.asarray(frequencies, dtype=float)
    if rigid:
        inertia = mass * np.array([ly**2 + t**2, lx**2 + t**2, lx**2 + ly**2]) / 12.0
        ru, rr = box_rigid_modes(nodes, mass, inertia, np.asarray(centre, dtype=float))
        u, r, f = np.concatenate([ru, u]), np.concatenate([rr, r]), np.concatenate([np.zeros(6), f])
    return SyntheticTop(frequencies=f, nodes=nodes, translations=u, rotations=r)
