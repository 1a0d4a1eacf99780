"""
The paper's transient and its settling time
===========================================

The LCD-inspection stage of the paper's Table 3.2 moves across a granite table on four isolators; its
reaction forces rock the table. We simulate the move with the exact rigid-body model and read the 5 %
settling time of each of the table's six signals after the carriages stop.
"""

# %%
# Load the bundled scenario and simulate it (the first run compiles the model, a few seconds).
from isolator import load_scenario, simulate

scenario = load_scenario("paper-table-3-2")
response = simulate(scenario)
print(f"the carriages stop at {response.stop_time:.2f} s")
for signal, time in response.settling_time.items():
    print(f"{signal:>2}: settles {time:.3f} s after the stop")

# %%
# The response: rotations left, translations right, the settling band after the stop shaded, the
# settling instant dashed.
fig = response.plot()
