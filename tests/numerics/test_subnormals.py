"""Loading the compiled models leaves the process's floating point alone (no flush-to-zero)."""

from __future__ import annotations

import subprocess
import sys


def test_compiled_libraries_do_not_flush_subnormals_to_zero():
    """-ffast-math at link time would add start-up code that sets FTZ/DAZ for the whole Python process."""
    code = (
        "import numpy as np\n"
        "from isolator import load_scenario, simulate\n"
        "simulate(load_scenario())\n"
        "x = np.array([1e-310])\n"
        "print(float((x / 2)[0]) > 0.0, float(np.nextafter(0.0, 1.0) * 1.0) > 0.0)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["True", "True"]
