"""
Modes against the stage's travel
================================

Linearised about a rest configuration, the table on its isolators has six rigid-body modes. As the
stage travels, its mass moves over the table and the rocking modes shift: :func:`isolator.modes_over_travel`
parks each carriage at points along its stroke and computes the modes there.
"""

# %%
from isolator import linearise, load_scenario, modes, modes_over_travel

scenario = load_scenario("paper-table-3-2")
parked = modes(linearise(scenario))
for f, zeta, dof in zip(parked.frequencies_hz, parked.damping_ratios, parked.dominant, strict=True):
    print(f"{dof:>2}: {f:5.2f} Hz, damping ratio {zeta:.3f}")

# %%
# Eleven positions along each carriage's stroke.
travel = modes_over_travel(scenario, samples=11)
fig = travel.plot()
