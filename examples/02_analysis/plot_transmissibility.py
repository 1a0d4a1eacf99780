"""
Floor-to-table transmissibility
===============================

How much floor vibration reaches the table, axis by axis: the linearised table as a python-control
state-space model, its frequency response from floor motion to table motion, the resonance peaks and
the frequency above which the table isolates.
"""

# %%
from isolator import linearise, load_scenario, transmissibility

lin = linearise(load_scenario("paper-table-3-2"))
print(lin.system.nstates, "states;", lin.system.ninputs, "inputs;", lin.system.noutputs, "outputs")
t = transmissibility(lin)
for axis in ("x", "y", "z"):
    peak, at = t.peak(axis)
    print(f"{axis}: peak {peak:.2f} at {at:.2f} Hz, isolates above {t.isolation_onset(axis):.2f} Hz")

# %%
# Same-axis transmissibility (Bode magnitude, python-control conventions); the dots are the peaks.
fig = t.plot("Table 3.2: floor to table")
