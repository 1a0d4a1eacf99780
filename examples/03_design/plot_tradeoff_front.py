"""
Isolation against settling: the trade-off front
===============================================

Soft isolators keep floor vibration off the table but let the stage's reaction rock it for longer;
damping shortens the settling but lets more high-frequency floor motion through.
:func:`studies.tradeoff.run_tradeoff_study` scales every isolator's stiffness and damping over a grid,
runs every design's transient and linearises it for its transmissibility. Here a coarse 5 x 5 grid
(the command's default is 17 x 16).
"""

# %%
import tempfile

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.ticker import NullFormatter, ScalarFormatter

from isolator import load_scenario
from studies.tradeoff import run_tradeoff_study

study = run_tradeoff_study(tempfile.mkdtemp(), load_scenario("paper-table-3-2"),
                           stiffness=[0.35, 0.6, 1.0, 1.7, 3.0], damping=[0.5, 1.0, 2.0, 4.0, 8.0],
                           progress=False, workers=1)
front = study.pareto()
for i, j in front:
    print(f"stiffness x{study.stiffness[i]:.2f}, damping x{study.damping[j]:.1f}: "
          f"settles in {study.settling_time[i, j]:.2f} s, transmissibility {study.transmissibility[i, j]:.3f}")

# %%
# Every design as a point; the front is what nothing beats in both.
fig, ax = plt.subplots(figsize=(7, 4.5), layout="constrained")
points = ax.scatter(study.transmissibility, study.settling_time,
                    c=np.log2(np.broadcast_to(study.damping, study.settling_time.shape)), cmap="viridis")
fig.colorbar(points, ax=ax, label="log2 of the damping factor")
idx = np.array(front)
order = np.argsort(study.transmissibility[idx[:, 0], idx[:, 1]])
ax.plot(study.transmissibility[idx[order, 0], idx[order, 1]], study.settling_time[idx[order, 0], idx[order, 1]],
        "r-o", mfc="none", label="Pareto front")
if (nominal := study.nominal()) is not None:
    ax.plot(*[[a[nominal]] for a in (study.transmissibility, study.settling_time)], "k*", ms=12,
            label="the scenario's isolators")
ax.set_xscale("log")
ax.xaxis.set_major_formatter(ScalarFormatter())
ax.xaxis.set_minor_formatter(NullFormatter())
ax.set_xticks([0.05, 0.1, 0.2, 0.4, 0.8], ["0.05", "0.1", "0.2", "0.4", "0.8"])
ax.set_xlabel(f"worst floor-to-table transmissibility at {study.reference_hz:g} Hz [m/m]")
ax.set_ylabel("largest 5 % settling time [s]")
ax.set_title("Table 3.2: settling against isolation")
ax.legend()
plt.show()
