"""The trade-off study's ``designs.csv``: every design's numbers, with the band its settling time is measured in."""

from __future__ import annotations

import csv

from isolator.scenario.arguments import check_public
from isolator.scenario.output_files import atomic_output

from .reporting import band_cell
from .tradeoff_results import TradeoffStudy

__all__ = ["write_designs_csv"]


def write_designs_csv(study: TradeoffStudy) -> None:
    """``designs.csv`` of a :class:`studies.tradeoff.TradeoffStudy`: one row per design.

    Columns: the two scales [-], ``settling_time_max_s`` (with a ``[sequence]``: ``total_time_s``), ``band``
    (``isolator simulate --band``'s form, m and rad; empty for a sequence), with ``[[windows]]``
    ``window_settling_time_max_s`` and ``moves_per_hour`` (a sequence: ``steps_per_hour``), the
    transmissibility at the reference frequency and the resonance peak [m/m], its frequency [Hz], with a random
    source ``budget_rms_m`` (the passive error budget's displacement RMS at the tool, the worst of x, y, z [m])
    and ``budget_axis`` (which), ``status``.
    """
    throughput = study.has_throughput
    rate = ["steps_per_hour"] if study.sequence else ["window_settling_time_max_s", "moves_per_hour"]
    with atomic_output(study.folder / "designs.csv", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["stiffness_scale", "damping_scale", "total_time_s" if study.sequence else
                         "settling_time_max_s", "band", *(rate if throughput else []),
                         f"transmissibility_at_{study.reference_hz:g}_hz", "peak_transmissibility",
                         "peak_frequency_hz", *(["budget_rms_m", "budget_axis"] if study.has_budget else []),
                         "status"])
        for i, ks in enumerate(study.stiffness):
            for j, cs in enumerate(study.damping):
                extra = []
                if throughput:
                    extra = [f"{study.per_hour[i, j]:.6g}"] if study.sequence else [
                        f"{study.window_settling[i, j]:.6g}", f"{study.per_hour[i, j]:.6g}"]
                writer.writerow([f"{ks:.6g}", f"{cs:.6g}", f"{study.settling_time[i, j]:.6g}",
                                 band_cell(study.band, study.half_widths[i, j]), *extra,
                                 f"{study.transmissibility[i, j]:.6g}", f"{study.peak[i, j]:.6g}",
                                 f"{study.peak_hz[i, j]:.6g}",
                                 *([f"{study.budget_rms[i, j]:.6g}", study.budget_axis[i, j]] if study.has_budget
                                   else []), study.status[i, j]])


check_public(globals())
