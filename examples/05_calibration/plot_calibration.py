"""
Calibrating the model from measured records
===========================================

Datasheet isolator values are often 20-30 % off. The bundled calibration ``table-3-2`` holds synthetic
records of the paper's Table 3.2 table whose isolators are 15-30 % off the datasheet: 60 s of random
floor motion read by nine table and three floor accelerometers, and the table's response while the stage
moves. :func:`isolator.calibrate` fits the isolators' stiffness and damping to both records together and
gives each parameter its 95 % interval.
"""

# %%
import matplotlib.pyplot as plt

from isolator import calibrate

result = calibrate("table-3-2")
for name, p in result.parameters.items():
    print(f"{name}: {p.initial:.4g} -> {p.value:.5g}, 95 % in [{p.ci95[0]:.5g}, {p.ci95[1]:.5g}]")

# %%
# The floor records' H1 and the move's traces against the nominal and the fitted model, and the
# parameters with their intervals. (The toolkit's figures are plain matplotlib Figures, not pyplot's:
# ``plt.figure(fig)`` hands one to pyplot to show it.)
fig = plt.figure(result.plot())
plt.show()
