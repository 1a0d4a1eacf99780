"""Natural frequencies, damping ratios and mode shapes of the parked table."""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import groupby
from typing import Any

import numpy as np

from isolator.analysis.linear import LinearModel, linearise
from isolator.errors import ParameterError
from isolator.model.equilibrium import DOF_NAMES
from isolator.model.flexible.naming import elastic_mode_names
from isolator.scenario.arguments import check_public
from isolator.scenario.definitions import Scenario
from isolator.scenario.readable import without_dust

__all__ = ["ModeTravel", "Modes", "modes", "modes_over_travel"]


@dataclass(frozen=True)
class Modes:
    """The modes of the table on its isolators, by ascending frequency: the six rigid-body modes, and on a
    top that bends (``[table.flexible]``) its elastic modes coupled with them.

    Attributes
    ----------
    frequencies_hz : ndarray (modes,)
        Undamped natural frequencies ``|lambda| / 2 pi`` [Hz].
    damping_ratios : ndarray (modes,)
        ``-Re(lambda) / |lambda|`` (>= 1: overdamped).
    eigenvalues : ndarray (modes,) complex
        One per mode: the one with positive imaginary part, or for an
        overdamped mode the slower of its two real ones [1/s].
    shapes : ndarray (modes, coordinates)
        Row k: mode k's displacement ``x, y, z`` [m] and rotation ``rx, ry, rz``
        [rad] at the mass centre (then the top's modal coordinates), phase-aligned
        and scaled so that its dominant entry is 1.
    energy_share : ndarray (modes, coordinates)
        Row k: the share of mode k's kinetic energy in each coordinate
        (``M_ii |shape_i|^2``, normalised to sum 1).
    relaxation_rates : ndarray
        Pneumatic tables: the real poles ``-lambda`` [1/s], ascending: the
        chambers' relaxation through orifices and lines, and any table motion
        they damp past oscillating (the oscillating modes are the others).
    integrators : int
        Pneumatic tables: poles at zero, one per leveling group (with the valves
        closed, the air in a group stays, and any such amount is at rest).
    coordinates : tuple of str
        The coordinates' names: ``x .. rz``, then the top's elastic modes by their
        motion (``twist 1``, ``bending x 1``, ...).
    """

    frequencies_hz: np.ndarray
    damping_ratios: np.ndarray
    eigenvalues: np.ndarray
    shapes: np.ndarray
    energy_share: np.ndarray
    relaxation_rates: np.ndarray = field(default_factory=lambda: np.zeros(0))
    integrators: int = 0
    coordinates: tuple[str, ...] = DOF_NAMES

    @property
    def relaxation_times(self) -> np.ndarray:
        """``1 / rate`` of each relaxation pole [s]."""
        return 1.0 / self.relaxation_rates

    @property
    def dominant(self) -> tuple[str, ...]:
        """The coordinate holding most of each mode's kinetic energy (a direction ``x .. rz``, or an elastic
        mode's name)."""
        return tuple(self.coordinates[int(i)] for i in np.argmax(self.energy_share, axis=1))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``frequencies_hz``, ``damping_ratios``, ``shapes`` (objects keyed by direction), ``dominant``."""
        return {
            "frequencies_hz": [float(f) for f in self.frequencies_hz],
            "damping_ratios": [float(z) for z in self.damping_ratios],
            "shapes": [{d: float(v) for d, v in zip(self.coordinates, row, strict=True)} for row in self.shapes],
            "dominant": list(self.dominant),
            "relaxation_rates": [float(r) for r in self.relaxation_rates],
            "integrators": self.integrators,
        }

    def summary(self) -> str:
        """A text table: mode, frequency, damping ratio, dominant direction."""
        width = max(8, *(len(d) for d in self.dominant))
        lines = [f"mode  frequency [Hz]  damping ratio  {'dominant':>{width}}  energy share"]
        for k, (f, z, d) in enumerate(zip(self.frequencies_hz, self.damping_ratios, self.dominant, strict=True)):
            share = ", ".join(
                f"{n} {100 * e:.0f}%" for n, e in zip(self.coordinates, self.energy_share[k], strict=True) if e >= 0.05
            )
            lines.append(f"{k + 1:>4}  {f:>14.4g}  {z:>13.4g}  {d:>{width}}  {share}")
        if self.relaxation_rates.size or self.integrators:
            rates = ", ".join(f"{r:.4g}" for r in self.relaxation_rates)
            lines.append(f"relaxation poles [1/s]: {rates or 'none'}; time constants "
                         + ", ".join(f"{1e3 / r:.3g} ms" for r in self.relaxation_rates))
            lines.append(f"air-mass integrators (valves closed): {self.integrators}")
        return "\n".join(lines)

    def plot(self, title: str = "") -> Any:
        """Bar charts of each mode's energy share per direction; returns the figure."""
        import matplotlib.pyplot as plt

        shown = min(len(self.frequencies_hz), 12)
        rows = max(2, -(-shown // 3))
        fig, axes = plt.subplots(rows, 3, figsize=(11 if len(self.coordinates) <= 6 else 14, 3 * rows), sharey=True,
                                 layout="constrained")
        colours = ["tab:blue"] * 3 + ["tab:orange"] * 3 + ["tab:green"] * (len(self.coordinates) - 6)
        for ax in axes.flat[shown:]:
            ax.set_visible(False)
        for k, ax in enumerate(axes.flat[:shown]):
            ax.bar(self.coordinates, 100 * self.energy_share[k], color=colours)
            if len(self.coordinates) > 6:
                ax.tick_params(axis="x", labelrotation=60, labelsize=7)
            ax.set_title(
                f"mode {k + 1}: {self.frequencies_hz[k]:.3g} Hz, "
                f"$\\zeta$ = {self.damping_ratios[k]:.3g}\nmostly {self.dominant[k]}",
                fontsize=10,
            )
            ax.set_ylim(0, 105)
            ax.grid(axis="y", alpha=0.3)
        for ax in axes[:, 0]:
            ax.set_ylabel("kinetic energy share [%]")
        for ax in axes[-1]:
            ax.set_xlabel("coordinate (blue: translation, orange: rotation, green: the top's elastic modes)"
                          if len(self.coordinates) > 6 else "direction (blue: translation, orange: rotation)",
                          fontsize=8 if len(self.coordinates) > 6 else None)
        fig.suptitle(title or ("Modes of the table on its isolators, the top bending" if len(self.coordinates) > 6
                               else "Rigid-body modes of the table on its isolators"))
        return fig


def modes(lin: LinearModel) -> Modes:
    """The modes of a linearised scenario.

    Parameters
    ----------
    lin : LinearModel
        From :func:`isolator.analysis.linear.linearise`.

    Returns
    -------
    Modes
        Frequencies [Hz], damping ratios, shapes and each mode's dominant motion, lowest first; relaxation
        poles [1/s] apart.

    Examples
    --------
    >>> from isolator import linearise, load_scenario, modes
    >>> m = modes(linearise(load_scenario("paper-table-3-2")))
    >>> m.frequencies_hz.round(2).tolist()
    [3.14, 3.36, 3.45, 5.83, 5.9, 6.3]
    >>> m.dominant
    ('y', 'x', 'z', 'rz', 'ry', 'rx')
    """
    a = np.asarray(lin.system.A)
    eig, vec = np.linalg.eig(a)
    ndof = lin.mass.shape[0]
    omega, zeta, lam, shapes = [], [], [], []
    scale = max(1.0, float(np.abs(eig).max()))
    relaxation, integrators = np.zeros(0), 0
    groups = _one_per_mode(eig)
    if lin.air is not None:  # real poles are the chambers' relaxation (and integrators), not modes
        real = eig.real[np.abs(eig.imag) <= 1e-9 * scale]
        integrators = int(np.sum(np.abs(real) <= 1e-9 * scale))
        relaxation = np.sort(-real[np.abs(real) > 1e-9 * scale])
        groups = [g for g in groups if len(g) == 1]
    for idx in groups:
        if len(idx) == 1:  # an oscillating mode
            value = complex(eig[idx[0]])
            omega.append(abs(value))
            zeta.append(-value.real / abs(value))
        else:  # two real eigenvalues: an overdamped mode (or a free direction)
            l1, l2 = float(eig[idx[0]].real), float(eig[idx[1]].real)
            w = float(np.sqrt(max(l1 * l2, 0.0)))
            omega.append(w)
            zeta.append(-(l1 + l2) / (2 * w) if w > 0 else 1.0)
            value = complex(max(l1, l2))  # the slower of the two
        lam.append(value)
        shapes.append(vec[:ndof, idx[0]])
    order = np.argsort(omega, kind="stable")
    omega_arr, zeta_arr = np.array(omega)[order], np.array(zeta)[order]
    lam_arr, shape_arr = np.array(lam)[order], np.array(shapes)[order]
    mass = np.abs(np.diag(lin.mass))
    energy = mass[None, :] * np.abs(shape_arr) ** 2
    energy /= energy.sum(axis=1, keepdims=True)
    dominant = np.argmax(energy, axis=1)
    ref = shape_arr[np.arange(len(shape_arr)), dominant]
    real = without_dust((shape_arr / ref[:, None]).real, 1.0)  # each shape's largest entry is 1: dust reads 0
    flexible = getattr(lin.scenario.table, "flexible", None)
    names = DOF_NAMES + (elastic_mode_names(flexible.data) if flexible is not None else ())
    return Modes(omega_arr / (2 * np.pi), zeta_arr, lam_arr, real, energy, relaxation, integrators, names)


def _one_per_mode(eig: np.ndarray) -> list[tuple[int, ...]]:
    """Indices of the eigenvalues that make the modes: one of each complex pair, pairs of real ones."""
    scale = max(1.0, float(np.abs(eig).max()))
    complex_idx = [i for i in range(eig.size) if eig[i].imag > 1e-9 * scale]
    real_idx = sorted((i for i in range(eig.size) if abs(eig[i].imag) <= 1e-9 * scale), key=lambda i: eig[i].real)
    # overdamped (or free) directions give two real eigenvalues each; pair them in order
    pairs: list[tuple[int, ...]] = [(real_idx[k], real_idx[k + 1]) for k in range(0, len(real_idx) - 1, 2)]
    singles: list[tuple[int, ...]] = [(i,) for i in complex_idx]
    return singles + pairs


@dataclass(frozen=True)
class ModeTravel:
    """Modes as carriages travel, one carriage at a time (the others at their start).

    Attributes
    ----------
    carriages : tuple of str
        The carriages that move.
    positions : list of ndarray
        Their coordinates swept [m], one array per carriage.
    frequencies_hz, damping_ratios : list of ndarray (n, 6)
        Per carriage, per position, the six modes ascending.
    dominant : list of tuple of tuple of str
        Per carriage, per position, each mode's dominant motion (``x`` .. ``rz``, as :attr:`Modes.dominant`).
    """

    carriages: tuple[str, ...]
    positions: list[np.ndarray]
    frequencies_hz: list[np.ndarray]
    damping_ratios: list[np.ndarray]
    dominant: list[tuple[tuple[str, ...], ...]] = field(default_factory=list)

    def motion(self, carriage: int, mode: int) -> str:
        """The dominant motion of mode ``mode`` (0-based, ascending) over carriage ``carriage``'s travel.

        Parameters
        ----------
        carriage, mode : int
            Indices of the carriage (in :attr:`carriages`) and of the mode.

        Returns
        -------
        str
            The motion, e.g. ``rz``; where it changes along the travel, each in travel order
            (``rz → rx → rz``); ``mode <n>`` without dominant motions.
        """
        if carriage >= len(self.dominant):
            return f"mode {mode + 1}"
        return " → ".join(motion for motion, _ in groupby(at[mode] for at in self.dominant[carriage]))

    def plot(self, title: str = "") -> Any:
        """Frequencies (top) and damping ratios (bottom) over each carriage's travel; returns the figure."""
        import matplotlib.pyplot as plt

        n = max(1, len(self.carriages))
        fig, axes = plt.subplots(2, n, figsize=(5.5 * n, 6.5), squeeze=False, sharex="col", layout="constrained")
        for j, name in enumerate(self.carriages):
            q = self.positions[j] * 1e3
            for k in range(6):
                axes[0, j].plot(q, self.frequencies_hz[j][:, k], label=self.motion(j, k))
                axes[1, j].plot(q, self.damping_ratios[j][:, k], label=self.motion(j, k))
            axes[0, j].set_title(f"carriage {name} travels (others at their start)")
            axes[1, j].set_xlabel(f"position of {name} [mm]")
            axes[0, j].set_ylabel("natural frequency [Hz]")
            axes[1, j].set_ylabel("damping ratio [-]")
            for ax in axes[:, j]:
                ax.grid(alpha=0.3)
            axes[0, j].legend(fontsize=8, loc="best", title="dominant motion", title_fontsize=8)
        if not self.carriages:
            axes[0, 0].text(0.5, 0.5, "no carriage moves", ha="center", transform=axes[0, 0].transAxes)
        fig.suptitle(title or "How the modes move as the stage travels")
        return fig


def modes_over_travel(scenario: Scenario, samples: int = 21) -> ModeTravel:
    """Sweep each moving carriage over its stroke and compute the modes at each position.

    Parameters
    ----------
    scenario : Scenario
        The scenario (or a bundled scenario's name, or a TOML file's path).
    samples : int
        Positions per carriage (>= 2).

    Returns
    -------
    ModeTravel
        Each carriage's positions [m] and the table's modes at each (frequencies, damping ratios, dominant
        motions).

    Examples
    --------
    >>> from isolator import load_scenario, modes_over_travel
    >>> travel = modes_over_travel(load_scenario("paper-table-3-2"), samples=5)
    >>> travel.carriages
    ('x-stage', 'y-stage')
    >>> [travel.motion(0, k) for k in range(6)]   # the modes' dominant motions over the x stage's travel
    ['y', 'x', 'z', 'rz → rx → rz', 'ry', 'rx → rz → rx']
    >>> fig = travel.plot()
    """
    if isinstance(samples, bool) or not isinstance(samples, int | np.integer) or not 2 <= samples <= 100_000:
        raise ParameterError(f"samples: must be a whole number from 2 to 100000, got {samples!r}")
    t_end = scenario.simulation.duration
    names, positions, freqs, zetas, dominant = [], [], [], [], []
    for carriage in scenario.carriages:
        lo, hi = carriage.profile.position_range(t_end)
        if hi - lo <= 0:
            continue
        q = np.linspace(lo, hi, samples)
        rows = [modes(linearise(scenario, positions={carriage.name: v})) for v in q]
        names.append(carriage.name)
        positions.append(q)
        freqs.append(np.array([m.frequencies_hz for m in rows]))
        zetas.append(np.array([m.damping_ratios for m in rows]))
        dominant.append(tuple(m.dominant for m in rows))
    return ModeTravel(tuple(names), positions, freqs, zetas, dominant)


check_public(globals(), ("Modes", "modes", "modes_over_travel"))
