"""
The table as an FMU: FMPy runs it, isolator simulate overlays it
=================================================================

``isolator fmu`` writes the table of a scenario as an FMI 2.0 FMU (Model Exchange and Co-Simulation) that
Simulink, Modelica tools or FMPy import. Here FMPy simulates Table 3.2's FMU both ways (Co-Simulation at a
1 ms communication step, Model Exchange with CVode) and the toolkit's own simulation is drawn over them:
the same table, to a millionth of each signal's peak. The same as
``isolator fmu paper-table-3-2 --out table.fmu``.
"""

# %%
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from fmpy import simulate_fmu

from isolator import load_scenario, simulate
from isolator.fmu import write_fmu

scenario = load_scenario("paper-table-3-2")
path = write_fmu(scenario, Path(tempfile.mkdtemp()) / "table.fmu")
names = ["x", "y", "z", "rx", "ry", "rz"]
stop = scenario.simulation.duration
cs = simulate_fmu(str(path), fmi_type="CoSimulation", output_interval=1e-3, stop_time=stop, output=names)
me = simulate_fmu(str(path), fmi_type="ModelExchange", relative_tolerance=1e-9, output_interval=1e-3,
                  stop_time=stop, output=names)
response = simulate(scenario)
for label, run in (("Co-Simulation", cs), ("Model Exchange", me)):
    worst = max(np.max(np.abs(np.interp(response.t, run["time"], run[n]) - response.signal(n)))
                / np.max(np.abs(response.signal(n))) for n in names)
    print(f"{label}: largest difference from isolator simulate {worst:.1e} of the signal's peak")

# %%
# Pitch and roll through the move: FMPy's two runs of the FMU and the toolkit's simulation.
fig, axes = plt.subplots(1, 2, figsize=(11, 3.8), layout="constrained")
for ax, name in zip(axes, ("ry", "rx"), strict=True):
    ax.plot(cs["time"], 1e6 * cs[name], lw=3, alpha=0.5, label="FMU, Co-Simulation (FMPy, 1 ms)")
    ax.plot(me["time"], 1e6 * me[name], lw=1.5, ls="--", label="FMU, Model Exchange (FMPy, CVode)")
    ax.plot(response.t, 1e6 * response.signal(name), lw=0.8, color="k", label="isolator simulate")
    ax.set_xlabel("time [s]")
    ax.set_ylabel(f"{name} [µrad]")
    ax.grid(True, alpha=0.3)
axes[0].legend(fontsize=8)
axes[0].set_title("Pitch")
axes[1].set_title("Roll")
plt.show()
