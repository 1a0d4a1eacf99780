"""
A sweep of isolator stiffness and damping
=========================================

:func:`isolator.sweep.sweep` runs a scenario for many designs of any named parameter; here every
isolator's stiffness and damping as factors on the scenario's, over a crossed grid. The rows come back
in design order with each design's settling time and status.
"""

# %%
import numpy as np

from isolator.sweep import sweep
from isolator.sweep.figure import plot_sweep

result = sweep("paper-table-3-2", workers=1,
               scale={"isolators[*].stiffness": np.geomspace(0.4, 2.5, 5).tolist(),
                      "isolators[*].damping": np.geomspace(0.3, 6.0, 8).tolist()})
print(result.summary())
print("best design:", result.best())

# %%
# The largest settling time over the grid; crosses in the strip above mark designs that do not settle
# within the run (a row per stiffness factor, in its line's colour).
fig = plot_sweep(result, title="Table 3.2: settling over stiffness and damping factors")
