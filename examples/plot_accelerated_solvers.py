"""
Accelerated solvers
===================

Local/global converges linearly; its follow-ups accelerate it while keeping its cheap
iteration. Chebyshev semi-iterative acceleration (H. Wang, ACM TOG 34(6), 2015) blends each
iterate with the two previous ones using an estimate ρ of the spectral radius of the
local/global iteration (:func:`clothsim.solvers.estimate_spectral_radius`).

To add another accelerated solver to this lesson (Anderson acceleration, L-BFGS), append
its name to ``METHODS`` below: every solver yields its iterates the same way
(:meth:`clothsim.solvers.Solver.iterates`).
"""

import matplotlib.pyplot as plt
import numpy as np

from clothsim.gallery import curtain
from clothsim.solvers import make_solver

METHODS = ["local-global", "chebyshev"]      # add "anderson", "lbfgs" where available

sim = curtain(15, k=2000.0)
sim.run(5)
problem, model = sim.problem(), sim.model
# Both methods approach the same stationary point of g: the converged local/global step.
# (On this symmetric curtain it is a saddle of g; Newton, which never stops at a saddle,
# finds a buckled minimum elsewhere: docs/accuracy.md.)
x_star = make_solver("local-global", model, iterations=20000, tolerance=1e-13).solve(problem).x
scale = np.linalg.norm(x_star - problem.initial_guess())

errors = {}
for method in METHODS:
    solver = make_solver(method, model)
    err = []
    for it in solver.iterates(problem):
        k, x = (it.k, it.x) if hasattr(it, "x") else it[:2]   # an Iterate (or a tuple)
        err.append(np.linalg.norm(x - x_star) / scale)
        if k == 100:
            break
    errors[method] = np.array(err)
    print(f"{method:14s} error after 100 iterations: {err[-1]:.2e}")

# %%
# Same cost per iteration, far fewer iterations for the same error.
assert errors["chebyshev"][-1] < 1e-2 * errors["local-global"][-1]

fig, ax = plt.subplots(figsize=(5, 3.2))
for method, err in errors.items():
    ax.semilogy(np.maximum(err, 1e-17), label=method)
ax.set(xlabel="iteration", ylabel="‖x_k − x*‖ / ‖x₀ − x*‖", title="one step, 225 vertices")
ax.legend()
fig.tight_layout()
