"""Modal files read: the CSV and the universal file (written here with pyuff) of the same modes give the same
data, units and modal masses converted, and each bad input of the contract's list is one ScenarioError naming
the file and the row, node or dataset."""

from __future__ import annotations

import importlib
import re

import numpy as np
import pytest

from isolator.errors import ScenarioError
from isolator.scenario.flexible import load_modal_data
from isolator.scenario.flexible.synthetic import synthetic_top
from isolator.scenario.flexible.writing import write_modal_csv, write_modal_uff

pyuff = pytest.importorskip("pyuff")

SIZE = (2.0, 1.0, 0.2)
MASS = 1000.0
FREQUENCIES = (120.0, 180.0, 250.0, 330.0)


def _csv(tmp_path, **options):
    top = synthetic_top(SIZE, MASS, frequencies=FREQUENCIES, **options)
    return write_modal_csv(tmp_path / "top.csv", top.frequencies, top.nodes, top.translations), top


def test_the_csv_is_read_with_the_rigid_modes_left_out(tmp_path):
    path, top = _csv(tmp_path)
    data = load_modal_data(path, thickness=0.2, origin=(0.0, 0.0, 0.1))
    np.testing.assert_array_equal(data.frequencies, FREQUENCIES)
    np.testing.assert_array_equal(data.damping, 0.01)
    np.testing.assert_allclose(data.nodes, top.nodes + np.array([0.0, 0.0, 0.1]))
    np.testing.assert_allclose(data.translations, top.translations[6:], rtol=1e-15)
    assert data.rotations is None
    assert data.rigid is not None
    assert data.labels[3] == "node 4 (line 5)"
    assert data.face_for(0.15) == "top"
    assert data.face_for(0.05) == "bottom"


def test_count_max_frequency_and_damping_choose_the_modes(tmp_path):
    top = synthetic_top(SIZE, MASS, frequencies=FREQUENCIES)
    damping = [np.nan] * 6 + [0.02, np.nan, 0.05, np.nan]
    path = write_modal_csv(tmp_path / "top.csv", top.frequencies, top.nodes, top.translations, damping=damping)
    data = load_modal_data(path, thickness=0.2, count=3, damping=0.03)
    np.testing.assert_array_equal(data.frequencies, FREQUENCIES[:3])
    np.testing.assert_array_equal(data.damping, [0.02, 0.03, 0.05])
    data = load_modal_data(path, thickness=0.2, count=3, max_frequency=200.0)
    np.testing.assert_array_equal(data.frequencies, FREQUENCIES[:2])
    assert load_modal_data(path, thickness=0.2, max_frequency=330.0).n_modes == 4


def _same(a, b, rtol=2e-5):  # dataset 55 holds 6 significant digits
    np.testing.assert_allclose(a.frequencies, b.frequencies, rtol=rtol)
    np.testing.assert_allclose(a.nodes, b.nodes, rtol=rtol, atol=1e-12)
    np.testing.assert_allclose(a.translations, b.translations, rtol=rtol, atol=1e-12)
    assert a.rigid.mass == pytest.approx(b.rigid.mass, rel=1e-5)


@pytest.mark.parametrize(("length", "force"), [(1.0, 1.0), (1000.0, 1.0), (1000.0, 1000.0), (3.28084, 0.224809)])
def test_a_universal_file_in_any_units_gives_the_csv_data(tmp_path, length, force):
    """mm-N-t, mm-mN-kg and feet-pounds files of the same modes: converted by dataset 164 to SI."""
    top = synthetic_top(SIZE, MASS, frequencies=FREQUENCIES)
    csv = load_modal_data(write_modal_csv(tmp_path / "top.csv", top.frequencies, top.nodes, top.translations,
                                          top.rotations), thickness=0.2)
    uff = load_modal_data(write_modal_uff(tmp_path / "top.unv", top.frequencies, top.nodes, top.translations,
                                          top.rotations, damping=[0.0] * 6 + [0.02] * 4, length=length,
                                          force=force), thickness=0.2)
    _same(csv, uff)
    np.testing.assert_allclose(uff.rotations, csv.rotations, rtol=2e-5, atol=1e-12)
    np.testing.assert_array_equal(uff.damping, 0.02)
    assert uff.labels[0] == "node 1"


def test_a_modal_mass_other_than_1_scales_the_shape(tmp_path):
    top = synthetic_top(SIZE, MASS, frequencies=FREQUENCIES)
    masses = np.linspace(0.5, 40.0, top.frequencies.size)
    plain = load_modal_data(write_modal_uff(tmp_path / "a.uff", top.frequencies, top.nodes, top.translations),
                            thickness=0.2)
    scaled = load_modal_data(write_modal_uff(tmp_path / "b.uff", top.frequencies, top.nodes, top.translations,
                                             modal_mass=masses), thickness=0.2)
    _same(plain, scaled)
    raw = pyuff.UFF(str(tmp_path / "b.uff")).read_sets()
    shapes = [d for d in raw if d["type"] == 55]
    assert shapes[7]["modal_m"] == pytest.approx(masses[7])
    assert shapes[7]["r3"][0] == pytest.approx(top.translations[7, 0, 2] * np.sqrt(masses[7]), rel=1e-5)


def test_csv_faces_and_uff_mid_surface_with_rotations_give_the_same_face_translations(tmp_path):
    """The same plate modes: a solid's two faces in CSV, a shell's mid-surface with rotations in UFF (faces at
    +-t/2 by u + theta x (0, 0, +-t/2)); the faces' interpolants agree everywhere on the top."""
    faces = synthetic_top(SIZE, MASS, frequencies=FREQUENCIES, layer="faces")
    mid = synthetic_top(SIZE, MASS, frequencies=FREQUENCIES, layer="mid")
    csv = load_modal_data(write_modal_csv(tmp_path / "top.csv", faces.frequencies, faces.nodes,
                                          faces.translations), thickness=SIZE[2])
    uff = load_modal_data(write_modal_uff(tmp_path / "top.unv", mid.frequencies, mid.nodes, mid.translations,
                                          mid.rotations), thickness=SIZE[2])
    xy = np.random.default_rng(1).uniform((-1.0, -0.5), (1.0, 0.5), (200, 2))
    for face in ("top", "bottom"):
        a, b = csv.translation(xy, face, "p"), uff.translation(xy, face, "p")
        np.testing.assert_allclose(a, b, atol=2e-5 * np.abs(a).max())  # dataset 55: 6 significant digits
    assert csv.rigid.mass == pytest.approx(uff.rigid.mass, rel=1e-5)


HEADER = "mode,frequency_hz,damping,x,y,z,ux,uy,uz\n"
NODES = ["0,0,0.1", "1,0,0.1", "0,1,0.1", "1,1,0.1", "0,0,-0.1", "1,0,-0.1", "0,1,-0.1", "1,1,-0.1"]


def _rows(modes=((1, 100.0), (2, 150.0)), nodes=NODES, damping=""):
    return "".join(f"{m},{f},{damping},{p},0.001,0.002,0.003\n" for m, f in modes for p in nodes)


CSV_CASES = {
    "nodes differ": (HEADER + "1,1.5,-0.1,0.001".join(_rows().rsplit("1,1,-0.1,0.001", 1)),
                     r"line 17: node 8 of mode 2 lies at \(1, 1.5, -0.1\) m, on line 9 \(mode 1\) at \(1, 1, -0.1\)"),
    "fewer rows": (HEADER + "".join(_rows().splitlines(True)[:-1]), r"line 10: mode 2 has 7 rows, mode 1 has 8"),
    "mode again": (HEADER + _rows(((1, 100.0), (2, 150.0), (1, 200.0))), r"line 18: mode 1 again \(first on line 2\)"),
    "not increasing": (HEADER + _rows(((1, 150.0), (2, 100.0))),
                       r"mode 2 \(line 10\) has the frequency 100 Hz, below 150 Hz of mode 1 \(line 2\)"),
    "not finite": (HEADER + _rows(((1, 100.0), (2, "nan"))), r"line 10, column 'frequency_hz': nan is not a finite"),
    "frequency per mode": (HEADER + _rows().replace("2,150.0", "2,151.0", 1),
                           r"line 11: mode 2 has frequency_hz 150, on line 10 151 \(one frequency per mode\)"),
    "part of the rotations": (HEADER.replace("uz", "uz,rx") + _rows().replace("\n", ",0\n"),
                              r"gives the rotations rx but not all of rx, ry, rz"),
    "damping": (HEADER + _rows(damping="1.5"), r"mode 1 \(line 2\) has the damping ratio 1.5"),
    "whole mode": (HEADER + _rows(((1.5, 100.0),)), r"line 2: mode 1.5 is not a whole number"),
    "single layer": (HEADER + _rows(nodes=NODES[:4]), r"single layer .* gives no rotations"),
    "face of 2 nodes": (HEADER + _rows(nodes=[*NODES[:3], "0,0,-0.1", "1,0,-0.1"]),
                        r"the bottom face \(nodes within 1 mm of the lowest z = -0.1 m\) has 2 nodes "
                        r"\(node 4 \(line 5\), node 5 \(line 6\)\)"),
    "face on a line": (HEADER + _rows(nodes=[*NODES[:4], "0,0,-0.1", "1,0,-0.1", "2,0,-0.1"]),
                       r"the bottom face's 3 nodes \(node 5 \(line 6\) ...\) lie on one line"),
    "same place": (HEADER + _rows(nodes=[*NODES, "1,1,-0.1"]),
                   r"node 8 \(line 9\) and node 9 \(line 10\) of the bottom face lie at the same \(x, y\)"),
}


@pytest.mark.parametrize("case", CSV_CASES)
def test_each_bad_csv_is_one_error_naming_the_file_and_the_row(tmp_path, case):
    text, pattern = CSV_CASES[case]
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(ScenarioError) as info:
        load_modal_data(path, thickness=0.2)
    message = str(info.value)
    assert message.startswith(f"table.flexible.modes: '{path}'")
    assert "\n" not in message
    assert re.search(pattern, message), message


def test_count_beyond_the_file_and_no_mode_left_are_refused(tmp_path):
    path = tmp_path / "top.csv"
    path.write_text(HEADER + _rows())
    with pytest.raises(ScenarioError, match=r"^table.flexible.count: 3 elastic modes asked, but .*top.csv' has 2 "
                                            r"\(from 100 to 150 Hz\)"):
        load_modal_data(path, count=3)
    with pytest.raises(ScenarioError, match=r"^table.flexible.max_frequency: 50 Hz leaves no elastic mode of .*"
                                            r"top.csv' \(its lowest is 100 Hz\)"):
        load_modal_data(path, max_frequency=50.0)
    path.write_text(HEADER + _rows(((1, 0.0), (2, 0.0))))
    with pytest.raises(ScenarioError, match=r"2 modes below 1 Hz"):
        load_modal_data(path)


def test_a_file_of_only_rigid_modes_has_no_elastic_mode(tmp_path):
    top = synthetic_top(SIZE, MASS, frequencies=())
    path = write_modal_csv(tmp_path / "top.csv", top.frequencies, top.nodes, top.translations)
    with pytest.raises(ScenarioError, match=r"top.csv': has no elastic mode \(every mode is below 1 Hz\)"):
        load_modal_data(path, thickness=0.2)


def test_another_suffix_is_refused(tmp_path):
    path = tmp_path / "top.txt"
    path.write_text(HEADER)
    with pytest.raises(ScenarioError, match=r"top.txt': must be a .csv or a universal file \(.unv, .uff\)"):
        load_modal_data(path)


def _uff(tmp_path, sets):
    path = tmp_path / "bad.unv"
    pyuff.UFF(str(path)).write_sets(sets, mode="overwrite")
    return path


def _nodes(labels=(1, 2, 3, 4), z=(0.1, 0.1, 0.1, 0.1)):
    n = len(labels)
    xy = np.array([(0, 0), (1, 0), (0, 1), (1, 1), (0.5, 0.5)][:n], dtype=float)
    return pyuff.prepare_2411(node_nums=np.array(labels), def_cs=np.zeros(n, int), disp_cs=np.zeros(n, int),
                              color=np.ones(n, int), x=xy[:, 0], y=xy[:, 1], z=np.array(z, dtype=float))


def _mode(mode, freq, labels=(1, 2, 3, 4), analysis=2, values=6):
    shape = {f"r{k}": np.full(len(labels), 0.001 * k) for k in range(1, values + 1)}
    return pyuff.prepare_55(model_type=1, analysis_type=analysis, data_ch=3 if values == 6 else 2, spec_data_type=8,
                            data_type=2, n_data_per_node=values, node_nums=np.array(labels), load_case=1,
                            mode_n=mode, freq=freq, modal_m=0.0, modal_damp_vis=0.0, modal_damp_his=0.0, **shape)


UFF_CASES = {
    "no nodes": ([_mode(1, 100.0)], r"has no nodes \(a dataset 2411 or 15 giving their coordinates\)"),
    "no modes": ([_nodes()], r"has no modes"),
    "nodes differ": ([_nodes((1, 2, 3, 4, 5), (0.1,) * 5), _mode(1, 100.0), _mode(2, 150.0, (1, 2, 3, 5))],
                     r"dataset 3 \(mode 2\): its nodes differ from those of dataset 2 \(node 4 missing\)"),
    "unknown node": ([_nodes(), _mode(1, 100.0, (1, 2, 3, 7))],
                     r"dataset 2: node 7 is not among the file's nodes"),
    "not increasing": ([_nodes(), _mode(1, 150.0), _mode(2, 100.0)],
                       r"dataset 3 \(mode 2\) has the frequency 100 Hz, below 150 Hz of dataset 2 \(mode 1\)"),
    "not finite": ([_nodes(), _mode(1, 100.0), _mode(2, float("nan"))],
                   r"dataset 3 \(mode 2\) has the frequency nan \(must be finite\)"),
    "not normal modes": ([_nodes(), {**_mode(1, 100.0, analysis=5), "freq_step_n": 1}],
                         r"dataset 2 \(mode .*\) has analysis type 5, not normal modes"),
    "single layer without rotations": ([_nodes(), _mode(1, 100.0, values=3)], r"gives no rotations"),
    "face of 2 nodes": ([_nodes((1, 2, 3, 4, 5), (0.1, 0.1, 0.1, -0.1, -0.1)), _mode(1, 100.0, (1, 2, 3, 4, 5))],
                        r"the bottom face .* has 2 nodes \(node 4, node 5\)"),
    "units": ([pyuff.prepare_164(units_code=9, units_description="x", temp_mode=1, length=-1.0, force=1.0,
                                 temp=1.0, temp_offset=0.0), _nodes(), _mode(1, 100.0)],
              r"dataset 1 \(units\) gives the length factor -1"),
}


@pytest.mark.parametrize("case", UFF_CASES)
def test_each_bad_universal_file_is_one_error_naming_the_file_and_the_dataset(tmp_path, case):
    sets, pattern = UFF_CASES[case]
    path = _uff(tmp_path, sets)
    with pytest.raises(ScenarioError) as info:
        load_modal_data(path, thickness=0.2)
    message = str(info.value)
    assert message.startswith(f"table.flexible.modes: '{path}'")
    assert "\n" not in message
    assert re.search(pattern, message), message


def test_a_broken_or_empty_universal_file_is_one_error(tmp_path):
    path = tmp_path / "bad.uff"
    path.write_text("    -1\n  2411\n   1 nonsense\n    -1\n")
    with pytest.raises(ScenarioError, match=r"bad.uff': (dataset 1 \(type 2411\) cannot be read|has no nodes)"):
        load_modal_data(path)
    path.write_text("")
    with pytest.raises(ScenarioError, match=r"bad.uff': is empty"):
        load_modal_data(path)
    with pytest.raises(ScenarioError, match=r"cannot read '.*missing.unv' \(no such file\)"):
        load_modal_data(tmp_path / "missing.unv")


def test_without_pyuff_the_error_names_the_extra(tmp_path, monkeypatch):
    path = _uff(tmp_path, [_nodes(), _mode(1, 100.0)])
    real = importlib.import_module

    def without(name, *args):
        if name == "pyuff":
            raise ImportError(name)
        return real(name, *args)

    monkeypatch.setattr(importlib, "import_module", without)
    with pytest.raises(ScenarioError, match=r"bad.unv': reading a universal file needs pyuff: pip install "
                                            r"'isolator\[uff\]'"):
        load_modal_data(path)


def test_nodes_from_a_dataset_15_and_a_negative_modal_mass(tmp_path):
    top = synthetic_top(SIZE, MASS, frequencies=FREQUENCIES, layer="mid", rigid=False)
    labels = np.arange(1, len(top.nodes) + 1)
    nodes = pyuff.prepare_15(node_nums=labels, def_cs=np.zeros(len(labels), int), disp_cs=np.zeros(len(labels), int),
                             color=np.ones(len(labels), int), x=top.nodes[:, 0], y=top.nodes[:, 1], z=top.nodes[:, 2])
    modes = []
    for m, f in enumerate(FREQUENCIES):
        values = {f"r{k + 1}": top.translations[m, :, k] for k in range(3)}
        values.update({f"r{k + 4}": top.rotations[m, :, k] for k in range(3)})
        modes.append(pyuff.prepare_55(model_type=1, analysis_type=2, data_ch=3, spec_data_type=8, data_type=2,
                                      n_data_per_node=6, node_nums=labels, load_case=1, mode_n=m + 1, freq=f,
                                      modal_m=1.0, modal_damp_vis=0.0, modal_damp_his=0.0, **values))
    data = load_modal_data(_uff(tmp_path, [nodes, *modes]), thickness=0.2)
    np.testing.assert_allclose(data.nodes, top.nodes, atol=1e-12)
    np.testing.assert_allclose(data.translations, top.translations, rtol=2e-5, atol=1e-12)
    modes[2]["modal_m"] = -2.0
    with pytest.raises(ScenarioError, match=r"dataset 4 \(mode 3\) has the modal mass -2 \(must be > 0"):
        load_modal_data(_uff(tmp_path, [nodes, *modes]), thickness=0.2)
