"""The linearised model's response from the floor to the table's sensors, and its exact derivatives with
respect to the model's parameters.

At the rest pose ``z0(p)`` (the static equilibrium, carriages parked) the one symbolic linearisation
(:func:`isolator.model.linearisation.build_linearisation`) gives ``M, C, K, G0, G1`` (and for pneumatic
tables the chamber matrices). At the angular frequency ``w`` the table's displacement ``d`` (and chamber
pressures ``e``) under a floor translation ``g`` solve

``[Z(w)  Kp; -(Pd + jw Pv)  jw I - Pp] [d; e] = [-(G0 + jw G1); Pg + jw Pgd] g``,  ``Z = -w^2 M + jw C + K``

and a table sensor reads ``(jw)^k n^T [I, -[R0 r]x] d`` (k = 0, 1, 2 for displacement, velocity,
acceleration). The derivatives: casadi's Jacobians of every matrix (and of ``R0``) with respect to ``z0``
and ``p``, ``dz0/dp = -(dr/dz)^-1 dr/dp`` from the static residual (implicit function theorem), then
``dX = Z^-1 (dF - dZ X)`` per frequency: exact, no finite differences.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from isolator.model.cache import get_model
from isolator.model.equilibrium import static_equilibrium
from isolator.model.linearisation import build_linearisation
from isolator.model.parameters import ParameterLayout
from isolator.model.rotations import cardan_matrix, skew
from isolator.scenario.sensors import Sensor

__all__ = ["FloorModel", "FloorResponse"]


@dataclass(frozen=True)
class FloorResponse:
    """The model's response from floor translations (world x, y, z) to table sensors.

    Attributes
    ----------
    H : ndarray (sensors, 3, nf)
        In each sensor's quantity per metre of floor translation.
    dH : ndarray (params, sensors, 3, nf) or None
        Derivatives with respect to each direction of ``tangents`` given.
    """

    H: np.ndarray
    dH: np.ndarray | None  # noqa: N815 (the derivative of H)


class FloorModel:
    """The response of one scenario structure, carriages parked at ``positions``, to floor translations.

    Parameters
    ----------
    layout : ParameterLayout
    positions : ndarray
        Carriage coordinates [m].
    sensors : sequence of Sensor
        Table sensors (their outputs, in order).
    """

    def __init__(self, layout: ParameterLayout, positions: np.ndarray, sensors: tuple[Sensor, ...]) -> None:
        self.layout = layout
        self.positions = np.asarray(positions, dtype=float)
        self.sensors = sensors
        self.model = get_model(layout, "exact")
        self.orders = np.array([s.order for s in sensors])
        structure = layout.pneumatic
        self.n_air = 0 if structure is None else structure.n_states
        nz = self.model.n_static
        z = ca.SX.sym("z", nz)
        p = ca.SX.sym("p", layout.size)
        c = ca.DM(np.concatenate([self.positions, np.zeros(2 * self.positions.size)]))
        mats = build_linearisation(layout)(z, c, p)
        rot = cardan_matrix(z[3:6])
        rows = []
        for s in sensors:
            n = ca.DM(np.asarray(s.direction, dtype=float)).T
            arm = rot @ ca.DM(np.asarray(s.position, dtype=float))
            rows.append(ca.horzcat(n, -n @ skew(arm)))
        out_rows = ca.vertcat(*rows) if rows else ca.SX.zeros(0, 6)
        parts = [*mats, out_rows]
        self._shapes = [(int(m.shape[0]), int(m.shape[1])) for m in parts]
        flat = ca.vertcat(*[ca.reshape(m, -1, 1) for m in parts])
        self._values = ca.Function("floor_matrices", [z, p], [flat])
        self._jacobians = ca.Function("floor_matrix_jacobians", [z, p], [ca.jacobian(flat, z), ca.jacobian(flat, p)])
        r = self.model.static_residual(z, c, p)[0]
        self._static = ca.Function("static_jacobians", [z, p], [ca.jacobian(r, z), ca.jacobian(r, p)])

    def _unflatten(self, flat: np.ndarray) -> list[np.ndarray]:
        out, k = [], 0
        for rows, cols in self._shapes:
            out.append(flat[k : k + rows * cols].reshape(cols, rows).T)  # casadi is column-major
            k += rows * cols
        return out

    def response(self, p: np.ndarray, f: np.ndarray, tangents: np.ndarray | None = None) -> FloorResponse:
        """The response at frequencies ``f`` [Hz] for the parameter vector ``p``, and its derivatives along
        ``tangents`` (params, parameter vector size): ``dH[j] = sum_e tangents[j, e] dH/dp_e``.

        Raises
        ------
        UnstableTableError
            The table has no stable rest with these parameters.
        """
        p = np.asarray(p, dtype=float)
        eq = static_equilibrium(self.model, p, self.positions, "with the carriages parked for the floor experiment")
        z0 = np.asarray(eq.pose, dtype=float)[: self.model.n_static]
        mats = self._unflatten(np.asarray(self._values(z0, p)).ravel())
        w = 2 * np.pi * np.asarray(f, dtype=float)
        system, rhs = self._assemble(mats, w, True)
        x = np.linalg.solve(system, rhs)  # (nf, n, 3)
        gain = (1j * w)[:, None] ** self.orders[None, :]  # (nf, sensors)
        rows = mats[-1]
        h = np.einsum("fs,sd,fdk->skf", gain, rows, x[:, :6, :])
        if tangents is None:
            return FloorResponse(h, None)
        jz, jp = (np.asarray(m) for m in self._jacobians(z0, p))
        sz, sp = (np.asarray(m) for m in self._static(z0, p))
        dz = -np.linalg.solve(sz, sp)  # dz0/dp
        total = (jp + jz @ dz) @ np.asarray(tangents, dtype=float).T  # (flat, params)
        dh = np.empty((total.shape[1], *h.shape), dtype=complex)
        for j in range(total.shape[1]):
            dmats = self._unflatten(total[:, j])
            dsys, drhs = self._assemble(dmats, w, False)
            dx = np.linalg.solve(system, drhs - dsys @ x)
            dh[j] = np.einsum("fs,sd,fdk->skf", gain, dmats[-1], x[:, :6, :]) + np.einsum(
                "fs,sd,fdk->skf", gain, rows, dx[:, :6, :])
        return FloorResponse(h, dh)

    def _assemble(self, mats: list[np.ndarray], w: np.ndarray, constant: bool) -> tuple[np.ndarray, np.ndarray]:
        """The complex system (nf, n, n) and right-hand side (nf, n, 3) at ``w`` [rad/s]; ``constant`` False
        gives their derivative for derivative matrices (the constant ``jw I`` left out)."""
        jw = (1j * w)[:, None, None]
        m, c, k, g0, g1 = mats[:5]
        z = -(w**2)[:, None, None] * m + jw * c + k
        f = -(g0[:, :3] + jw * g1[:, :3])
        if not self.n_air:
            return z, f
        kp, pd, pv, pp, pg, pgd = mats[7:13]
        n_air = self.n_air
        eye = np.eye(n_air) if constant else np.zeros((n_air, n_air))
        top = np.concatenate([z, np.broadcast_to(kp, (w.size, *kp.shape))], axis=2)
        bottom = np.concatenate([-(pd + jw * pv), jw * eye - pp], axis=2)
        rhs = np.concatenate([f, pg[:, :3] + jw * pgd[:, :3]], axis=1)
        return np.concatenate([top, bottom], axis=1), rhs
