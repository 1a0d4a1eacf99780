"""Measured records (isolator.calibration.records): CSV and UFF read back, every bad file one error line."""

from __future__ import annotations

import re
import struct
from pathlib import Path

import numpy as np
import pytest

from isolator.calibration.records import Record, read_record
from isolator.errors import ParameterError, ScenarioError

pyuff = pytest.importorskip("pyuff")

SENSORS = ("a-z", "b-x", "floor-z")


def _write(tmp_path: Path, text: str, name: str = "rec.csv") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def _table(n: int = 5, rate: float = 100.0) -> str:
    lines = ["t,a-z,floor-z"]
    lines += [f"{i / rate!r},{0.1 * i},{-0.5 * i}" for i in range(n)]
    return "\n".join(lines) + "\n"


def _refused(path: Path, *parts: str, sensors: tuple[str, ...] = SENSORS, uff: dict | None = None) -> str:
    """The one-line message read_record refuses ``path`` with; it starts with the path and holds ``parts``."""
    with pytest.raises(ScenarioError) as info:
        read_record(path, sensors, uff)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: "), message
    for part in parts:
        assert part in message, (part, message)
    return message


# --- CSV ---------------------------------------------------------------------------------------


def test_csv_round_trip(tmp_path):
    rate = 500.0
    t = np.arange(2000) / rate
    a = np.sin(2 * np.pi * 3.0 * t)
    f = 1e-6 * np.cos(2 * np.pi * 7.0 * t)
    path = tmp_path / "floor.csv"
    # time not first, a blank line inside, a byte-order mark: all accepted
    rows = [f"{float(x)!r},{float(y)!r},{float(z)!r}" for x, y, z in zip(a, t, f, strict=True)]
    path.write_text("\ufeffa-z,t,floor-z\n" + "\n".join(rows[:10]) + "\n\n" + "\n".join(rows[10:]) + "\n",
                    encoding="utf-8")
    record = read_record(path, SENSORS)
    assert isinstance(record, Record)
    assert record.path == path
    assert list(record.channels) == ["a-z", "floor-z"]  # file order, t apart; b-x absent
    np.testing.assert_array_equal(record.t, t)
    np.testing.assert_array_equal(record.channels["a-z"], a)
    np.testing.assert_array_equal(record.channels["floor-z"], f)
    assert record.rate == pytest.approx(rate, rel=1e-12)
    assert not record.t.flags.writeable
    assert not record.channels["a-z"].flags.writeable
    with pytest.raises(TypeError):
        record.channels["x"] = t  # type: ignore[index]


def test_csv_plain_and_quoted_files_agree(tmp_path):
    """The fast path (plain lines) and the row-by-row path (quotes) read the same numbers."""
    plain = read_record(_write(tmp_path, _table(), "plain.csv"), SENSORS)
    quoted = read_record(_write(tmp_path, _table().replace("t,a-z", '"t","a-z"'), "quoted.csv"), SENSORS)
    np.testing.assert_array_equal(plain.t, quoted.t)
    np.testing.assert_array_equal(plain.channels["a-z"], quoted.channels["a-z"])


def test_csv_missing_t(tmp_path):
    _refused(_write(tmp_path, "time,a-z\n0,1\n0.1,2\n"), "line 1", "no column 't'", "expected a CSV record")


def test_csv_unknown_column_suggests_the_closest_sensor(tmp_path):
    message = _refused(_write(tmp_path, "t,a_z\n0,1\n0.1,2\n"), "line 1", "column 'a_z' names no sensor",
                       "a-z, b-x, floor-z", "did you mean 'a-z'?")
    no_hint = _refused(_write(tmp_path, "t,qqqq\n0,1\n0.1,2\n", "b.csv"), "column 'qqqq' names no sensor")
    assert "did you mean" not in no_hint
    assert message.count(":") >= 2


def test_csv_duplicate_column(tmp_path):
    _refused(_write(tmp_path, "t,a-z,a-z\n0,1,1\n0.1,2,2\n"), "line 1", "column 'a-z' appears 2 times")
    _refused(_write(tmp_path, "t,a-z,t\n0,1,0\n0.1,2,0.1\n", "b.csv"), "column 't' appears 2 times")


def test_csv_unnamed_column(tmp_path):
    _refused(_write(tmp_path, "t,,a-z\n0,1,1\n0.1,2,2\n"), "line 1", "column 2 has no name")


def test_csv_only_time(tmp_path):
    _refused(_write(tmp_path, "t\n0\n0.1\n"), "line 1", "at least one sensor column")


def test_csv_value_not_a_number(tmp_path):
    text = _table().splitlines()
    text[5] = "0.04,abc,1"
    _refused(_write(tmp_path, "\n".join(text) + "\n"), "line 6, column 'a-z': 'abc' is not a number")
    text[5] = "0.04,,1"
    _refused(_write(tmp_path, "\n".join(text) + "\n", "b.csv"), "line 6, column 'a-z': '' is not a number")


@pytest.mark.parametrize("bad", ["nan", "inf", "-inf", "NaN"])
def test_csv_nan_or_inf(tmp_path, bad):
    text = _table(8).splitlines()
    text[7] = f"0.06,1,{bad}"
    _refused(_write(tmp_path, "\n".join(text) + "\n"), f"line 8, column 'floor-z': {bad}", "finite")


def test_csv_nan_in_a_quoted_file_names_its_line(tmp_path):
    """The row-by-row path reports the same problem with the right line (blank lines counted)."""
    text = '"t","a-z"\n0,1\n\n0.01,nan\n'
    _refused(_write(tmp_path, text), "line 4, column 'a-z': nan")


@pytest.mark.parametrize(("row", "count"), [("0.04,1", 2), ("0.04,1,2,3", 4)])
def test_csv_short_or_long_row(tmp_path, row, count):
    text = _table().splitlines()
    text[5] = row
    _refused(_write(tmp_path, "\n".join(text) + "\n"), f"line 6: {count} values for 3 columns", "t,a-z,floor-z")


@pytest.mark.parametrize(("text", "got"), [("t,a-z\n", "no data rows"), ("t,a-z\n0,1\n", "one data row")])
def test_csv_fewer_than_two_rows(tmp_path, text, got):
    _refused(_write(tmp_path, text), got, "at least two samples")


def test_csv_time_not_increasing(tmp_path):
    text = _table(8).splitlines()
    text[6] = "0.04," + text[6].split(",", 1)[1]  # line 7 repeats line 6's time
    _refused(_write(tmp_path, "\n".join(text) + "\n"), "line 7", "t = 0.04 is not after t = 0.04", "increase")
    text[6] = "0.01," + text[6].split(",", 1)[1]
    _refused(_write(tmp_path, "\n".join(text) + "\n", "b.csv"), "line 7", "is not after")


def test_csv_non_uniform_sampling(tmp_path):
    text = _table(8).splitlines()
    text[6] = "0.0501," + text[6].split(",", 1)[1]  # line 7: 0.0501 instead of 0.05
    _refused(_write(tmp_path, "\n".join(text) + "\n"), "line 7", "t = 0.0501 is 0.0101 s after the previous sample",
             "the mean spacing is", "uniformly sampled")


def test_csv_uniform_to_the_tolerance_passes(tmp_path):
    """Times printed to 12 significant digits are uniform to 1e-6 of the spacing."""
    t = np.arange(3000) / 3000.0
    rows = "\n".join(f"{x:.12g},{x:.3f}" for x in t)
    record = read_record(_write(tmp_path, "t,a-z\n" + rows + "\n"), SENSORS)
    assert record.rate == pytest.approx(3000.0, rel=1e-9)


def test_csv_missing_file_folder_empty_and_not_utf8(tmp_path):
    _refused(tmp_path / "nothing.csv", "no such file")
    (tmp_path / "folder.csv").mkdir()
    _refused(tmp_path / "folder.csv", "is a folder")
    _refused(_write(tmp_path, "", "empty.csv"), "is empty")
    _refused(_write(tmp_path, "\n  \n", "blank.csv"), "is empty")
    latin = tmp_path / "latin.csv"
    latin.write_bytes("t,a-z\n0,1\n0.1,2 \xb5m\n".encode("latin-1"))
    _refused(latin, "not UTF-8", "0xb5")


def test_path_given_as_text_is_named_as_given(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    _write(tmp_path, "t,a_z\n0,1\n0.1,2\n", "rel.csv")
    with pytest.raises(ScenarioError, match=r"^rel\.csv: line 1"):
        read_record("rel.csv", SENSORS)


def test_sensor_named_t_is_refused(tmp_path):
    with pytest.raises(ParameterError, match="'t' is the time column"):
        read_record(_write(tmp_path, _table()), ("t", "a-z"))


# --- UFF ---------------------------------------------------------------------------------------


def _dataset(node: int, direction: int, data: np.ndarray, *, func_type: int = 1, start: float = 0.0,
             step: float = 0.002, binary: int = 1) -> dict:
    return pyuff.prepare_58(
        binary=binary, func_type=func_type, rsp_node=node, rsp_dir=direction, ref_node=0, ref_dir=0,
        data=data, x=start + step * np.arange(len(data)), abscissa_spacing=1, abscissa_spec_data_type=17,
        ordinate_spec_data_type=12, orddenom_spec_data_type=0, id1=f"node {node} dir {direction}",
    )


def _uff(tmp_path: Path, datasets: list[dict], name: str = "rec.uff") -> Path:
    """Write ``datasets`` to a new file (pyuff's "overwrite" mode loses binary datasets: add to a new file)."""
    path = tmp_path / name
    path.unlink(missing_ok=True)
    pyuff.UFF(str(path)).write_sets(datasets, mode="add")
    return path


def test_uff_round_trip_with_signs_and_extra_channels(tmp_path):
    rng = np.random.default_rng(1)
    a, b, c, extra = (rng.standard_normal(1500) for _ in range(4))
    path = _uff(tmp_path, [
        _dataset(7, 1, extra),       # node 7 +X: no sensor, skipped
        _dataset(3, -3, b),          # node 3 -Z: sensor 'b-x' asks for -Z
        _dataset(3, 3, c),           # node 3 +Z: a different channel, the 'floor-z' one
        _dataset(1, 3, a),
        _dataset(9, 2, extra),       # skipped
    ], name="REC.UNV")
    uff = {"a-z": (1, "Z"), "b-x": (3, "-Z"), "floor-z": (3, "+Z")}
    record = read_record(path, SENSORS, uff)
    assert list(record.channels) == ["b-x", "floor-z", "a-z"]  # file order
    np.testing.assert_array_equal(record.channels["a-z"], a)
    np.testing.assert_array_equal(record.channels["b-x"], b)   # the -3 dataset, not the +3 one
    np.testing.assert_array_equal(record.channels["floor-z"], c)
    np.testing.assert_allclose(record.t, 0.002 * np.arange(1500), rtol=0, atol=1e-12)
    assert record.rate == pytest.approx(500.0)
    assert not record.channels["a-z"].flags.writeable


def test_uff_ascii_and_absent_sensor(tmp_path):
    data = np.linspace(-1.0, 1.0, 50)
    path = _uff(tmp_path, [_dataset(2, 2, data, binary=0, start=1.5, step=0.01)])
    record = read_record(path, SENSORS, {"a-z": (2, "+Y"), "b-x": (4, "X")})
    assert list(record.channels) == ["a-z"]  # b-x's channel is not in the file: absent, no error
    np.testing.assert_allclose(record.channels["a-z"], data, rtol=1e-11)
    np.testing.assert_allclose(record.t, 1.5 + 0.01 * np.arange(50))


def test_uff_no_matching_channel_lists_what_the_file_holds(tmp_path):
    path = _uff(tmp_path, [_dataset(1, 3, np.ones(10)), _dataset(2, -1, np.ones(10))])
    _refused(path, "no channel of a sensor", "'a-z' = node 5 +Z", "node 1 +Z, node 2 -X",
             uff={"a-z": (5, "+Z")})
    _refused(path, "no uff mapping given", "node 1 +Z")


def test_uff_time_axes_must_agree(tmp_path):
    x = np.zeros(20)
    for other, what in [(_dataset(2, 3, x, step=0.001), "spacing"), (_dataset(2, 3, x, start=0.1), "start"),
                        (_dataset(2, 3, np.zeros(21)), "samples")]:
        path = _uff(tmp_path, [_dataset(1, 3, x), other], name=f"{what}.uff")
        _refused(path, "channels node 1 +Z and node 2 +Z have different time axes", what,
                 uff={"a-z": (1, "Z"), "b-x": (2, "Z")})


def test_uff_other_function_type_of_a_sensor_channel(tmp_path):
    path = _uff(tmp_path, [_dataset(1, 3, np.zeros(8)), _dataset(2, 3, np.zeros(8), func_type=4)])
    _refused(path, "channel node 2 +Z (sensor 'b-x') has function type 4", "time response",
             uff={"a-z": (1, "Z"), "b-x": (2, "Z")})
    # the same dataset for no sensor is skipped
    assert list(read_record(path, SENSORS, {"a-z": (1, "Z")}).channels) == ["a-z"]


def test_uff_non_finite_value(tmp_path):
    """pyuff writes NaN as 0: the binary sample is patched in the file."""
    data = np.zeros(30)
    data[17] = 12345.678
    path = _uff(tmp_path, [_dataset(4, -2, data)])
    raw = path.read_bytes()
    assert raw.count(struct.pack("=d", 12345.678)) == 1
    path.write_bytes(raw.replace(struct.pack("=d", 12345.678), struct.pack("=d", np.nan)))
    _refused(path, "channel node 4 -Y, sample 17: nan", uff={"a-z": (4, "-Y")})


def test_uff_same_channel_twice(tmp_path):
    path = _uff(tmp_path, [_dataset(1, 3, np.zeros(8)), _dataset(1, 3, np.ones(8))])
    _refused(path, "channel node 1 +Z (sensor 'a-z') appears in two datasets 58", uff={"a-z": (1, "+Z")})


def test_uff_unparseable_empty_and_missing(tmp_path):
    broken = tmp_path / "broken.uff"
    broken.write_text("    -1\n    58\nthis is not a dataset\n    -1\n", encoding="utf-8")
    _refused(broken, "cannot be read as a universal file", uff={"a-z": (1, "Z")})
    _refused(_write(tmp_path, "", "empty.uff"), "is empty", uff={"a-z": (1, "Z")})
    _refused(tmp_path / "none.uff", "no such file", uff={"a-z": (1, "Z")})


def test_uff_without_pyuff(tmp_path, monkeypatch):
    import importlib

    path = _uff(tmp_path, [_dataset(1, 3, np.zeros(8))])
    real = importlib.import_module

    def no_pyuff(name: str, *args, **kwargs):
        if name == "pyuff":
            raise ImportError("No module named 'pyuff'")
        return real(name, *args, **kwargs)

    monkeypatch.setattr(importlib, "import_module", no_pyuff)
    _refused(path, "reading UFF needs pyuff: pip install 'isolator[uff]'", uff={"a-z": (1, "Z")})


@pytest.mark.parametrize(("uff", "reason"), [
    ({"nope": (1, "Z")}, "uff['nope']: names no sensor"),
    ({"a-z": (1, "W")}, "uff['a-z']: the direction must be one of"),
    ({"a-z": ("1", "Z")}, "uff['a-z']: the node must be an integer"),
    ({"a-z": (1,)}, "uff['a-z']: must be (node, direction)"),
    ({"a-z": (1, "Z"), "b-x": (1, "+Z")}, "uff['b-x']: node 1 +Z is also sensor 'a-z'"),
])
def test_uff_bad_mapping(tmp_path, uff, reason):
    path = _uff(tmp_path, [_dataset(1, 3, np.zeros(8))])
    with pytest.raises(ParameterError, match=re.escape(reason)):
        read_record(path, SENSORS, uff)


def test_uff_uneven_abscissa_accepted_when_uniform(tmp_path):
    """A dataset written with an uneven abscissa (x stored per sample) is read when its x is uniform."""
    data = np.arange(40.0)
    uneven = _dataset(1, 3, data, binary=0)
    uneven["abscissa_spacing"] = 0
    record = read_record(_uff(tmp_path, [uneven]), SENSORS, {"a-z": (1, "Z")})
    np.testing.assert_allclose(record.t, 0.002 * np.arange(40), atol=1e-12)
    np.testing.assert_allclose(record.channels["a-z"], data)
    skewed = _dataset(1, 3, data, binary=0)
    skewed["abscissa_spacing"] = 0
    skewed["x"] = 0.002 * np.arange(40.0)
    skewed["x"][25:] += 0.0005
    _refused(_uff(tmp_path, [skewed], name="skewed.uff"), "channel node 1 +Z, sample 25", "uniformly sampled",
             uff={"a-z": (1, "Z")})
