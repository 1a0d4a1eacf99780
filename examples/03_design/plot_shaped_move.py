"""
A shaped move that leaves the table quiet
=========================================

A ZVD input shaper tuned to the mode each carriage excites most convolves the move with three
impulses, so that the table's ringing from the acceleration cancels the ringing from the braking: the
move gets a little longer, the settling much shorter.
"""

# %%
import matplotlib.pyplot as plt

from controllers.profiles import shaped_scenario
from isolator import load_scenario, simulate

scenario = load_scenario("paper-table-3-2")
paper = simulate(scenario)
zvd = simulate(shaped_scenario(scenario, "zvd"))
for name, run in (("paper profile", paper), ("ZVD-shaped", zvd)):
    move = run.stop_time - run.move_start
    print(f"{name}: move {move:.2f} s, settling {run.settling_time_max:.2f} s, "
          f"cycle {move + run.settling_time_max:.2f} s")

# %%
# Heave and yaw around the stop, each run on its own clock from its stop.
fig, axes = plt.subplots(2, 1, sharex=True, figsize=(7, 5), layout="constrained")
for ax, signal, unit, scale in ((axes[0], "z", "µm", 1e6), (axes[1], "rz", "µrad", 1e6)):
    for name, run in (("paper profile", paper), ("ZVD-shaped", zvd)):
        ax.plot(run.t - run.stop_time, scale * run.signal(signal), label=name)
    ax.set_ylabel(f"{signal} [{unit}]")
    ax.axvline(0.0, color="k", lw=0.8)
axes[0].set_title("Table 3.2: table motion around the carriages' stop")
axes[1].set_xlabel("time after the stop [s]")
axes[1].set_xlim(-3.0, 3.0)
axes[0].legend()
plt.show()
