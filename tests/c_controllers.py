"""Compile an exported controller with the system compiler and step it through ctypes (shared by the tests of
the C export and of ``isolator controller``)."""

from __future__ import annotations

import ctypes
import shutil
import subprocess

import numpy as np
import pytest

from controllers.feedback import write_c

COMPILER = shutil.which("cc") or shutil.which("gcc")
needs_compiler = pytest.mark.skipif(COMPILER is None, reason="no C compiler (cc or gcc)")

# probes the contract's macros from outside: integer constants (file-scope array sizes), a double rate,
# the complete struct type
PROBE = """#include "controller.h"
static const int probe_sizes[ISOLATOR_CTRL_INPUTS][ISOLATOR_CTRL_OUTPUTS][ISOLATOR_CTRL_CARRIAGES + 1] = {{{0}}};
int probe_inputs(void) { return ISOLATOR_CTRL_INPUTS + 0 * probe_sizes[0][0][0]; }
int probe_outputs(void) { return ISOLATOR_CTRL_OUTPUTS; }
int probe_carriages(void) { return ISOLATOR_CTRL_CARRIAGES; }
double probe_rate(void) { return ISOLATOR_CTRL_SAMPLE_RATE / 2; }
unsigned long probe_state_size(void) { return (unsigned long)sizeof(isolator_ctrl_state); }
"""


def build(controller, folder):
    """Write and compile the controller (with the probe) with -Werror; its library through ctypes."""
    write_c(controller, folder)
    (folder / "probe.c").write_text(PROBE)
    lib = folder / "libcontroller.so"
    subprocess.run([COMPILER, "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-shared", "-fPIC",
                    "-o", str(lib), str(folder / "controller.c"), str(folder / "probe.c")],
                   check=True, capture_output=True, text=True)
    dll = ctypes.CDLL(str(lib))
    dll.probe_rate.restype = ctypes.c_double
    dll.probe_state_size.restype = ctypes.c_ulong
    assert dll.probe_inputs() == len(controller.sensors)
    assert dll.probe_outputs() == len(controller.actuators)
    assert dll.probe_carriages() == len(controller.carriages)
    assert dll.probe_rate() == controller.sample_rate / 2
    assert dll.probe_state_size() >= 8 * controller.states
    return dll


class CController:
    """The compiled controller stepped through ctypes, its state readable."""

    def __init__(self, dll, controller):
        self.dll, self.c = dll, controller
        self.state = ctypes.create_string_buffer(dll.probe_state_size())
        self.y = (ctypes.c_double * len(controller.sensors))()
        self.q = (ctypes.c_double * max(len(controller.carriages), 1))()
        self.u = (ctypes.c_double * len(controller.actuators))()
        dll.isolator_ctrl_reset(self.state)

    @property
    def x(self):
        return np.frombuffer(self.state.raw, dtype=np.float64)[: self.c.states].copy()

    def step(self, y, q):
        self.y[:] = list(y)
        self.q[: len(q)] = list(q)
        self.dll.isolator_ctrl_step(self.state, self.y, self.q, self.u)
        return np.array(self.u[:])


def compare(controller, dll, ys, qs):
    """Run C and Python side by side; every command and the states equal to 1e-12 (relative)."""
    cc = CController(dll, controller)
    x = controller.reset()
    us_c, us_py, xs_c, xs_py = [], [], [], []
    for y, q in zip(ys, qs, strict=True):
        us_c.append(cc.step(y, q))
        x, u = controller.step(x, y, q)
        us_py.append(u)
        xs_c.append(cc.x)
        xs_py.append(x)
    us_c, us_py = np.array(us_c), np.array(us_py)
    assert np.abs(us_py).max() > 0
    np.testing.assert_allclose(us_c, us_py, rtol=1e-12, atol=1e-12 * np.abs(us_py).max())
    if controller.states:
        xs_c, xs_py = np.array(xs_c), np.array(xs_py)
        np.testing.assert_allclose(xs_c, xs_py, rtol=1e-12, atol=1e-12 * np.abs(xs_py).max())
    return cc
