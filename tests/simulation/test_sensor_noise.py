"""Sensor noise with a spectrum (docs/scenario-format.md, "Error budget: random disturbances and noise at the
points"): a sensor's noise is a sequence at the controller's rate whose one-sided PSD below half that rate is
its ``noise_psd``; white ``noise`` (RMS per sample) is drawn as before, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import welch

from isolator import Simulator, scenario_from_dict
from isolator.scenario.random_sources import SpectralDensity
from isolator.scenario.sensors import Sensor
from isolator.simulation.closed_loop import controller_law
from isolator.simulation.sensor_noise import sensor_noise, shaped_noise
from sampled_loops import RATE, dynamic, geophone_data

#: a geophone-like noise floor that falls as f^-2, then f^-3 [(m/s)^2/Hz], zero outside 2-300 Hz
TABLE = SpectralDensity((1e-14, 1e-16, 1e-19), (2.0, 20.0, 200.0))


def test_shaped_noise_has_the_table_spectrum():
    """Welch's estimate (Hann, 2048-sample segments without overlap: each bin an average of K independent
    exponential periodograms, relative standard error 1/sqrt(K)) equals the table in every bin within 5 sigma,
    and over every band of 20 alternate bins (nearly independent with Hann) within 4 sigma of the mean."""
    n, nperseg = 2**20, 2048
    segments = n // nperseg
    white = np.random.default_rng(3).standard_normal(n)
    noise = shaped_noise(white, TABLE, RATE)
    f, psd = welch(noise, RATE, window="hann", nperseg=nperseg, noverlap=0)
    inside = (f >= 8.0) & (f <= 180.0)
    ratio = psd[inside] / TABLE(f[inside])
    sigma = 1.0 / np.sqrt(segments)
    assert np.abs(ratio - 1).max() < 5 * sigma, np.abs(ratio - 1).max() / sigma
    alternate = ratio[::2]
    bands = alternate[: alternate.size // 20 * 20].reshape(-1, 20).mean(axis=1)
    assert np.abs(bands - 1).max() < 4 * sigma / np.sqrt(20), (bands - 1) / (sigma / np.sqrt(20))
    # outside the table the density is zero: nothing but the window's leakage there (Hann: < 1e-6 of inside)
    assert psd[(f > 260.0) & (f < 900.0)].max() < 1e-6 * TABLE(np.array([200.0]))[0]
    # and the variance is the integral of the table, within 4 sigma: the relative standard error of a
    # variance over T seconds is 1 / sqrt(T B), B = (int S)^2 / int S^2 the effective bandwidth
    grid = np.geomspace(2.0, 200.0, 20001)
    total, squares = np.trapezoid(TABLE(grid), grid), np.trapezoid(TABLE(grid) ** 2, grid)
    assert noise.var() == pytest.approx(total, rel=4 * np.sqrt(squares / (n / RATE)) / total)


def test_a_flat_density_is_white_noise_of_the_same_rms():
    """``noise_psd = 2 sigma^2 / fs`` shapes nothing: the samples are ``sigma * w`` to rounding."""
    white = np.random.default_rng(0).standard_normal((4001, 2))
    sigma = 3e-8
    out = shaped_noise(white, SpectralDensity.flat(2 * sigma**2 / RATE), RATE)
    np.testing.assert_allclose(out, sigma * white, rtol=0, atol=1e-12 * sigma)


def _with_psd(flat: bool = False) -> dict:
    """The parked geophone table, its first four geophones with a ``noise_psd`` (the table, or the flat density
    of their white noise) instead of ``noise``; the others keep their white ``noise``."""
    data = geophone_data()
    for sensor in data["sensors"][:4]:
        sigma = sensor.pop("noise")
        sensor["noise_psd"] = 2 * sigma**2 / RATE if flat else TABLE.to_toml()
    return data


def test_the_controller_draws_each_sensor_with_its_spectrum():
    """One standard-normal draw per tick and sensor, as before: white sensors read ``noise * w`` bit for bit,
    sensors with ``noise_psd`` their column of the same draw shaped by the spectrum."""
    s = scenario_from_dict(_with_psd())
    sim = Simulator(s)
    p = sim.parameters
    start, _ = sim.equilibria(p)
    ctrl = dynamic(s)
    t = np.arange(2**17) / RATE
    quiet = controller_law(s, sim.model, p, start, ctrl).offsets(t)
    noisy = controller_law(s, sim.model, p, start, ctrl, noise=True, seed=7).offsets(t) - quiet
    w = np.random.default_rng(7).standard_normal((t.size, len(s.sensors)))
    sigma = np.array([x.noise for x in s.sensors])
    np.testing.assert_array_equal(noisy[:, 4:], (quiet[:, 4:] + w[:, 4:] * sigma[4:]) - quiet[:, 4:])
    np.testing.assert_allclose(noisy[:, :4], shaped_noise(w[:, :4], TABLE, RATE), rtol=0, atol=1e-20)
    np.testing.assert_array_equal(sensor_noise(s.sensors, w, RATE)[:, 4:], w[:, 4:] * sigma[4:])
    grid = np.geomspace(2.0, 200.0, 20001)
    rms = np.sqrt(np.trapezoid(TABLE(grid), grid))
    # 65 s of a process of effective bandwidth 6 Hz: the RMS within 2.5 % (one sigma)
    np.testing.assert_allclose(noisy[:, :4].std(axis=0), rms, rtol=0.1)
    # a sensor without noise stays quiet
    still = Sensor("still", "table", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), "velocity")
    assert not sensor_noise([still], w[:, :1], RATE).any()


def test_white_noise_runs_are_unchanged_and_a_flat_spectrum_is_the_same_run():
    """The closed loop with the geophones' white noise, and with the same noise given as its flat density
    ``2 noise^2 / fs``: the same run to rounding."""
    white = scenario_from_dict(geophone_data())
    flat = scenario_from_dict(_with_psd(flat=True))
    ctrl = dynamic(white)
    one = Simulator(white).run(controller=ctrl, noise=True, seed=4)
    two = Simulator(flat).run(controller=ctrl, noise=True, seed=4)
    quiet = Simulator(white).run(controller=ctrl)
    moved = np.abs(one.signals - quiet.signals).max(axis=1)
    assert (moved > 0).all()
    np.testing.assert_allclose(two.signals, one.signals, rtol=0, atol=1e-9 * moved.max())


def test_the_command_draws_the_spectrum(tmp_path, capsys):
    """``isolator simulate --controller DIR --noise`` on a scenario file with ``noise_psd``: the library's run
    with the same seed, and not the run with the sensors' noise left out."""
    import json

    import tomli_w

    from conftest import run_command

    data = _with_psd()
    scenario_file = tmp_path / "noisy.toml"
    scenario_file.write_text(tomli_w.dumps(data))
    s = scenario_from_dict(data)
    ctrl = dynamic(s)
    (tmp_path / "ctl").mkdir()
    ctrl.to_json(tmp_path / "ctl" / "controller.json")
    status, out, err = run_command(["simulate", str(scenario_file), "--controller", str(tmp_path / "ctl"), "--noise",
                                    "--seed", "2", "--json"], capsys)
    assert status == 0, err
    peaks = json.loads(out)["peak"]
    ours = Simulator(s).run(controller=ctrl, noise=True, seed=2).peak
    for key, value in ours.items():
        assert peaks[key] == pytest.approx(value, rel=1e-9, abs=1e-18), key
    # the first four geophones alone (the others' white noise off) move the table
    for sensor in data["sensors"][4:]:
        sensor["noise"] = 0.0
    only_psd = Simulator(scenario_from_dict(data)).run(controller=ctrl, noise=True, seed=2)
    quiet = Simulator(s).run(controller=ctrl)
    assert np.abs(quiet.signals).max() < 1e-14  # parked, nothing pushes: at rest to rounding
    assert (np.abs(only_psd.signals).max(axis=1) > 1e-11).all()  # 0.3-0.9 nm and nrad
