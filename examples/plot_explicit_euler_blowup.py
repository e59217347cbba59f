"""
Explicit (symplectic) Euler blows up above 2 / ω_max
====================================================

An explicit integrator is stable only when h < 2 / ω_max, ω_max² the largest eigenvalue of
M⁻¹ L (:func:`clothsim.solvers.stable_time_step`). Implicit Euler, as minimized by
local/global, has no such limit. We run the same cloth with symplectic Euler just below
and just above the limit, and with local/global at the paper's h = 1/30 s, far above it.
(ω_max comes from L, whose springs are as stiff across as along; a real spring is softer
across, so the true limit can lie a little above 2 / ω_max: the run above the limit
therefore takes 1.3 h_max, and the lesson checks that it blows up within half a second.)
"""

import warnings

import matplotlib.pyplot as plt
import numpy as np

from clothsim.gallery import curtain, grid_cloth
from clothsim.solvers import StabilityWarning, stable_time_step

h_max = stable_time_step(grid_cloth(9, k=800.0))
print(f"stability limit h_max = 2 / ω_max = {h_max * 1e3:.3f} ms")


def run(h, method, seconds=0.5):
    sim = curtain(9, k=800.0, h=h, method=method)
    growth = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StabilityWarning)   # above the limit on purpose
        for _ in range(int(seconds / h)):
            sim.step()
            growth.append(np.abs(sim.state.positions).max())
            if not np.isfinite(growth[-1]) or growth[-1] > 1e3:
                break
    return np.arange(1, len(growth) + 1) * h, np.array(growth)


curves = {"symplectic Euler, h = 0.9 h_max": run(0.9 * h_max, "symplectic-euler"),
          "symplectic Euler, h = 1.3 h_max": run(1.3 * h_max, "symplectic-euler"),
          "local/global, h = 1/30 s": run(1 / 30, "local-global")}
stable, unstable, implicit = curves.values()

# %%
# Below the limit the cloth stays within a few metres of the origin; above it the
# coordinates explode; implicit Euler at a step many times the limit is fine.
assert stable[1].max() < 3 and implicit[1].max() < 3
assert unstable[1].max() > 1e3 or not np.all(np.isfinite(unstable[1]))
assert 1 / 30 > 10 * h_max

fig, ax = plt.subplots(figsize=(5, 3.2))
for label, (t, g) in curves.items():
    ax.semilogy(t, g, label=label)
ax.set(xlabel="time [s]", ylabel="max |coordinate| [m]", title="explicit vs implicit")
ax.legend(fontsize=7)
fig.tight_layout()
