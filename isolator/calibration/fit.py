"""The least-squares fit of every experiment together, its uncertainty and identifiability.

The unknowns are the logarithms of the fitted parameters, inside the logarithms of their bounds
(``scipy.optimize.least_squares``, trust-region reflective). Each experiment's residuals are already divided
by its own noise estimate; the covariance of the log-parameters is ``max(s^2, 1) (J^T J)^-1`` with ``J`` the
weighted Jacobian at the solution and ``s^2 = sum r^2 / (m - n)`` the residual variance: a misfit beyond the
noise estimates widens the intervals, a residual below them does not narrow them (the noise estimates are
absolute, and neighbouring H1 bins are correlated through the window, which a small residual variance would
hide: with ``s^2`` alone a floor record's intervals held the truth 81 % of the time over 30 seeds). A
parameter's 95 % interval is ``exp(log value +- t sd)`` with Student's ``t`` for ``m - n`` degrees of freedom
(positive, as a stiffness must be); its standard deviation ``value * sd`` (first order). A parameter of a
direction the records do not fix gets no interval (``std`` infinite, ``ci95`` its bounds).

Identifiability (the contract): the information matrix ``J^T J`` scaled to unit diagonal is singular to
``1e-8`` of its largest eigenvalue, or a correlation exceeds ``0.999``. The parameters of each unresolved
direction (an eigenvector's entries of at least 0.1 of its largest, or a group of correlated parameters)
are reported together.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from isolator.calibration.definition import Calibration
from isolator.calibration.experiments import FloorExperiment, MoveExperiment, Residuals
from isolator.errors import OptimisationError, ParameterError, SimulationError, UnstableTableError

__all__ = ["CORRELATION_LIMIT", "EIGEN_LIMIT", "Fit", "fit_parameters", "unidentifiable_groups"]

#: an information matrix singular to this fraction of its largest eigenvalue cannot tell parameters apart
EIGEN_LIMIT = 1e-8
#: nor can a correlation above this
CORRELATION_LIMIT = 0.999


@dataclass(frozen=True)
class Fit:
    """The fitted values and their uncertainty.

    Attributes
    ----------
    values : ndarray (n,)
        [SI]
    std : ndarray (n,)
        [SI]
    ci95 : ndarray (n, 2)
        [SI]
    correlation : ndarray (n, n)
    unidentifiable : list of list of str
        The parameters of each direction the records cannot resolve (empty: identifiable).
    residual_variance : float
        ``s^2``, dimensionless (about 1 when the noise estimates are right).
    evaluations : int
        Model evaluations the fit took.
    residuals_before, residuals_after : dict of str to float
        RMS of each experiment's weighted residuals at the start and at the fit.
    residuals : dict of str to ndarray
        Each experiment's weighted residuals at the fit.
    """

    values: np.ndarray
    std: np.ndarray
    ci95: np.ndarray
    correlation: np.ndarray
    unidentifiable: list[list[str]]
    residual_variance: float
    evaluations: int
    residuals_before: dict[str, float]
    residuals_after: dict[str, float]
    residuals: dict[str, np.ndarray] = field(default_factory=dict, repr=False)


def _tangents(calibration: Calibration, values: np.ndarray) -> np.ndarray:
    """d p / d log(value_j), rows (params, parameter vector size)."""
    out = np.zeros((len(calibration.parameters), calibration.layout.size))
    for j, (f, v) in enumerate(zip(calibration.parameters, values, strict=True)):
        out[j, list(f.entries)] = v
    return out


def fit_parameters(calibration: Calibration, experiments: Sequence[FloorExperiment | MoveExperiment],
                   progress: Callable[[str], None] | None = None, jacobian: str = "model") -> Fit:
    """Fit the calibration's parameters to every experiment together.

    ``jacobian``: "model" (the floor model's exact derivatives, the move's perturbed runs in one batch of SIMD
    lanes) or "differences" (scipy's forward differences, every run on its own: the baseline the benchmark
    compares with).

    Raises
    ------
    OptimisationError
        The model cannot be evaluated near the start (no stable rest, a diverging run).
    """
    if jacobian not in ("model", "differences"):
        raise ParameterError(f"jacobian: must be 'model' or 'differences', got {jacobian!r}")
    names = calibration.names
    lo = np.log([f.bounds[0] for f in calibration.parameters])
    hi = np.log([f.bounds[1] for f in calibration.parameters])
    cache: dict[bytes, list[Residuals]] = {}
    count = [0]

    def evaluate(x: np.ndarray, derivatives: bool) -> list[Residuals]:
        """The residuals at ``x`` (and their Jacobian when asked: only at the points the solver keeps)."""
        key = np.asarray(x, dtype=float).tobytes()
        known = cache.get(key)
        if known is None or (derivatives and any(r.J is None for r in known)):
            values = np.exp(x)
            p = calibration.vector(values)
            tangents = _tangents(calibration, values) if derivatives else None
            try:
                known = [e.residuals(p, tangents) for e in experiments]
            except (UnstableTableError, SimulationError) as exc:
                where = ", ".join(f"{n} = {v:.6g}" for n, v in zip(names, values, strict=True))
                raise OptimisationError(f"calibrate: the model cannot be evaluated at {where}: {exc}") from None
            cache.clear()
            cache[key] = known
            count[0] += 1
            if progress is not None:
                cost = sum(float(r.r @ r.r) for r in known)
                progress(f"evaluation {count[0]}: weighted cost {cost:.6g}")
        return known

    def fun(x: np.ndarray) -> np.ndarray:
        return np.concatenate([r.r for r in evaluate(x, False)])

    def jac(x: np.ndarray) -> np.ndarray:
        return np.vstack([r.J for r in evaluate(x, True) if r.J is not None])

    x0 = np.log(calibration.initial)
    before = {e.name: _rms(r.r) for e, r in zip(experiments, evaluate(x0, False), strict=True)}
    solution = least_squares(fun, x0, jac=jac if jacobian == "model" else "2-point", bounds=(lo, hi), method="trf",
                             x_scale=1.0, xtol=1e-10,
                             ftol=1e-12, gtol=1e-12, max_nfev=200)
    x = solution.x
    final = evaluate(x, True)  # the covariance from the model's Jacobian, whichever the solver used
    after = {e.name: _rms(r.r) for e, r in zip(experiments, final, strict=True)}
    r = np.concatenate([f.r for f in final])
    J = np.vstack([f.J for f in final if f.J is not None])
    m, n = r.size, x.size
    dof = max(m - n, 1)
    s2 = float(r @ r) / dof
    info = J.T @ J
    cov = max(s2, 1.0) * np.linalg.pinv(info, rcond=1e-15)
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    scale = np.where(sd > 0, sd, 1.0)
    correlation = np.clip(cov / np.outer(scale, scale), -1.0, 1.0)
    np.fill_diagonal(correlation, 1.0)
    from scipy import stats  # imported where used: scipy.stats takes a quarter of a second

    quantile = float(stats.t.ppf(0.975, dof))
    values = np.exp(x)
    ci = np.column_stack([np.exp(x - quantile * sd), np.exp(x + quantile * sd)])
    groups = unidentifiable_groups(info, names)
    std = values * sd
    for name in {n for g in groups for n in g}:  # a direction the records do not fix: no interval at all
        j = names.index(name)
        std[j] = math.inf
        ci[j] = calibration.parameters[j].bounds
    return Fit(values, std, ci, correlation, groups, s2, count[0], before, after,
               {e.name: f.r for e, f in zip(experiments, final, strict=True)})


def _rms(r: np.ndarray) -> float:
    return float(np.sqrt(np.mean(r**2))) if r.size else 0.0


def unidentifiable_groups(info: np.ndarray, names: Sequence[str]) -> list[list[str]]:
    """The parameters of each direction the information matrix ``info`` (n, n) cannot resolve: eigenvalues
    below :data:`EIGEN_LIMIT` of the largest (of the unit-diagonal scaled matrix), correlations above
    :data:`CORRELATION_LIMIT`."""
    d = np.sqrt(np.clip(np.diag(info), 1e-300, None))
    scaled = info / np.outer(d, d)
    vals, vecs = np.linalg.eigh(scaled)
    groups: list[set[int]] = []
    top = max(float(vals[-1]), 1e-300)
    for k in range(vals.size):
        if vals[k] < EIGEN_LIMIT * top:
            v = np.abs(vecs[:, k])
            groups.append({int(i) for i in np.flatnonzero(v >= 0.1 * v.max())})
    try:
        cov = np.linalg.inv(scaled)
        sd = np.sqrt(np.abs(np.diag(cov)))
        corr = cov / np.outer(sd, sd)
    except np.linalg.LinAlgError:
        corr = np.eye(len(names))
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            if abs(corr[i, j]) > CORRELATION_LIMIT:
                groups.append({i, j})
    merged: list[set[int]] = []
    for g in groups:  # join groups that share a parameter
        joined = [m for m in merged if m & g]
        for m in joined:
            merged.remove(m)
            g = g | m
        merged.append(g)
    return [[names[i] for i in sorted(g)] for g in sorted(merged, key=min)]
