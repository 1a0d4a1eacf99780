"""
A feedback design: skyhook damping
==================================

Skyhook damping pushes each actuator against the absolute velocity at its point. Designed on the
linearised plant with python-control, checked as a closed loop (with the actuators' lag, continuous and
sampled), then run in the time-varying simulation at its sample rate with saturation.
"""

# %%
import matplotlib.pyplot as plt

from controllers import feedback as fb
from isolator import Simulator, linearise, load_scenario, transmissibility

scenario = load_scenario("paper-table-3-2-active")
lin = linearise(scenario)
sky = fb.skyhook(lin, damping=5e4, sample_rate=1000.0)
passive_t = transmissibility(lin)
active_t = transmissibility(fb.closed_loop(lin, sky))
print(f"heave peak: passive {passive_t.peak('z')[0]:.2f}, skyhook {active_t.peak('z')[0]:.2f}")

sim = Simulator(scenario)
passive = sim.run()
active = sim.run(feedback=fb.feedback_law(scenario, sky))
print(f"settling: passive {passive.settling_time_max:.2f} s, skyhook {active.settling_time_max:.2f} s")

# %%
# Heave transmissibility, and the heave after the stop.
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.8), layout="constrained")
for name, t in (("passive", passive_t), ("skyhook", active_t)):
    ax1.loglog(t.frequency_hz, t.magnitude("z"), label=name)
ax1.set_xlabel("frequency [Hz]")
ax1.set_ylabel("z transmissibility [m/m]")
ax1.set_title("Floor to table, heave")
for name, run in (("passive", passive), ("skyhook", active)):
    ax2.plot(run.t - run.stop_time, 1e6 * run.signal("z"), label=name)
ax2.set_xlim(-1.0, 3.0)
ax2.set_xlabel("time after the stop [s]")
ax2.set_ylabel("z [µm]")
ax2.set_title("Heave around the stop")
ax1.legend()
plt.show()
