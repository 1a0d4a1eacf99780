"""``isolator calibrate --report DIR``: report.md with the parameter table, the modes before and after, the
residuals per experiment and the figure."""

from __future__ import annotations

from pathlib import Path

from isolator.calibration.result import CalibrationResult
from isolator.scenario.output_files import write_output_text

__all__ = ["write_report"]


def write_report(result: CalibrationResult, folder: str | Path) -> Path:
    """Write ``folder/report.md`` and ``folder/calibration.png``; returns the report's path."""
    import matplotlib.pyplot as plt

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    fig = result.plot(folder / "calibration.png")
    plt.close(fig)
    lines = [f"# Calibration of {result.calibration.scenario.name}", ""]
    if result.calibration.path is not None:
        lines += [f"Calibration file: `{result.calibration.path}`; scenario `{result.calibration.scenario_file}`.", ""]
    lines += ["## Parameters (SI units)", "", "| parameter | initial | fitted | std | 95 % interval | bounds |",
              "|---|---:|---:|---:|---|---|"]
    for n, e in result.parameters.items():
        lines.append(f"| `{n}` | {e.initial:.6g} | {e.value:.6g} | {e.std:.3g} | [{e.ci95[0]:.6g}, {e.ci95[1]:.6g}] | "
                     f"[{e.bounds[0]:.4g}, {e.bounds[1]:.4g}] |")
    lines += ["", "Identifiable: " + ("yes" if result.identifiable else "**no** (" + "; ".join(
        ", ".join(g) for g in result.unidentifiable) + ")") + f". Residual variance s² = "
              f"{result.fit.residual_variance:.4g} (about 1 when each record's noise estimate is right; the "
              "intervals are scaled by it).", "", "Correlations:", "",
              "| | " + " | ".join(f"`{n}`" for n in result.parameters) + " |",
              "|---|" + "---:|" * len(result.parameters)]
    for n, row in zip(result.parameters, result.correlation, strict=True):
        lines.append(f"| `{n}` | " + " | ".join(f"{v:+.3f}" for v in row) + " |")
    lines += ["", "## Residuals per experiment", "",
              "RMS of the residuals divided by each record's noise estimate (1: the model explains the record to "
              "its noise).", "", "| experiment | kind | points | before | after |", "|---|---|---:|---:|---:|"]
    for n, x in result.experiments.items():
        lines.append(f"| {n} | {x['kind']} | {x['points']} | {x['residual_before']:.4g} | {x['residual_after']:.4g} |")
    lines += ["", "## Modes at the scenario's start", "", "| mode | nominal [Hz] | fitted [Hz] | nominal damping | "
              "fitted damping |", "|---:|---:|---:|---:|---:|"]
    nom, fit = result.modes["nominal"], result.modes["fitted"]
    for i, (a, b, za, zb) in enumerate(zip(nom["frequencies_hz"], fit["frequencies_hz"], nom["damping_ratios"],
                                           fit["damping_ratios"], strict=False)):
        lines.append(f"| {i + 1} | {a:.4g} | {b:.4g} | {za:.3f} | {zb:.3f} |")
    lines += ["", "![calibration](calibration.png)", ""]
    path = folder / "report.md"
    write_output_text(path, "\n".join(lines))
    return path
