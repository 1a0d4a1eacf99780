"""Issue 42 (trust round 4), the FMUs' names, units and compiler: any legal file name makes a valid, unique
model identifier (item 6); every Real variable carries its SI unit and a profiles plant's q: outputs drive a
controller FMU's q: inputs (item 14); CC is honoured or refused by name (item 15)."""

from __future__ import annotations

import dataclasses
import shutil
import warnings
import zipfile

import casadi as ca
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from conftest import run_command
from fmu_master import Slave, master_loop, relative_error
from isolator import Simulator, load_scenario
from isolator.fmu import write_fmu
from isolator.fmu.package import IDENTIFIER_LENGTH, model_identifier, valid_identifier
from isolator.fmu.units import BASE_UNITS, PARAMETER_UNITS, state_units
from isolator.numerics import native
from isolator.scenario.bundled import bundled_scenarios
from isolator.scenario.rules import field_of
from isolator.simulation.discrete_controller import DiscreteController, ScheduleEntry

pytest.importorskip("fmpy")
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from controllers.feedback import design_controller, write_controller_fmu

pytestmark = pytest.mark.skipif(shutil.which("cc") is None and shutil.which("gcc") is None, reason="no C compiler")

C_KEYWORDS = {"auto", "break", "case", "char", "const", "continue", "default", "do", "double", "else", "enum",
              "extern", "float", "for", "goto", "if", "inline", "int", "long", "register", "restrict", "return",
              "short", "signed", "sizeof", "static", "struct", "switch", "typedef", "union", "unsigned", "void",
              "volatile", "while"}
#: a file name's stem: any text a file system takes (no slash, no NUL), up to 251 characters
STEMS = st.text(st.characters(blacklist_characters="/\x00", blacklist_categories=("Cs",)), min_size=1, max_size=251)


@given(STEMS)
def test_any_file_name_makes_a_valid_model_identifier(stem):
    """A C identifier (and a casadi function prefix) of at most IDENTIFIER_LENGTH characters, no keyword, the
    same every time; a name that already is one is kept."""
    identifier = model_identifier(stem)
    assert identifier.isascii()
    assert identifier[0].isalpha()
    assert "__" not in identifier
    assert all(c.isalnum() or c == "_" for c in identifier)
    assert not identifier.endswith("_")
    assert len(identifier) <= IDENTIFIER_LENGTH
    assert identifier not in C_KEYWORDS
    assert ca.Function.check_name(f"{identifier}_ode")
    assert valid_identifier(identifier)
    assert model_identifier(stem) == identifier
    assert (identifier == stem) == valid_identifier(stem)


@given(STEMS, STEMS)
def test_two_file_names_never_share_a_model_identifier(a, b):
    if a != b:
        assert model_identifier(a) != model_identifier(b)


@pytest.mark.parametrize("stem", ["_t", "my__table", "tabelle-größe", "a" * 251, "int"])
def test_the_fmu_command_takes_legal_file_names(tmp_path, capsys, stem):
    """``isolator fmu --out`` crashed in casadi (or on a file name too long) for these: now each FMU is
    written, valid, its binary named by its model identifier, and it runs."""
    out = tmp_path / f"{stem}.fmu"
    status, _text, err = run_command(["fmu", "paper-table-3-2", "--out", str(out)], capsys)
    assert status == 0, err
    assert validate_fmu(str(out)) == []
    md = read_model_description(str(out))
    identifier = md.coSimulation.modelIdentifier
    assert identifier == md.modelExchange.modelIdentifier == model_identifier(stem)
    with zipfile.ZipFile(out) as zf:
        assert f"binaries/linux64/{identifier}.so" in zf.namelist() or not shutil.which("cc")
    if stem == "tabelle-größe":
        slave = Slave(out, tmp_path)
        slave.fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.01)
        assert np.all(np.isfinite(slave.get(["x", "y", "z"])))
        slave.close()


def test_every_parameter_field_of_the_bundled_scenarios_has_a_unit():
    fields = set()
    for name in bundled_scenarios():
        fields |= {field_of(n) for n in Simulator(load_scenario(name)).layout.names}
    assert fields <= set(PARAMETER_UNITS), fields - set(PARAMETER_UNITS)
    assert set(PARAMETER_UNITS.values()) <= set(BASE_UNITS)
    units, rates = state_units(21, 2)  # a pneumatic table: 8 chamber pressures; two lagged actuators
    assert units[13:21] == ["Pa"] * 8
    assert units[21:] == ["N", "N"]
    assert rates[3:7] == ["1/s"] * 4


@pytest.fixture(scope="module")
def geophones(tmp_path_factory):
    """The geophones' table on its profiles as a plant FMU, with two parameters."""
    scenario = load_scenario("paper-table-3-2-geophones")
    path = write_fmu(scenario, tmp_path_factory.mktemp("plant") / "table.fmu",
                     parameters=["isolators[*].damping.z", "table.inertia.z"])
    return scenario, path


def scheduled(scenario) -> DiscreteController:
    """A skyhook (no weight search) scheduled over the x-stage's travel: half its gain at one end, one and a
    half at the other, so that the commands depend on q."""
    plain = design_controller(scenario, "skyhook", 2000.0, options={"gain": 2e4})
    ends = [-0.7, 0.7]
    entries = [ScheduleEntry((q, 0.0), plain.A, plain.B, scale * plain.C, scale * plain.D)
               for q, scale in zip(ends, (0.5, 1.5), strict=True)]
    return DiscreteController(plain.sample_rate, plain.sensors, plain.actuators, plain.carriages, "scheduled skyhook",
                              schedule=tuple(entries), schedule_carriage=0)


def test_every_real_variable_carries_its_si_unit(geophones, tmp_path):
    scenario, path = geophones
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path), validate=True, validate_model_structure=True)
    defined = {u.name for u in md.unitDefinitions}
    units = {v.name: v.unit for v in md.modelVariables}
    assert all(v.unit in defined for v in md.modelVariables), [v.name for v in md.modelVariables if not v.unit]
    expected = {"x": "m", "rz": "rad", "f:z1": "N", "floor:vz": "m/s", "q:x-stage": "m", "time": "s",
                "isolators[*].damping.z": "N.s/m", "table.inertia.z": "kg.m2", "state[3]": "1",
                "state[12]": "rad/s", "der(state[9])": "m/s2", f"state[{13 + 11}]": "N"}
    assert {k: units[k] for k in expected} == expected
    assert {units[f"s:{s.name}"] for s in scenario.sensors} == {"m/s"}
    newton = next(u for u in md.unitDefinitions if u.name == "N").baseUnit
    assert (newton.kg, newton.m, newton.s) == (1, 1, -2)
    controller = write_controller_fmu(scheduled(scenario), tmp_path / "controller.fmu", scenario=scenario)
    assert validate_fmu(str(controller)) == []
    units = {v.name: v.unit for v in read_model_description(str(controller)).modelVariables}
    assert units["u:z1"] == "N"
    assert units["q:x-stage"] == "m"
    assert units["time"] == "s"
    assert {units[f"y:{s.name}"] for s in scenario.sensors} == {"m/s"}


def test_plant_q_outputs_wired_to_a_scheduled_controllers_q_inputs_equal_simulate(geophones, tmp_path):
    """A profiles plant outputs its carriages' positions q:<carriage>; a master that wires them (and the
    geophones' readings) into a scheduled controller FMU, in the contract's order, gives the table's signals
    within 1e-6 of their peaks of ``simulate --controller``, and q: is the profiles' position."""
    scenario, path = geophones
    scenario = dataclasses.replace(scenario, simulation=dataclasses.replace(scenario.simulation, duration=9.0))
    ctrl = scheduled(scenario)
    plant = Slave(path, tmp_path, name="plant")
    controller = Slave(write_controller_fmu(ctrl, tmp_path / "controller.fmu", scenario=scenario), tmp_path,
                       name="controller")
    response = Simulator(scenario).run(controller=ctrl)
    h = 1.0 / ctrl.sample_rate
    steps = round(scenario.simulation.duration / h)
    signals, sensors = ["x", "y", "z", "rx", "ry", "rz"], [f"s:{s}" for s in ctrl.sensors]
    positions = [f"q:{c}" for c in ctrl.carriages]
    values = master_loop(plant, controller, ctrl, steps, h, signals + sensors + positions, positions)
    out, q = values[:, :6], values[:, 6 + len(sensors):]
    t = np.arange(steps + 1) * h
    for i, c in enumerate(scenario.carriages):
        np.testing.assert_allclose(q[:, i], c.profile.evaluate(t)[0], rtol=0, atol=1e-12)
    for i, name in enumerate(signals):
        got = np.interp(response.t, t, out[:, i])
        assert relative_error(got, response.signals[i]) < 1e-6, name
    unscheduled = Simulator(scenario).run(controller=design_controller(scenario, "skyhook", 2000.0,
                                                                       options={"gain": 2e4}))
    assert relative_error(response.signal("z"), unscheduled.signal("z")) > 1e-3  # the schedule matters


def test_a_cc_that_is_not_found_is_one_line_naming_it(tmp_path, capsys, monkeypatch):
    """``CC=/nonexistent/cc`` was ignored without a word (cc was used): now the FMU is refused naming CC."""
    monkeypatch.setenv("CC", "/nonexistent/cc")
    for argv in (["fmu", "paper-table-3-2", "--out", str(tmp_path / "t.fmu")],
                 ["controller", "paper-table-3-2-geophones", "--method", "skyhook", "--sample-rate", "2000",
                  "--out", str(tmp_path / "ctl"), "--fmu"]):
        status, _, err = run_command(argv, capsys)
        assert status == 2
        assert len(err) == 1
        assert "CC" in err[0], err
        assert "/nonexistent/cc" in err[0], err
        assert "not found" in err[0], err
    assert sorted(p.name for p in tmp_path.rglob("*") if p.is_file()) == []


def test_a_cc_that_does_not_compile_is_one_line_naming_it(tmp_path, capsys, monkeypatch):
    false = shutil.which("false")
    if false is None:
        pytest.skip("no false command")
    monkeypatch.setenv("CC", false)
    status, _, err = run_command(["fmu", "paper-table-3-2", "--out", str(tmp_path / "t.fmu")], capsys)
    assert status == 2
    assert len(err) == 1, err
    assert "CC" in err[0], err
    assert false in err[0], err
    assert "does not compile" in err[0], err
    assert not (tmp_path / "t.fmu").exists()


def test_a_cc_with_flags_of_its_own_is_honoured(tmp_path, capsys, monkeypatch):
    """CC is split as a shell splits it: a compiler with a flag builds the FMU (a wrapper script records it)."""
    compiler = shutil.which("gcc") or shutil.which("cc")
    record = tmp_path / "called"
    wrapper = tmp_path / "my cc"
    wrapper.write_text(f'#!/bin/sh\necho "$@" >> "{record}"\nexec "{compiler}" "$@"\n')
    wrapper.chmod(0o755)
    monkeypatch.setenv("CC", f"'{wrapper}' -O1")
    status, _, err = run_command(["fmu", "paper-table-3-2", "--out", str(tmp_path / "t.fmu")], capsys)
    assert status == 0, err
    assert validate_fmu(str(tmp_path / "t.fmu")) == []
    assert all(line.startswith("-O1 ") for line in record.read_text().splitlines())


def test_the_native_build_warns_of_a_cc_it_cannot_find(monkeypatch):
    monkeypatch.setenv("CC", "/nonexistent/cc-for-the-model")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        found = native.find_compiler("c")
    assert found != "/nonexistent/cc-for-the-model"
    assert any("CC" in str(w.message) and "/nonexistent/cc-for-the-model" in str(w.message) for w in caught)
