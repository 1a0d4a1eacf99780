"""The table as an FMU (``isolator fmu``): FMPy runs it (Co-Simulation at 1 ms, Model Exchange with CVode) and
every output equals ``isolator simulate``'s within 1e-6 of its peak; inputs, forces, parameters; the XML is
valid and the C compiles strictly; bad input is one line and writes nothing."""

from __future__ import annotations

import dataclasses
import shutil
import subprocess
import zipfile

import numpy as np
import pytest

from conftest import run_command
from fmu_master import relative_error, run
from isolator import Simulator, load_scenario
from isolator.fmu import write_fmu
from isolator.scenario.definitions import Point
from isolator.scenario.ground import Ground
from isolator.scenario.profile_shapes import samples
from isolator.scenario.profiles import SineProfile
from isolator.simulation.actuation import ForceHistory
from isolator.simulation.stepping import Method

fmpy = pytest.importorskip("fmpy")
from fmpy import extract, read_model_description, simulate_fmu  # noqa: E402
from fmpy.fmi2 import FMU2Model  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

pytestmark = pytest.mark.skipif(shutil.which("cc") is None and shutil.which("gcc") is None, reason="no C compiler")

STEP = 1e-3


def shortened(name: str, duration: float | None = None, **changes) -> object:
    """A bundled scenario, its run ``duration`` s (default its own; no shorter than the moves)."""
    scenario = load_scenario(name)
    simulation = scenario.simulation if duration is None else dataclasses.replace(scenario.simulation,
                                                                                  duration=duration)
    return dataclasses.replace(scenario, simulation=simulation, **changes)


def reference_columns(response) -> dict[str, np.ndarray]:
    """The FMU's outputs as ``isolator simulate`` gives them."""
    out = {n: response.signals[i] for i, n in enumerate(response.signal_names)}
    out |= {f"s:{n}": response.sensor_signals[i] for i, n in enumerate(response.sensor_names)}
    for i, n in enumerate(response.point_names):
        out |= {f"{n}:{a}": response.point_signals[i, k] for k, a in enumerate("xyz")}
    return out


def assert_close(t, values, names, response, limit=1e-6):
    reference = reference_columns(response)
    assert set(names) == set(reference)
    for j, name in enumerate(names):
        got = np.interp(response.t, t, values[:, j])
        assert relative_error(got, reference[name]) < limit, name


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    """Table 3.2 with a point, and its FMU."""
    scenario = shortened("paper-table-3-2", points=(Point("probe", (0.3, -0.2, 0.45)),))
    path = write_fmu(scenario, tmp_path_factory.mktemp("table") / "table.fmu")
    return scenario, path


def output_names(path) -> list[str]:
    """The table's outputs (the carriages' positions q:, outputs of a profiles FMU, are checked elsewhere)."""
    return [v.name for v in read_model_description(str(path)).modelVariables
            if v.causality == "output" and not v.name.startswith("q:")]


def test_the_fmu_validates_and_its_sources_compile_strictly(table, tmp_path):
    _, path = table
    assert validate_fmu(str(path)) == []
    with zipfile.ZipFile(path) as zf:
        zf.extractall(tmp_path)
        names = zf.namelist()
    assert any(n.startswith("binaries/") for n in names)
    sources = sorted((tmp_path / "sources").glob("*.c"))
    assert len(sources) == 2
    for source in sources:
        subprocess.run(["gcc" if shutil.which("gcc") else "cc", "-std=c99", "-Wall", "-Wextra", "-Werror",
                        "-pedantic", "-c", "-o", str(tmp_path / "probe.o"), str(source)], check=True,
                       capture_output=True, cwd=tmp_path / "sources")
    md = read_model_description(str(path))
    nominals = {v.name: float(v.nominal) for v in md.modelVariables if v.name.startswith("state[")}
    assert nominals["state[0]"] == 1e-6
    assert nominals["state[3]"] == 1.0


def test_table_3_2_co_simulation_and_model_exchange_equal_simulate(table, tmp_path):
    scenario, path = table
    response = Simulator(scenario).run()
    names = output_names(path)
    t, values = run(path, tmp_path, names, scenario.simulation.duration, STEP)
    assert_close(t, values, names, response)
    me = simulate_fmu(str(path), fmi_type="ModelExchange", relative_tolerance=1e-9, output_interval=STEP,
                      stop_time=scenario.simulation.duration, output=names)
    assert_close(me["time"], np.column_stack([me[n] for n in names]), names, response)


def test_carriages_as_inputs_fed_the_profiles_equal_simulate(tmp_path):
    scenario = shortened("paper-table-3-2")
    path = write_fmu(scenario, tmp_path / "inputs.fmu", carriages="inputs")
    assert validate_fmu(str(path)) == []
    profiles = [(c.name, c.profile) for c in scenario.carriages]

    def inputs(t):
        """q, v, a at t and their derivatives up to the jerk, on the piece the next step lies on (a host that
        knows the profiles and ends its steps on their breakpoints)."""
        values, rates = {}, {}
        for name, profile in profiles:
            q, v, a = (float(x[0]) for x in profile.evaluate(np.array([t]), np.array([t + 1e-9])))
            knots = np.asarray(profile.knots)
            piece = int(np.clip(np.searchsorted(knots, t + 1e-9, side="right") - 1, 0, len(knots) - 2))
            c = np.asarray(profile.coefficients[piece]) if knots[0] <= t + 1e-9 < knots[-1] else np.zeros(4)
            tau = t - knots[piece]
            jerk = sum(k * (k - 1) * (k - 2) * c[k] * tau ** (k - 3) for k in range(3, c.size))
            values |= {f"q:{name}": q, f"v:{name}": v, f"a:{name}": a}
            rates |= {f"q:{name}": [v, a, jerk], f"v:{name}": [a, jerk], f"a:{name}": [jerk]}
        return values, rates

    names = output_names(path)
    t, values = run(path, tmp_path, names, scenario.simulation.duration, STEP, inputs, extra=scenario.breakpoints)
    assert_close(t, values, names, Simulator(scenario).run())


def test_sensors_and_lagged_actuators_with_a_sine_force_equal_simulate_forces(tmp_path):
    """The geophones' table: twelve velocity sensors, twelve actuators with a 200 Hz lag; a sine on two of them,
    interpolated linearly between 1 ms samples as a forces file is (followed exactly through the input
    derivatives), one of them clipped at its 500 N. The reference is ``simulate --forces`` itself (its RK4 steps
    take the lags exactly, ``lag_stages``), and RK4 at 1/8 of its step a second one (a converged run: 2e-11 of
    the peak from 1/64). doStep's steps are the passive table's: the lags cost no step."""
    scenario = shortened("paper-table-3-2-geophones", 9.0)
    path = write_fmu(scenario, tmp_path / "geophones.fmu")
    passive = write_fmu(dataclasses.replace(scenario, actuators=(), sensors=()), tmp_path / "passive.fmu")
    steps = []
    for fmu in (path, passive):
        with zipfile.ZipFile(fmu) as zf:
            source = zf.read(f"sources/{fmu.stem}.c").decode()
        line = next(line for line in source.splitlines() if line.startswith("#define MAX_STEP "))
        steps.append(float(line.split()[2]))
    assert steps[0] == pytest.approx(steps[1], rel=1e-9)
    samples = np.arange(0.0, 9.0 + STEP / 2, STEP)
    names_f = [a.name for a in scenario.actuators]
    forces = np.zeros((len(names_f), samples.size))
    forces[names_f.index("z1")] = 300.0 * np.sin(2 * np.pi * 7.0 * samples)
    forces[names_f.index("x2")] = 700.0 * np.sin(2 * np.pi * 3.0 * samples + 0.3)  # clipped at 500 N
    history = ForceHistory(samples, forces, tuple(names_f))
    sim = Simulator(scenario)
    start, end = sim.equilibria(sim.parameters)
    method = sim.method_for(max(start.max_frequency, end.max_frequency), actuated=True)
    refined = sim.run_method(sim.parameters, start, end, Method(8 * method.substeps), forces=history)

    def inputs(t):
        k = round(t / STEP)
        nxt = min(k + 1, samples.size - 1)
        return ({f"f:{n}": forces[i, k] for i, n in enumerate(names_f)},
                {f"f:{n}": (forces[i, nxt] - forces[i, k]) / STEP for i, n in enumerate(names_f)})

    names = output_names(path)
    assert sum(n.startswith("s:") for n in names) == 12
    t, values = run(path, tmp_path, names, 9.0, STEP, inputs)
    assert_close(t, values, names, sim.run(forces=history))
    assert_close(t, values, names, refined)


def test_a_parameter_set_in_the_fmu_is_the_same_as_changes(tmp_path):
    scenario = shortened("paper-table-3-2", 9.0)
    path = write_fmu(scenario, tmp_path / "tunable.fmu", parameters=["isolators[*].stiffness.z", "table.mass"])
    md = read_model_description(str(path))
    start = {v.name: float(v.start) for v in md.modelVariables if v.causality == "parameter"}
    assert start == {"isolators[*].stiffness.z": 5.7e5, "table.mass": scenario.table.mass}
    changes = {"isolators[*].stiffness.z": 7.4e5, "table.mass": 1.15 * scenario.table.mass}
    names = output_names(path)
    t, values = run(path, tmp_path, names, 9.0, STEP, start_values=changes)
    response = Simulator(scenario).run(changes=changes)
    assert_close(t, values, names, response)
    assert np.max(np.abs(values[0])) < 1e-15  # it starts at rest: the equilibrium of the changed parameters
    plain = Simulator(scenario).run()
    assert relative_error(response.signal("z"), plain.signal("z")) > 1e-2  # the change matters


def test_a_pneumatic_table_equals_simulate(tmp_path):
    """Air springs with damping chambers and leveling valves, which open and close nine times in the run. The
    reference is ``isolator simulate`` (DOP853 steps ending where the valves switch,
    :mod:`isolator.simulation.valve_events`), and the simulator's RK4 at 1/32 of its step a second one."""
    scenario = shortened("paper-table-3-2-pneumatic", 10.0)
    path = write_fmu(scenario, tmp_path / "pneumatic.fmu")
    assert validate_fmu(str(path)) == []
    sim = Simulator(scenario)
    start, end = sim.equilibria(sim.parameters)
    method = sim.method_for(max(start.max_frequency, end.max_frequency))
    response = sim.run()
    names = output_names(path)
    t, values = run(path, tmp_path, names, 10.0, STEP)
    assert_close(t, values, names, response)
    assert_close(t, values, names, sim.run_method(sim.parameters, start, end, Method(32 * method.substeps)))
    me = simulate_fmu(str(path), fmi_type="ModelExchange", relative_tolerance=1e-9, output_interval=STEP,
                      stop_time=10.0, output=names)
    assert_close(me["time"], np.column_stack([me[n] for n in names]), names, response)


@pytest.mark.parametrize("argv", [
    ["--out", "{tmp}/plain.txt/table.fmu"],
    ["--out", "{tmp}/table.fmu", "--parameters", "isolators[*].stifness.z"],
    ["--out", "{tmp}/table.fmu", "--set", "isolators[*].stiffness.z=soft"],
    ["--out", "{tmp}/table.fmu", "--set", "isolators[*].stifness.z=1e6"],
    ["--out", "{tmp}/table.fmu", "--set", "isolators[*].stiffness.z=-1"],
    ["--out", "{tmp}/table.fmu", "--carriages", "both"],
])
def test_bad_input_is_one_line_and_writes_nothing(tmp_path, capsys, argv):
    (tmp_path / "plain.txt").write_text("a file, not a folder")
    before = sorted(tmp_path.rglob("*"))
    status, _, err = run_command(["fmu", "paper-table-3-2", *[a.format(tmp=tmp_path) for a in argv]], capsys)
    assert status == 2
    assert len(err) == 1
    assert any(key in err[0] for key in ("--out", "--parameters", "--set", "--carriages")), err
    assert sorted(tmp_path.rglob("*")) == before


def test_no_c_compiler_says_which_were_looked_for(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("CC", "no-such-cc")
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    status, _, err = run_command(["fmu", "paper-table-3-2", "--out", str(tmp_path / "t.fmu")], capsys)
    assert status == 2
    assert len(err) == 1
    assert "no C compiler" in err[0]
    assert "no-such-cc" in err[0]
    assert "gcc" in err[0]
    assert not (tmp_path / "t.fmu").exists()


def test_hostile_names_reach_the_xml_and_the_c_escaped(tmp_path):
    """Quotes, comment ends, trigraphs, markup and non-ASCII in names: the XML holds them exactly, the C
    compiles strictly, the outputs are there by those names."""
    names = ['probe "a" */ ??/', "<&'é>"]
    scenario = shortened("paper-table-3-2", points=tuple(Point(n, (0.3, 0.1 * k, 0.4)) for k, n in enumerate(names)))
    path = write_fmu(scenario, tmp_path / "hostile.fmu")
    assert validate_fmu(str(path)) == []
    outputs = output_names(path)
    assert [f"{n}:x" for n in names] == [o for o in outputs if o.endswith(":x")]
    with zipfile.ZipFile(path) as zf:
        zf.extractall(tmp_path)
    for source in sorted((tmp_path / "sources").glob("*.c")):
        subprocess.run(["gcc" if shutil.which("gcc") else "cc", "-std=c99", "-Wall", "-Wextra", "-Werror",
                        "-pedantic", "-trigraphs", "-c", "-o", str(tmp_path / "probe.o"), str(source)], check=True,
                       capture_output=True, cwd=tmp_path / "sources")


def test_a_relative_out_path(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    status, _text, err = run_command(["fmu", "paper-table-3-2", "--out", "sub/table.fmu"], capsys)
    assert status == 0, err
    assert validate_fmu(str(tmp_path / "sub" / "table.fmu")) == []
    assert sorted(p.name for p in (tmp_path / "sub").iterdir()) == ["table.fmu"]


def test_a_sampled_profile_and_a_moving_floor_equal_simulate(tmp_path):
    """The x-stage on a sampled profile (a clamped spline through 50 ms samples: 160 pieces, each a breakpoint)
    and the floor heaving and rolling by sines (the scenario's [ground] motion, profiles of the FMU's time)."""
    base = load_scenario("paper-table-3-2")
    t = np.arange(0.0, 8.0 + 1e-9, 0.05)
    q = base.carriages[0].profile.evaluate(t)[0]
    carriages = (dataclasses.replace(base.carriages[0], profile=samples(t, q)), *base.carriages[1:])
    ground = Ground(motion={"z": SineProfile(2e-6, 2 * np.pi * 3.0, t0=0.2), "rx": SineProfile(1e-6, 2 * np.pi * 5.0)})
    scenario = shortened("paper-table-3-2", carriages=carriages, ground=ground)
    path = write_fmu(scenario, tmp_path / "sampled.fmu")
    names = output_names(path)
    t_out, values = run(path, tmp_path, names, scenario.simulation.duration, STEP)
    assert_close(t_out, values, names, Simulator(scenario).run())


def test_model_exchange_announces_the_breakpoints_as_time_events(table, tmp_path):
    scenario, path = table
    md = read_model_description(str(path))
    fmu = FMU2Model(guid=md.guid, unzipDirectory=extract(str(path), unzipdir=str(tmp_path / "me")),
                    modelIdentifier=md.modelExchange.modelIdentifier, instanceName="me")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    events = []
    for _ in range(len(scenario.breakpoints) + 1):
        *_, defined, next_time = fmu.newDiscreteStates()
        if not defined:
            break
        events.append(next_time)
        fmu.enterContinuousTimeMode()
        fmu.setTime(events[-1])
        fmu.enterEventMode()
    fmu.terminate()
    fmu.freeInstance()
    np.testing.assert_allclose(events, scenario.breakpoints, rtol=0, atol=1e-12)
