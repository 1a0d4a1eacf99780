"""
A controller for the real table: design from geophones, check, export as C
===========================================================================

The bundled ``paper-table-3-2-geophones`` table measures its motion with twelve geophones, one at each
actuator. An LQG controller is designed from those sensors at 2 kHz, gain-scheduled over the x-stage's
travel, checked closed-loop at the travel's ends and middle with the isolators' stiffness and damping
uncertain, written as C99 code, and run in the simulation exactly as the exported code runs it. The same
as ``isolator controller paper-table-3-2-geophones --method lqg --sample-rate 2000 --schedule 3
--uncertainty stiffness=+-20%,damping=+-30% --out DIR`` and ``isolator simulate ... --controller DIR``.
"""

# %%
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt

from controllers import feedback as fb
from isolator import Simulator, load_scenario

scenario = load_scenario("paper-table-3-2-geophones")
controller = fb.design_controller(scenario, "lqg", 2000.0, schedule=3)
report = fb.check_robustness(scenario, controller, fb.parse_uncertainty("stiffness=+-20%,damping=+-30%"))
report.raise_if_unstable()
print("\n".join(report.summary()[:3]))

folder = Path(tempfile.mkdtemp())
controller.to_json(folder)
header, source = fb.write_c(controller, folder)
print(f"{source.name}: {len(source.read_text().splitlines())} lines of C99, {controller.states} states")

sim = Simulator(scenario)
passive = sim.run()
active = sim.run(controller=controller)
print(f"settling: passive {passive.settling_time_max:.2f} s, LQG from the geophones "
      f"{active.settling_time_max:.2f} s")

# %%
# Pitch (from its final tilt) and heave around the stop, and the forces the actuators apply.
fig, axes = plt.subplots(1, 3, figsize=(12, 3.8), layout="constrained")
for name, run in (("passive", passive), ("LQG (geophones)", active)):
    axes[0].plot(run.t - run.stop_time, 1e6 * (run.signal("ry") - run.final[4]), label=name)
    axes[1].plot(run.t - run.stop_time, 1e6 * run.signal("z"), label=name)
for k, name in enumerate(active.actuator_names[:3]):
    axes[2].plot(active.t, active.actuator_forces[k], label=name)
axes[0].set_ylabel("ry from its final value [µrad]")
axes[1].set_ylabel("z [µm]")
axes[2].set_ylabel("force [N]")
titles = ("Pitch around the stop", "Heave around the stop", "Actuator forces at isolator 1")
for ax, title in zip(axes, titles, strict=True):
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
axes[0].set_xlim(-1.0, 3.0)
axes[0].set_ylim(-80.0, 80.0)
axes[1].set_xlim(-1.0, 3.0)
axes[0].set_xlabel("time after the stop [s]")
axes[1].set_xlabel("time after the stop [s]")
axes[2].set_xlabel("time [s]")
plt.show()
