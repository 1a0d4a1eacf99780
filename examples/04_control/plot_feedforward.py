"""
Feedforward from the planned motion
===================================

The bundled ``paper-table-3-2-active`` adds a vertical and two horizontal 500 N actuators at each
isolator. Feedforward from the planned carriage motion cancels the carriages' reaction on the table,
allocated over the actuators instant by instant, and keeps the table on its quasi-static path.
"""

# %%
import matplotlib.pyplot as plt

from controllers.feedforward import compare_feedforward, feedforward_allocation
from isolator import load_scenario

scenario = load_scenario("paper-table-3-2-active")
comparison = compare_feedforward(scenario, feedforward_allocation(scenario))
for mode in ("passive", "controlled"):
    settled = {k: v for k, v in comparison.settling[mode].items() if v is not None}
    print(f"{mode}: settling {max(settled.values()):.3f} s (largest, in 5 % of the passive peaks)")

# %%
# The table's deviation from its quasi-static path, passive and with feedforward.
fig, axes = plt.subplots(2, 1, sharex=True, figsize=(7, 5), layout="constrained")
for ax, (k, signal, unit) in zip(axes, ((0, "x", "µm"), (4, "ry", "µrad")), strict=True):
    for name, run in (("passive", comparison.passive), ("with feedforward", comparison.controlled)):
        ax.plot(run.t, 1e6 * (run.signals[k] - comparison.quasi_static[k]), label=name)
    ax.set_ylabel(f"{signal} - path [{unit}]")
axes[0].set_title("Table 3.2, active: deviation from the quasi-static path")
axes[1].set_xlabel("time [s]")
axes[0].legend()
plt.show()
