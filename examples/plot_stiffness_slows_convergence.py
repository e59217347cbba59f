"""
Stiffness slows convergence
===========================

Local/global converges linearly, at a rate set by how different the constant matrix
M + h² L is from the true Hessian. The stiffer the springs, the more the
direction-dependent part of the Hessian (which local/global ignores) matters compared with
the mass, and the slower the convergence. The paper's numbers on an 11 × 11 sheet: relative
error after 200 iterations about 1e-12 at k = 1e2, 2e-9 at k = 1e4, 4e-5 at k = 1e6.
"""

import matplotlib.pyplot as plt
import numpy as np

from clothsim.gallery import curtain
from clothsim.solvers import LocalGlobalSolver, NewtonSolver

stiffness = [1e2, 1e4, 1e6]
curves = {}
for k in stiffness:
    sim = curtain(11, k=k, plane="xz")
    sim.run(3)
    problem = sim.problem()
    x_star = NewtonSolver(sim.model, iterations=100, tolerance=1e-14).solve(problem).x
    scale = np.linalg.norm(x_star - problem.initial_guess())
    err = []
    for it in LocalGlobalSolver(sim.model).iterates(problem):
        err.append(np.linalg.norm(it.x - x_star) / scale)
        if it.k == 200:
            break
    curves[k] = np.array(err)
    print(f"k = {k:.0e} N/m: error after 200 iterations {err[-1]:.1e}")

# %%
# The error after 200 iterations grows with the stiffness, by orders of magnitude.
e = [curves[k][-1] for k in stiffness]
assert e[0] < e[1] < e[2] and e[0] < 1e-2 * e[2]

fig, ax = plt.subplots(figsize=(5, 3.2))
for k in stiffness:
    ax.semilogy(np.maximum(curves[k], 1e-17), label=f"k = {k:.0e} N/m")
ax.set(xlabel="iteration", ylabel="‖x_k − x*‖ / ‖x₀ − x*‖", title="11 × 11 cloth, h = 1/30 s")
ax.legend()
fig.tight_layout()
