"""The settling band as an object: each kind resolves to six half-widths, every settling time carries its
band (JSON, summary, plot), and ``isolator simulate --band`` measures any run in a given band."""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import active_dict, base_dict, make
from isolator import SIGNALS, Band, ParameterError, Settling, Simulator
from isolator.cli.app import main
from isolator.simulation.band import MOTION_FLOOR, parse_half_widths

PEAKS = np.array([2e-5, 1e-6, 3e-7, 4e-5, 1e-4, 0.0])


def test_own_band_resolves_to_a_fraction_of_the_runs_own_peaks():
    band = Band.own(0.05)
    assert band.kind == "own"
    assert band.half_widths is None
    np.testing.assert_allclose(band.resolve(PEAKS), 0.05 * PEAKS)
    resolved = band.resolved(PEAKS)
    assert resolved.kind == "own"
    assert resolved.fraction == 0.05
    assert resolved.widths == dict(zip(SIGNALS, 0.05 * PEAKS, strict=True))
    # stacked runs: each its own peaks
    np.testing.assert_allclose(band.resolve(np.vstack([PEAKS, 2 * PEAKS])), 0.05 * np.vstack([PEAKS, 2 * PEAKS]))
    assert Band.from_settling(Settling()) == Band.own(0.05)


def test_baseline_band_is_a_fraction_of_the_baselines_peaks_whatever_the_run():
    band = Band.of_baseline("passive", dict(zip(SIGNALS, PEAKS, strict=True)), 0.1)
    assert (band.kind, band.fraction, band.baseline) == ("baseline", 0.1, "passive")
    # a signal the baseline does not move: a fraction of the motion floor, not zero
    np.testing.assert_allclose(band.half_widths, 0.1 * np.maximum(PEAKS, MOTION_FLOOR))
    np.testing.assert_allclose(band.resolve(np.ones(6)), band.half_widths)
    assert band.resolved(np.ones(6)) is band


def test_absolute_band_from_tolerance_values_or_the_option():
    band = Band.from_settling(Settling(fraction=None, tolerance=(1e-6, 2e-6)))
    assert band.kind == "absolute"
    assert band.fraction is None
    assert band.half_widths == (1e-6, 1e-6, 1e-6, 2e-6, 2e-6, 2e-6)
    np.testing.assert_allclose(band.resolve(PEAKS), [1e-6] * 3 + [2e-6] * 3)
    assert parse_half_widths("x=1e-6,y=1e-6,z=1e-6,rx=2e-6,ry=2e-6,rz=2e-6") == band
    assert parse_half_widths(band.option()) == band
    assert Band.absolute(list(band.half_widths)) == band


@pytest.mark.parametrize(("text", "named"), [
    ("x=1e-6", "missing y"),
    ("x=1e-6,y=1e-6,z=1e-6,rx=1,ry=1,rz=nan", "rz"),
    ("x=1e-6,y=1e-6,z=1e-6,rx=1,ry=1,rz=-1", "rz"),
    ("x=1e-6,y=1e-6,z=1e-6,rx=1,ry=1,q=1", "q=1"),
    ("x=abc", "x must be a number"),
])
def test_bad_half_widths_name_the_option(text, named):
    with pytest.raises(ParameterError, match="--band") as info:
        parse_half_widths(text)
    assert named in str(info.value)


def test_band_dict_round_trip():
    band = Band.of_baseline("paper", PEAKS + 1e-6)
    data = json.loads(json.dumps(band.to_dict()))
    assert data["kind"] == "baseline"
    assert data["baseline"] == "paper"
    assert set(data["half_widths"]) == set(SIGNALS)
    assert Band.from_dict(data) == band
    assert Band.from_dict(data["half_widths"]).half_widths == band.half_widths
    with pytest.raises(ParameterError, match=r"band\.half_widths"):
        Band.from_dict({"kind": "absolute", "half_widths": {"x": 1.0}})


def test_every_run_carries_its_band_in_json_summary_and_plot():
    response = Simulator(make(base_dict())).run()
    band = response.band
    assert band.kind == "own"
    assert band.fraction == 0.05
    assert band.widths == pytest.approx({k: 0.05 * v for k, v in response.peak.items()})
    assert all(response.settling[k].band == pytest.approx(band.widths[k]) for k in SIGNALS)
    data = response.to_dict()
    assert data["band"] == {"kind": "own", "fraction": 0.05, "baseline": None, "half_widths": band.widths}
    line = [x for x in response.summary().splitlines() if x.startswith("settling band")]
    assert len(line) == 1
    assert "5 % of each signal's own peak" in line[0]
    assert "µm" in line[0]
    assert "µrad" in line[0]
    import matplotlib

    matplotlib.use("Agg")
    fig = response.plot()
    assert "own peak" in fig._suptitle.get_text()


def test_with_band_equals_a_run_given_the_band():
    sim = Simulator(make(base_dict()))
    own = sim.run()
    band = Band.absolute([2e-6] * 3 + [5e-6] * 3)
    given, again = sim.run(band=band), own.with_band(band)
    assert given.band == again.band == band
    assert given.settling_time == again.settling_time
    assert given.settling_time != own.settling_time
    # the own band, resolved, given back as absolute half-widths: the same numbers
    assert sim.run(band=Band.absolute(own.band.half_widths)).settling_time == own.settling_time


def test_with_band_on_runs_stepped_with_forces():
    from controllers.feedforward import feedforward_allocation

    scenario = make(active_dict())
    sim = Simulator(scenario)
    run = sim.run(forces=feedforward_allocation(scenario).forces)
    band = Band.absolute(run.band.half_widths)
    assert sim.run(forces=feedforward_allocation(scenario).forces, band=band).settling_time == run.settling_time
    assert run.with_band(band).settling_time == run.settling_time


def _json(capsys, args):
    assert main(args) == 0
    return json.loads(capsys.readouterr().out)


def test_simulate_band_option_reproduces_a_band(tmp_path, capsys):
    scenario = "paper-table-3-2"
    own = _json(capsys, ["simulate", scenario, "--json"])
    assert own["band"]["kind"] == "own"
    option = Band.from_dict(own["band"]["half_widths"]).option()
    fixed = _json(capsys, ["simulate", str(scenario), "--json", "--band", option])
    assert fixed["band"]["kind"] == "absolute"
    assert fixed["band"]["half_widths"] == own["band"]["half_widths"]
    assert fixed["settling_time"] == own["settling_time"]
    # a study's band object, or a file holding one under "band"
    (tmp_path / "band.json").write_text(json.dumps({"settling_time_max": 1.0, "band": own["band"]}))
    read = _json(capsys, ["simulate", str(scenario), "--json", "--band-json", str(tmp_path / "band.json")])
    assert read["settling_time"] == own["settling_time"]
    # a wider band settles sooner
    wide = Band.absolute([10 * v for v in own["band"]["half_widths"].values()]).option()
    assert _json(capsys, ["simulate", str(scenario), "--json", "--band", wide])["settling_time_max"] < \
        own["settling_time_max"]


@pytest.mark.parametrize(("args", "named"), [
    (["--band", "x=1e-6"], "--band"),
    (["--band", "x=1e-6,y=1,z=1,rx=1,ry=1,rz=0"], "--band"),
    (["--band-json", "missing.json"], "--band-json"),
])
def test_simulate_bad_band_is_one_line_exit_2(tmp_path, capsys, monkeypatch, args, named):
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "--json", *args]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert named in err


def test_simulate_band_json_not_a_band(tmp_path, capsys):
    (tmp_path / "b.json").write_text("[1, 2]")
    assert main(["simulate", "--json", "--band-json", str(tmp_path / "b.json")]) == 2
    assert "--band-json" in capsys.readouterr().err
