"""
Error against wall time: local/global and Newton (the paper's Fig. 1)
=====================================================================

One implicit Euler step of a falling cloth hinged along one edge (625 vertices), solved by
local/global and by Newton's method. Plotted against *wall time*, not iterations:
a local/global iteration is two triangular solves with a matrix factored once, a Newton
iteration assembles and factors a new Hessian. So local/global is ahead for the first digits
(a visually acceptable answer costs a fraction of one Newton iteration), and Newton, which
converges quadratically, wins for tight tolerances.
"""

import time

import matplotlib.pyplot as plt
import numpy as np

from clothsim.gallery import swing
from clothsim.solvers import LocalGlobalSolver, NewtonSolver

sim = swing(25)                        # 625 vertices; released horizontal, hinged on one edge
sim.run(5)                             # a step in the middle of the fall
problem, model = sim.problem(), sim.model
x_star = NewtonSolver(model, iterations=50, tolerance=1e-13).solve(problem).x
x_init = problem.initial_guess()
scale = np.linalg.norm(x_star - x_init)


def error(x):
    return np.linalg.norm(x - x_star) / scale


# %%
# Local/global: time every iterate (the factorization is done before the clock starts, as
# in a simulation where it is reused every step).
lg = LocalGlobalSolver(model)
lg.system(problem)
lg_time, lg_err = [0.0], [1.0]
start = time.perf_counter()
for it in lg.iterates(problem):
    if it.k > 0:
        lg_time.append(time.perf_counter() - start)
        lg_err.append(error(it.x))
    if it.k == 3000 or (it.k > 0 and lg_time[-1] > 2.0):
        break

# %%
# Newton: k iterations from scratch, for k = 1 … 5 (each run timed in full).
nt_time, nt_err = [0.0], [1.0]
for k in range(1, 6):
    start = time.perf_counter()
    x = NewtonSolver(model, iterations=k, tolerance=None).solve(problem).x
    nt_time.append(time.perf_counter() - start)
    nt_err.append(error(x))

# %%
# The facts. Before Newton's first iterate exists, local/global has already removed a good
# part of the error (the first digits are cheap); Newton then converges quadratically to
# rounding while local/global, linear, is still far from it at the same wall time.


def lg_error_at(t):
    return lg_err[int(np.searchsorted(lg_time, t, side="right")) - 1]


print(f"one Newton iteration: {nt_time[1] * 1e3:.1f} ms; local/global by then: "
      f"{lg_error_at(nt_time[1]):.2e}; Newton after 5: {nt_err[5]:.1e} in "
      f"{nt_time[5] * 1e3:.0f} ms, local/global by then {lg_error_at(nt_time[5]):.1e}")
assert lg_error_at(0.5 * nt_time[1]) < 0.9          # progress while Newton has no answer
assert nt_err[5] < 1e-9                               # Newton: quadratic, to rounding
assert lg_error_at(nt_time[5]) > 1e-4                 # local/global: linear, still far

fig, ax = plt.subplots(figsize=(5.5, 3.4))
t0 = lg_time[1]                       # log axes: start at the first local/global iterate
ax.loglog(np.array(lg_time[1:]) * 1e3, lg_err[1:], label="local/global")
# Newton's best answer so far: none (error 1) until its first iterate is done
ax.loglog(np.r_[t0, nt_time[1:]] * 1e3, np.maximum(np.r_[1.0, nt_err[1:]], 1e-16), "o-",
          drawstyle="steps-post", label="Newton")
ax.set(xlabel="wall time [ms]", ylabel="‖x − x*‖ / ‖x₀ − x*‖",
       title="one step, 625 vertices: error against time")
ax.grid(True, which="both", alpha=0.3)
ax.legend()
fig.tight_layout()
