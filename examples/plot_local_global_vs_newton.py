"""
Local/global and Newton: error against iterations
=================================================

One implicit Euler step solved by local/global and by Newton: the error of each iterate
against the exact step x* (Newton to rounding). Local/global's error falls steadily
(linearly), Newton's quadratically; both reach the same x*. Counted in iterations Newton
looks better everywhere; the lesson on wall time shows why the paper prefers local/global.
"""

import matplotlib.pyplot as plt
import numpy as np

import clothsim as cs
from clothsim.solvers import LocalGlobalSolver, NewtonSolver

n = 15
mesh = cs.grid(n, n, size=(1.0, 1.0), plane="xz")
model = cs.Model.build(mesh, cs.grid_springs(mesh, structural=500.0, shear=500.0,
                                             bending=50.0), total_mass=1.0)
# a realistic step: the cloth swinging down, 10 steps after release from horizontal
sim = cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(), cs.Pin([0, n - 1])])
sim.run(10)
problem = sim.problem()
x0 = problem.x
x_star = NewtonSolver(model).solve(problem).x          # the exact implicit Euler step
scale = np.linalg.norm(x_star - x0)
lg_err, nt_err = [], []
for k in range(1, 41):
    lg_err.append(np.linalg.norm(LocalGlobalSolver(model, iterations=k)
                                 .solve(problem).x - x_star) / scale)
for k in range(1, 9):
    nt_err.append(np.linalg.norm(NewtonSolver(model, iterations=k, tolerance=None)
                                 .solve(problem).x - x_star) / scale)

# %%
# Local/global: monotone, steady linear decrease; Newton: quadratic once close.
assert all(b <= a * (1 + 1e-9) for a, b in zip(lg_err, lg_err[1:]))
assert lg_err[-1] < 0.5 * lg_err[9] and nt_err[-1] < 1e-12
error_after_10 = lg_err[9]
print(f"relative error after 10 local/global iterations: {error_after_10:.3e}")

fig, ax = plt.subplots(figsize=(5, 3.2))
ax.semilogy(range(1, 41), lg_err, label="local/global")
ax.semilogy(range(1, 9), np.maximum(nt_err, 1e-17), "o-", label="Newton")
ax.set(xlabel="iterations", ylabel="‖x_k − x*‖ / ‖x* − x_n‖")
ax.legend()
fig.tight_layout()
