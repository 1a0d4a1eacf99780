"""
Sizing the air springs: the pneumatic study's map
=================================================

An air spring's damping comes from a capillary orifice between its spring chamber and a damping
chamber. :func:`studies.pneumatic.run_pneumatic_study` sweeps every isolator's orifice diameter against
the damping-chamber volume ratio ``N = V2/V1r``, and finds the orifice that minimises the heave
transmissibility peak at each ratio; on a symmetric table that peak is the relaxation isolator's closed
form ``1 + 2/N``. Here a coarse 5 x 4 grid (the command's default is 15 x 11).
"""

# %%
import tempfile

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.ticker import NullFormatter, ScalarFormatter

from isolator import load_scenario
from studies.pneumatic import default_diameters, run_pneumatic_study

scenario = load_scenario("paper-table-3-2-pneumatic")
diameters = default_diameters(scenario)[1::3]
study = run_pneumatic_study(tempfile.mkdtemp(), scenario, diameters, [0.5, 1.0, 2.0, 4.0], progress=False, workers=1)
for optimum, closed in zip(study.optima, study.closed_form, strict=True):
    print(f"N = {optimum.ratio:g}: optimal orifice {1e3 * optimum.diameter:.3f} mm, heave peak {optimum.peak:.3f} "
          f"(closed form {closed.peak:.3f})")

# %%
# The heave transmissibility peak over the grid, the optimal orifice per ratio, the scenario's design.
fig, ax = plt.subplots(figsize=(7, 4.5), layout="constrained")
mesh = ax.pcolormesh(1e3 * study.diameters, study.ratios, study.heave_peak.T, shading="nearest",
                     norm="log", cmap="viridis")
fig.colorbar(mesh, ax=ax, label="heave transmissibility peak [m/m]")
ax.plot([1e3 * o.diameter for o in study.optima], [o.ratio for o in study.optima], "w-o", label="optimal orifice")
ax.plot(1e3 * study.own_diameter, study.own_ratio, "r*", ms=14, label="the scenario's air springs")
ax.set_xscale("log")
ax.set_yscale("log", base=2)
for axis in (ax.xaxis, ax.yaxis):
    axis.set_major_formatter(ScalarFormatter())
    axis.set_minor_formatter(NullFormatter())
ax.set_xticks(1e3 * study.diameters, [f"{1e3 * d:.2f}" for d in study.diameters])
ax.set_yticks(study.ratios, [f"{n:g}" for n in study.ratios])
ax.set_xlabel("orifice diameter [mm]")
ax.set_ylabel("volume ratio N = V2/V1r [-]")
ax.set_title("Air springs of Table 3.2: heave peak over orifice and volume")
ax.legend(loc="upper right")
print("settling about the leveling table, range over the grid [s]:",
      np.round([np.nanmin(study.settling_time), np.nanmax(study.settling_time)], 2))
plt.show()
