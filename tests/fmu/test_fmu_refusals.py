"""The FMUs refuse what they cannot compute, with the FMI 2.0 status and a logged message naming the variable
(trust round 4, issue 42 item 4): non-finite inputs, input derivatives, times, states and step sizes; a
``doStep`` too long to count; parameters the scenario reader would refuse, when initialisation ends. Driven
through FMPy's low-level API; the call sequences and values generated with hypothesis."""

from __future__ import annotations

import math
import shutil
import subprocess
from ctypes import byref, c_double
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from isolator import Simulator, load_scenario
from isolator.errors import ParameterError
from isolator.fmu import write_fmu
from isolator.model.names import expand_changes

fmpy = pytest.importorskip("fmpy")
from fmpy import calloc, extract, free, read_model_description  # noqa: E402
from fmpy.fmi1 import FMICallException  # noqa: E402
from fmpy.fmi2 import (  # noqa: E402
    FMU2Model,
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    fmi2Discard,
    fmi2Error,
    fmi2LastSuccessfulTime,
    fmi2Terminated,
)
from fmpy.logging import addLoggerProxy  # noqa: E402

from controllers.feedback import design_controller, write_controller_fmu  # noqa: E402

pytestmark = pytest.mark.skipif(shutil.which("cc") is None and shutil.which("gcc") is None, reason="no C compiler")

TUNABLE = ["table.mass", "isolators[*].damping.z", "isolators[0].stiffness.z", "table.inertia.z"]
NON_FINITE = st.sampled_from([math.nan, math.inf, -math.inf])


class Log:
    """FMI callbacks that keep the FMU's log messages (status, text), formatted by FMPy's native proxy."""

    def __init__(self) -> None:
        self.messages: list[tuple[int, str]] = []

        def logger(env, name, status, category, message):
            self.messages.append((status, message.decode("utf-8")))

        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(logger)
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        addLoggerProxy(byref(self.callbacks))


class Fmu:
    """One FMU extracted once; instances with a :class:`Log` each."""

    def __init__(self, path, folder):
        self.md = read_model_description(str(path))
        self.unzip = extract(str(path), unzipdir=str(folder))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.names = {v.valueReference: v.name for v in self.md.modelVariables}

    def instance(self, model_exchange: bool = False, initialise: bool = True):
        log = Log()
        kind, interface = (FMU2Model, self.md.modelExchange) if model_exchange else (FMU2Slave, self.md.coSimulation)
        fmu = kind(guid=self.md.guid, unzipDirectory=self.unzip, modelIdentifier=interface.modelIdentifier,
                   instanceName="probe")
        fmu.instantiate(callbacks=log.callbacks)
        fmu._log = log  # the callbacks live as long as the instance
        if initialise:
            fmu.setupExperiment(startTime=0.0)
            fmu.enterInitializationMode()
            fmu.exitInitializationMode()
        return fmu, log


def refused(call, *args) -> int:
    """The status of a call that must fail (FMPy raises for fmi2Discard and worse)."""
    with pytest.raises(FMICallException) as caught:
        call(*args)
    return caught.value.status


@pytest.fixture(scope="module")
def plant(tmp_path_factory):
    """Table 3.2 (its carriages on their profiles) with four parameters."""
    scenario = load_scenario("paper-table-3-2")
    folder = tmp_path_factory.mktemp("plant")
    return scenario, Fmu(write_fmu(scenario, folder / "table.fmu", parameters=TUNABLE), folder / "unzip")


@pytest.fixture(scope="module")
def controller(tmp_path_factory):
    """A skyhook from the geophones (no weight search) as the controller FMU."""
    scenario = load_scenario("paper-table-3-2-geophones")
    ctrl = design_controller(scenario, "skyhook", 2000.0, options={"gain": 2e4})
    folder = tmp_path_factory.mktemp("controller")
    path = write_controller_fmu(ctrl, folder / "controller.fmu", scenario=scenario)
    return ctrl, Fmu(path, folder / "unzip")


def plant_calls(fmu: Fmu):
    """A plant's Co-Simulation calls: set an input (finite, or not), set an input derivative, step."""
    inputs = [v.name for v in fmu.md.modelVariables if v.causality == "input"]
    value = st.one_of(st.floats(-1e3, 1e3), NON_FINITE)
    scaled = lambda name, x: x if name.startswith("f:") or not math.isfinite(x) else x * 1e-6
    set_input = st.tuples(st.just("set"), st.sampled_from(inputs), value).map(lambda c: (*c[:2], scaled(c[1], c[2])))
    derivative = st.tuples(st.just("derivative"), st.sampled_from(inputs), value, st.integers(1, 3)).map(
        lambda c: (c[0], c[1], scaled(c[1], c[2]), c[3]))
    step = st.tuples(st.just("step"), st.floats(0.0, 0.01))
    return st.lists(st.one_of(set_input, derivative, step), min_size=1, max_size=6)


def test_non_finite_inputs_and_their_derivatives_are_refused_naming_them(plant):
    """A NaN actuator command once became the full negative force with status OK: now every non-finite input
    or input derivative is fmi2Error with one message naming the input, the instance then refusing all but a
    reset; finite calls all succeed and leave finite outputs."""
    _, fmu = plant
    outputs = [v.valueReference for v in fmu.md.modelVariables if v.causality == "output"]

    @given(plant_calls(fmu))
    def check(calls):
        instance, log = fmu.instance()
        t = 0.0
        try:
            for call in calls:
                if call[0] == "step":
                    instance.doStep(currentCommunicationPoint=t, communicationStepSize=call[1])
                    t += call[1]
                    continue
                name, x = call[1], call[2]
                args = ([fmu.vr[name]], [x]) if call[0] == "set" else ([fmu.vr[name]], [call[3]], [x])
                method = instance.setReal if call[0] == "set" else instance.setRealInputDerivatives
                if math.isfinite(x):
                    method(*args)
                    continue
                assert refused(method, *args) == fmi2Error
                assert len(log.messages) == 1
                status, text = log.messages[0]
                assert status == fmi2Error
                assert name in text, text
                assert "must be finite" in text, text
                assert refused(instance.doStep, t, 1e-3) == fmi2Error  # failed: only a reset now
                instance.reset()
                instance.setupExperiment(startTime=0.0)
                instance.enterInitializationMode()
                instance.exitInitializationMode()
                return
            assert np.all(np.isfinite(instance.getReal(outputs)))
            assert log.messages == []
        finally:
            instance.freeInstance()

    check()


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_times_and_states_are_refused(plant, bad):
    """setupExperiment(NaN), setTime(NaN), a NaN state and doStep with a NaN or infinite point or step were
    accepted with status OK. A non-finite state of Model Exchange is fmi2Discard (the integrator may retry
    with a shorter step) and is not taken; the rest are fmi2Error, each with a message naming what."""
    _, fmu = plant
    instance, log = fmu.instance(initialise=False)
    assert refused(instance.setupExperiment, None, bad) == fmi2Error
    assert "startTime" in log.messages[-1][1]
    instance.freeInstance()

    me, log = fmu.instance(model_exchange=True)
    n = sum(v.name.startswith("state[") for v in fmu.md.modelVariables)
    states = (c_double * n)()
    me.getContinuousStates(states, n)
    for k in (0, 3, n - 1):
        changed = (c_double * n)(*states)
        changed[k] = bad
        assert refused(me.setContinuousStates, changed, n) == fmi2Discard
        status, text = log.messages[-1]
        assert status == fmi2Discard
        assert f"state[{k}]" in text, text
        assert "finite" in text, text
    now = (c_double * n)()
    me.getContinuousStates(now, n)
    assert list(now) == list(states)  # not taken
    assert refused(me.setTime, bad) == fmi2Error
    assert "time" in log.messages[-1][1]
    me.freeInstance()

    for point, step in ((bad, 1e-3), (0.0, bad)):
        cs, log = fmu.instance()
        assert refused(cs.doStep, point, step) == fmi2Error
        assert "fmi2DoStep" in log.messages[-1][1]
        assert "finite" in log.messages[-1][1]
        cs.freeInstance()


def test_a_step_longer_than_the_count_is_discarded_and_changes_nothing(plant):
    """A doStep past 2^31 RK4 steps returned garbage with status OK (the count overflowed an int): it is
    fmi2Discard, nothing done (the last successful time is the step's start, the FMU does not want to
    terminate), and the same instance then steps as a fresh one does."""
    _, fmu = plant
    outputs = [v.valueReference for v in fmu.md.modelVariables if v.causality == "output"]
    instance, log = fmu.instance()
    assert refused(instance.doStep, 0.0, 1e7) == fmi2Discard
    status, text = log.messages[-1]
    assert status == fmi2Discard
    assert "1e+07 s" in text
    assert "shorter" in text
    assert instance.getRealStatus(fmi2LastSuccessfulTime) == 0.0
    assert not instance.getBooleanStatus(fmi2Terminated)
    instance.doStep(0.0, 0.5)
    fresh, _ = fmu.instance()
    fresh.doStep(0.0, 0.5)
    np.testing.assert_array_equal(instance.getReal(outputs), fresh.getReal(outputs))
    instance.freeInstance()
    fresh.freeInstance()


def _values(name: str):
    """Values for a parameter: the rule's edges and beyond, ordinary ones, non-finite and huge ones."""
    edges = {"table.mass": [1e-3, 0.0, -1.0, 5e-4], "table.inertia.z": [0.0, -1.0, 1e5, 1e3]}
    return st.one_of(st.sampled_from(edges.get(name, [0.0, -1e-9, -5.0])), st.floats(-1e4, 1e4),
                     st.sampled_from([2e15, -2e15]))


@given(st.sampled_from(TUNABLE).flatmap(lambda n: st.tuples(st.just(n), _values(n))))
def test_parameters_the_reader_refuses_fail_initialisation_naming_them(plant, case):
    """An FMU parameter set to a mass <= 0 or a negative damping ran (and diverged). Now
    fmi2ExitInitializationMode is fmi2Error with one message naming the parameter and the rule exactly when
    the toolkit's own ``changes=`` refuses the value (the triangle of the principal moments included)."""
    scenario, fmu = plant
    name, value = case
    sim = Simulator(scenario)
    try:
        sim.layout.with_changes(sim.parameters, expand_changes(sim.layout, {name: value}, "changes"), "changes")
        python_refuses = None
    except ParameterError as exc:
        python_refuses = str(exc)
    instance, log = fmu.instance(initialise=False)
    try:
        instance.setupExperiment(startTime=0.0)
        instance.setReal([fmu.vr[name]], [value])
        instance.enterInitializationMode()
        try:
            instance.exitInitializationMode()
            c_refuses, status = None, 0
        except FMICallException as exc:
            c_refuses, status = log.messages[-1][1], exc.status
        assert status in (0, fmi2Error)
        if python_refuses is None:  # valid: the FMU starts (or finds no equilibrium, without blaming the rule)
            assert c_refuses is None or "parameter" not in c_refuses, c_refuses
        else:
            assert c_refuses is not None, python_refuses
            assert len(log.messages) == 1
            if "triangle" in python_refuses:  # the vector's rule, naming the vector
                assert "parameter table.inertia: principal moments must satisfy the triangle inequality" in c_refuses
            else:  # the same words as the reader's
                words = python_refuses.split(": ", 1)[1].rpartition(", got")[0]
                assert f"parameter {name}: {words}, got " in c_refuses, (python_refuses, c_refuses)
    finally:
        instance.freeInstance()


def controller_calls(ctrl):
    names = [f"y:{s}" for s in ctrl.sensors] + [f"q:{c}" for c in ctrl.carriages]
    value = st.one_of(st.floats(-1.0, 1.0), NON_FINITE)
    set_input = st.tuples(st.just("set"), st.sampled_from(names), value)
    step = st.tuples(st.just("step"), st.one_of(st.floats(0.0, 0.01), NON_FINITE))
    return st.lists(st.one_of(set_input, step), min_size=1, max_size=6)


def test_the_controller_fmu_refuses_non_finite_inputs_and_steps(controller):
    """The controller FMU passed NaN through with status OK and never returned from doStep(t, inf): a
    non-finite input or step is fmi2Error naming it, at once; finite calls give finite commands."""
    ctrl, fmu = controller
    outputs = [fmu.vr[f"u:{a}"] for a in ctrl.actuators]

    @given(controller_calls(ctrl))
    def check(calls):
        instance, log = fmu.instance()
        t = 0.0
        try:
            for call in calls:
                x = call[-1]
                if math.isfinite(x):
                    if call[0] == "set":
                        instance.setReal([fmu.vr[call[1]]], [x])
                    else:
                        instance.doStep(currentCommunicationPoint=t, communicationStepSize=x)
                        t += x
                    continue
                if call[0] == "set":
                    assert refused(instance.setReal, [fmu.vr[call[1]]], [x]) == fmi2Error
                    assert call[1] in log.messages[-1][1]
                else:
                    assert refused(instance.doStep, t, x) == fmi2Error
                    assert "fmi2DoStep" in log.messages[-1][1]
                assert len(log.messages) == 1
                assert "must be finite" in log.messages[0][1]
                return
            assert np.all(np.isfinite(instance.getReal(outputs)))
        finally:
            instance.freeInstance()

    check()


def test_the_controller_fmu_refuses_steps_it_cannot_count(controller):
    _, fmu = controller
    instance, log = fmu.instance()
    assert refused(instance.doStep, 0.0, 1e7) == fmi2Discard  # 2e10 samples: nothing done, step shorter
    assert "shorter" in log.messages[-1][1]
    assert instance.getRealStatus(fmi2LastSuccessfulTime) == 0.0
    instance.doStep(0.0, 1e-3)
    assert refused(instance.doStep, 1e-3, 1e300) == fmi2Error  # beyond 2^53 samples
    assert "2^53" in log.messages[-1][1]
    instance.freeInstance()
    instance, log = fmu.instance(initialise=False)
    assert refused(instance.setupExperiment, None, math.nan) == fmi2Error
    assert "startTime" in log.messages[-1][1]
    instance.freeInstance()


def test_the_controller_fmus_sources_compile_strictly(controller, tmp_path):
    """The refusals' C (printf-style messages, 64-bit counts) is C99 without a warning."""
    _, fmu = controller
    sources = Path(fmu.unzip) / "sources"
    for source in sorted(sources.glob("*.c")):
        subprocess.run(["gcc" if shutil.which("gcc") else "cc", "-std=c99", "-Wall", "-Wextra", "-Werror",
                        "-pedantic", "-trigraphs", "-c", "-o", str(tmp_path / "probe.o"), str(source)], check=True,
                       capture_output=True, cwd=sources)
