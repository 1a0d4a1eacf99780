"""Calibration inputs: records that cannot tell parameters apart are refused naming them; every bad calibration file
or record is one line, exit status 2, nothing written."""

from __future__ import annotations

import json

import numpy as np
import pytest
import tomli_w

from isolator import ParameterLayout, scenario_from_dict
from isolator.calibration import calibrate
from isolator.calibration.floor_model import FloorModel
from isolator.cli.app import main
from isolator.errors import UnidentifiableError


def _symmetric_table() -> dict:
    """A symmetric table without carriages, a heave accelerometer at its centre and one on the floor."""
    isolators = [{"position": [x, y, -0.15], "stiffness": [5e5, 5e5, 5e5], "damping": [4e3, 4e3, 4e3]}
                 for x in (-0.8, 0.8) for y in (-0.5, 0.5)]
    return {"name": "symmetric", "table": {"mass": 1500.0, "size": [2.0, 1.2, 0.3]}, "isolators": isolators,
            "simulation": {"duration": 2.0},
            "sensors": [{"name": "t-z", "on": "table", "position": [0.0, 0.0, 0.15], "direction": [0.0, 0.0, 1.0],
                         "quantity": "acceleration"},
                        {"name": "f-z", "on": "floor", "position": [0.0, 0.0, -0.5], "direction": [0.0, 0.0, 1.0],
                         "quantity": "acceleration"}]}


def _heave_record(path, data: dict, seed: int = 0, rate: float = 100.0, duration: float = 40.0) -> None:
    """A steady, periodic heave record: a random floor acceleration along z (1-15 Hz) through the linear model's
    exact response, 1 % noise."""
    sc = scenario_from_dict(data)
    layout = ParameterLayout.of(sc)
    n = int(rate * duration)
    f = np.fft.rfftfreq(n, 1 / rate)
    rng = np.random.default_rng(seed)
    spectrum = np.where((f >= 1.0) & (f <= 15.0), np.exp(2j * np.pi * rng.uniform(size=f.size)), 0.0)
    acc = np.fft.irfft(spectrum, n)
    h = np.zeros(f.size, complex)
    h[1:] = FloorModel(layout, sc.initial_positions(), sc.sensors[:1]).response(layout.pack(sc), f[1:]).H[0, 2]
    table = np.fft.irfft(h * np.where(f > 0, spectrum / np.where(f > 0, -(2 * np.pi * f) ** 2, 1.0), 0.0), n)
    noisy = [v + 0.01 * np.std(v) * rng.standard_normal(n) for v in (table, acc)]
    np.savetxt(path, np.column_stack([np.arange(n) / rate, *noisy]), delimiter=",", header="t,t-z,f-z", comments="")


@pytest.fixture
def heave(tmp_path):
    data = _symmetric_table()
    (tmp_path / "table.toml").write_bytes(tomli_w.dumps(data).encode())
    _heave_record(tmp_path / "heave.csv", data)
    path = tmp_path / "calibration.toml"
    path.write_text('scenario = "table.toml"\nfit = ["table.mass", "isolators[*].stiffness.z", '
                    '"isolators[*].damping.z"]\n[[experiments]]\nname = "heave"\nfile = "heave.csv"\nkind = "floor"\n'
                    'frequency = [1.0, 15.0]\n')
    return path


def test_heave_only_records_cannot_tell_mass_stiffness_and_damping_apart(heave, tmp_path, capsys):
    with pytest.raises(UnidentifiableError) as info:
        calibrate(heave)
    assert info.value.groups == [["table.mass", "isolators[*].stiffness.z", "isolators[*].damping.z"]]
    out = tmp_path / "fitted.toml"
    assert main(["calibrate", str(heave), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert err.startswith("isolator: error:")
    for name in ("table.mass", "isolators[*].stiffness.z", "isolators[*].damping.z"):
        assert name in err
    assert not out.exists()
    assert main(["calibrate", str(heave), "--out", str(out), "--json", "--allow-unidentifiable"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["identifiable"] is False
    assert data["unidentifiable"] == [["table.mass", "isolators[*].stiffness.z", "isolators[*].damping.z"]]
    for name in ("table.mass", "isolators[*].stiffness.z", "isolators[*].damping.z"):  # no interval: the bounds
        entry = data["parameters"][name]
        assert entry["std"] is None
        assert entry["ci95"] == pytest.approx([entry["initial"] / 10, entry["initial"] * 10])
    assert out.exists()


def test_a_refusal_leaves_no_folder_behind(heave, tmp_path, capsys):
    out, report, plot = tmp_path / "a" / "b" / "f.toml", tmp_path / "rep", tmp_path / "c" / "p.png"
    assert main(["calibrate", str(heave), "--out", str(out), "--report", str(report), "--plot", str(plot)]) == 2
    assert "cannot tell apart" in capsys.readouterr().err
    for folder in (tmp_path / "a", report, tmp_path / "c"):
        assert not folder.exists()


def test_heave_records_fit_stiffness_and_damping_with_the_mass_known(heave):
    text = heave.read_text().replace('"table.mass", ', "")
    heave.write_text(text)
    result = calibrate(heave)
    assert result.identifiable
    assert abs(result.parameters["isolators[*].stiffness.z"].value / 5e5 - 1) < 0.01
    assert abs(result.parameters["isolators[*].damping.z"].value / 4e3 - 1) < 0.03


_GOOD = 'scenario = "table.toml"\nfit = ["isolators[*].stiffness.z"]\n' \
        '[[experiments]]\nname = "heave"\nfile = "heave.csv"\nkind = "floor"\nfrequency = [1.0, 15.0]\n'


@pytest.mark.parametrize(("edit", "message"), [
    (lambda t: t.replace("fit =", "fitt ="), "fitt: unknown key; did you mean 'fit'?"),
    (lambda t: t.replace("stiffness.z", "stifness.z"), "fit[0]: not a parameter of this scenario"),
    (lambda t: t.replace('fit = ["isolators[*].stiffness.z"]', 'fit = []'), "fit: must be a non-empty list"),
    (lambda t: t.replace('fit = ["isolators[*].stiffness.z"]',
                         'fit = ["isolators[*].stiffness.z"]\nbounds = { "isolators[*].stiffness.z" = [1e6, 2e6] }'),
     "must contain the scenario's value"),
    (lambda t: t.replace('kind = "floor"', 'kind = "shaker"'), "experiments[0].kind: must be"),
    (lambda t: t.replace('frequency = [1.0, 15.0]', 'frequency = [15.0, 1.0]'), "experiments[0].frequency: low"),
    (lambda t: t.replace('file = "heave.csv"', 'file = "missing.csv"'), "missing.csv: no such file"),
    (lambda t: t.replace('scenario = "table.toml"', 'scenario = "nowhere.toml"'), "nowhere.toml: no such scenario"),
    (lambda t: t.replace('kind = "floor"\nfrequency = [1.0, 15.0]', 'kind = "move"'),
     "kind = \"move\" needs carriages that move"),
    (lambda t: t + '[[sensors]]\nname = "t-z"\non = "table"\nposition = [0, 0, 0]\ndirection = [0, 0, 1]\n'
                   'quantity = "velocity"\n', "sensors[0].name: 't-z' is used twice"),
    (lambda t: t.replace('name = "heave"', 'name = "heave"\npositions = { "x-stage" = 0.1 }'),
     "no such carriage"),
])
def test_bad_calibration_files_are_one_line(tmp_path, edit, message, capsys):
    data = _symmetric_table()
    (tmp_path / "table.toml").write_bytes(tomli_w.dumps(data).encode())
    _heave_record(tmp_path / "heave.csv", data, duration=20.0)
    (tmp_path / "calibration.toml").write_text(edit(_GOOD))
    out = tmp_path / "fitted.toml"
    assert main(["calibrate", str(tmp_path / "calibration.toml"), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert err.startswith("isolator: error:"), err
    assert message in err, err
    assert not out.exists()


@pytest.mark.parametrize(("record", "message"), [
    ("t,t-z,f-z\n0,1,2\n0.01,nan,2\n0.02,1,2\n", "line 3, column 't-z'"),
    ("t,t-z,f-z,extra\n0,1,2,3\n0.01,1,2,3\n", "column 'extra'"),
    ("t-z,f-z\n1,2\n1,2\n", "'t'"),
    ("t,t-z,f-z\n0,1,2\n", "at least two samples"),
    ("t,t-z,f-z\n0,1,2\n0.01,1,2\n0.03,1,2\n", "line"),
    ("t,t-z\n0,1\n0.01,1\n0.02,1\n", "holds no floor sensor"),
])
def test_bad_records_are_one_line(tmp_path, record, message, capsys):
    (tmp_path / "table.toml").write_bytes(tomli_w.dumps(_symmetric_table()).encode())
    (tmp_path / "heave.csv").write_text(record)
    (tmp_path / "calibration.toml").write_text(_GOOD)
    out = tmp_path / "fitted.toml"
    assert main(["calibrate", str(tmp_path / "calibration.toml"), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert message in err, err
    assert not out.exists()


def test_bad_arguments_of_the_api_and_the_command(tmp_path, capsys):
    with pytest.raises(Exception, match="calibration: must be"):
        calibrate(42)  # type: ignore[arg-type]
    assert main(["calibrate", str(tmp_path / "none.toml"), "--out", str(tmp_path / "f.csv")]) == 2
    assert "--out" in capsys.readouterr().err
    assert main(["calibrate", str(tmp_path / "none.toml"), "--out", str(tmp_path / "f.toml")]) == 2
    assert "no such calibration file" in capsys.readouterr().err


@pytest.mark.parametrize(("share", "warned"), [(0.3, True), (1e-6, False)])
def test_a_noisy_floor_sensor_is_warned_about(heave, share, warned):
    """Noise on the floor sensor (declared by its ``noise`` key) biases every H1 low; the fit says so when the
    bias exceeds half the estimate's random error."""
    import tomllib
    import warnings

    folder = heave.parent
    floor = np.loadtxt(folder / "heave.csv", delimiter=",", skiprows=1)[:, 2]
    data = tomllib.loads((folder / "table.toml").read_text())
    data["sensors"][1]["noise"] = share * float(np.std(floor))
    (folder / "table.toml").write_bytes(tomli_w.dumps(data).encode())
    heave.write_text(heave.read_text().replace('"table.mass", ', ""))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        calibrate(heave)
    said = [str(w.message) for w in caught if "floor sensor 'f-z'" in str(w.message)]
    assert bool(said) == warned, said
    if warned:
        assert "biases the H1 low" in said[0]
