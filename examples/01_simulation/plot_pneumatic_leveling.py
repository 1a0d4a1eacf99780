"""
Leveling after a shift of weight
================================

On air springs, the stage's 400 kg moving forward shifts the load between the isolators; leveling
valves add air to the front group and vent the rear ones until the table is level again. The bundled
``paper-table-3-2-pneumatic`` puts the paper's table on four air springs in three leveling groups.
"""

# %%
from isolator import load_scenario, simulate

run = simulate(load_scenario("paper-table-3-2-pneumatic"))
for group, time in run.leveling_time.items():
    print(f"group {group}: level {time:.2f} s after the stop")
print(f"settling (5 % about the final, level table): {run.settling_time_max:.2f} s")
print(f"settling about the leveling table: {run.dynamic_settling_time_max:.2f} s")

# %%
# Chamber pressures and the valves' sensor heights through the move and the leveling.
fig = run.plot_leveling()
