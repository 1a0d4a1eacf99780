"""A plain numpy + scipy.solve_ivp implementation of the exact model: the speed baseline.

Written by hand from Newton-Euler (no casadi), integrated with DOP853 and
restarted at the profiles' breakpoints. Also the tight-tolerance reference
for the accuracy figure of ``bench_simulate.py``.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import fsolve

from isolator import Scenario
from isolator.validation.multibody import solve_piecewise


def _rot(qt):
    w, x, y, z = qt / np.linalg.norm(qt)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


class NumpyTable:
    def __init__(self, sc: Scenario) -> None:
        self.sc = sc
        self.M = sc.table.mass
        self.J = np.diag(sc.table.inertia)
        self.s = np.array([i.position for i in sc.isolators])
        self.k = np.array([i.stiffness for i in sc.isolators])
        self.c = np.array([i.damping for i in sc.isolators])
        self.g = np.array([0, 0, -sc.gravity])
        self.m = np.array([c.mass for c in sc.carriages])
        self.mt = self.M + self.m.sum()
        self.f0 = np.zeros_like(self.k)
        self.f0[:, 2] = sc.isolator_preloads()

    def carriages(self, t, sel):
        qs = np.array([c.profile.evaluate(np.array([t]), np.array([sel])) for c in self.sc.carriages])[:, :, 0]
        d = self.sc.carriage_positions(qs[:, 0])
        dv = self.sc.carriage_positions(qs[:, 1]) - self.sc.carriage_positions(np.zeros(len(qs)))
        da = self.sc.carriage_positions(qs[:, 2]) - self.sc.carriage_positions(np.zeros(len(qs)))
        return d, dv, da

    def accel(self, y, d, dv, da):
        p, qt, v, w = y[0:3], y[3:7], y[7:10], y[10:13]
        R = _rot(qt)
        arms = self.s @ R.T
        pv = v + np.cross(R @ w, arms)
        f = self.f0 - self.k * (p + arms - self.s) - self.c * pv
        F = f.sum(0) + self.mt * self.g
        tau = R.T @ np.cross(arms, f).sum(0)
        m = self.m[:, None]
        S = (m * d).sum(0)
        Sd, Sdd = (m * dv).sum(0), (m * da).sum(0)
        Jc = sum(mi * (di @ di * np.eye(3) - np.outer(di, di)) for mi, di in zip(self.m, d, strict=True))
        Fb = R.T @ F - Sdd - 2 * np.cross(w, Sd) - np.cross(w, np.cross(w, S))
        gb = R.T @ self.g
        rest = (
            tau + np.cross(S, gb) - np.cross(w, (self.J + Jc) @ w)
            - (m * np.cross(d, da)).sum(0) - (m * np.cross(d, np.cross(2 * w, dv))).sum(0)
        )
        # m a - S x alpha = Fb ; S x a + (J + Jc) alpha = rest
        Sx = np.array([[0, -S[2], S[1]], [S[2], 0, -S[0]], [-S[1], S[0], 0]])
        A = np.block([[self.mt * np.eye(3), -Sx], [Sx, self.J + Jc]])
        sol = np.linalg.solve(A, np.r_[Fb, rest])
        return R @ sol[:3], sol[3:]

    def rhs(self, t, y, sel):
        a, alpha = self.accel(y, *self.carriages(t, sel))
        qw, qx, qy, qz = y[3:7]
        p, q, r = y[10:13]
        qdot = 0.5 * np.array([-qx * p - qy * q - qz * r, qw * p + qy * r - qz * q,
                               qw * q + qz * p - qx * r, qw * r + qx * q - qy * p])
        return np.r_[y[7:10], qdot, a, alpha]

    def equilibrium(self, q):
        d = self.sc.carriage_positions(q)
        z0 = np.zeros((len(q), 3))

        def res(z):
            th = np.linalg.norm(z[3:])
            ax = z[3:] / th if th > 0 else np.zeros(3)
            y = np.r_[z[:3], np.cos(th / 2), np.sin(th / 2) * ax, np.zeros(6)]
            a, al = self.accel(y, d, z0, z0)
            return np.r_[a, al * 1e3]

        z = fsolve(res, np.zeros(6), xtol=1e-14)
        th = np.linalg.norm(z[3:])
        ax = z[3:] / th if th > 0 else np.zeros(3)
        return np.r_[z[:3], np.cos(th / 2), np.sin(th / 2) * ax, np.zeros(6)]

    def simulate(self, rtol=1e-8, atol=1e-12):
        t_eval = self.sc.simulation.sample_times()
        y0 = self.equilibrium(self.sc.initial_positions())
        states = solve_piecewise(self.rhs, y0, t_eval, self.sc.breakpoints, rtol=rtol, atol=atol)
        return t_eval, states, y0
