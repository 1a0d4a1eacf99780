"""The calibration figure explains itself: the grey coherence fill has its right axis labelled and a legend
entry, and the phase curves are continuous (no jumps at +-180 deg) and drawn on the fitted model's branch."""

from __future__ import annotations

import numpy as np
import pytest

from isolator.calibration import calibrate
from isolator.calibration.figure import calibration_figure


@pytest.fixture(scope="module")
def figure(tmp_path_factory, mujoco_records, write_calibration):
    move, floor = mujoco_records
    result = calibrate(write_calibration(tmp_path_factory.mktemp("fig"), move, floor, 3, ("floor", "move")))
    return calibration_figure(result)


def test_the_coherence_axis_is_labelled_and_in_the_legend(figure):
    magnitudes = [ax for ax in figure.axes if ax.get_ylabel().startswith("|H|")]
    coherence = [ax for ax in figure.axes if ax.get_ylabel() == "coherence [-]"]
    assert magnitudes
    assert len(coherence) == len(magnitudes)
    for ax in coherence:
        assert ax.get_ylim() == (0, 1.05)
        assert len(ax.collections) == 1  # the grey fill
    legend = next(ax.get_legend() for ax in magnitudes if ax.get_legend() is not None)
    assert [t.get_text() for t in legend.get_texts()] == ["measured H1", "nominal model", "fitted model",
                                                         "coherence (right axis)"]


def test_the_phase_is_unwrapped(figure):
    phases = [ax for ax in figure.axes if ax.get_ylabel() == "phase, unwrapped [deg]"]
    assert phases
    for ax in phases:
        measured, nominal, fitted = ax.get_lines()
        for line in (nominal, fitted):  # the models' phases are smooth: no step near 360 deg
            assert np.max(np.abs(np.diff(line.get_ydata()))) < 90
        # the measured phase within 180 deg of the fitted one's, on its branch
        assert np.all(np.abs(measured.get_ydata() - fitted.get_ydata()) <= 180 + 1e-9)
    spans = [np.ptp(ax.get_lines()[2].get_ydata()) for ax in phases]
    assert max(spans) > 180  # a resonance turns the phase by 180 deg or more: wrapped, it would jump
