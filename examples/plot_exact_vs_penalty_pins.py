"""
Exact pins against penalty pins
===============================

Two ways to hold a vertex. *Exact* (``method="constraint"``): the vertex is removed from
the unknowns and put at its target. *Penalty* (the paper's own code): a stiff zero-rest-
length spring to the target, which enters L's diagonal and the right-hand side. A penalty
pin gives a little: the hanging cloth pulls it down by about (its share of the weight) / k.
As k grows the two agree.
"""

import matplotlib.pyplot as plt
import numpy as np

from clothsim import Simulation
from clothsim.gallery import hanging_cloth, top_corners


def hang(method, stiffness=1e5):
    model, effects = hanging_cloth(7, pin_method=method, pin_stiffness=stiffness)
    sim = Simulation(model, h=1 / 30, effects=effects, iterations=20)
    sim.run(60)                                   # 2 s: it hangs nearly still
    return model, sim.state.positions


model, exact = hang("constraint")
corners = top_corners(7)
assert np.array_equal(exact[corners], model.mesh.vertices[corners])   # never moves

ks = [1e2, 1e3, 1e4, 1e5]
slip = []
for k in ks:
    _, x = hang("penalty", k)
    slip.append(np.linalg.norm(x[corners] - model.mesh.vertices[corners], axis=1).max())
    print(f"penalty k = {k:.0e} N/m: pinned corners moved {slip[-1]:.2e} m")

# %%
# The penalty pins' slip falls like 1/k (10× stiffer, about 10× less), and is what each pin
# carries, half the weight of the 1 kg cloth, divided by k.
assert all(b < 0.2 * a for a, b in zip(slip, slip[1:]))
for k, d in zip(ks, slip):
    assert abs(d - 0.5 * 1.0 * 9.81 / k) < 0.1 * 0.5 * 9.81 / k
_, x = hang("penalty", 1e5)
assert np.abs(x - exact).max() < 1e-3

fig, ax = plt.subplots(figsize=(5, 3.2))
ax.loglog(ks, slip, "o-")
ax.set(xlabel="penalty stiffness k [N/m]", ylabel="pinned corner displacement [m]",
       title="penalty pins converge to exact pins as k → ∞")
fig.tight_layout()
