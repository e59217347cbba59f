"""
Checking a port against clothsim
================================

clothsim exists partly to regression-check other implementations. ``liu13-port`` holds what
the paper authors' own C++ program computes for its default scene (a 21 × 21 sheet, two
penalty pins, 10 local/global iterations per frame): its initial positions, springs and
61 frames of positions. We rebuild the same model here from those files, take one step with
clothsim from the same state, and compare with the port's frame 1.

The data ships with clothsim (the data set ``liu13-port``, :mod:`clothsim.datasets`,
unpacked on first use).
"""

import matplotlib.pyplot as plt
import numpy as np

import clothsim as cs
from clothsim import datasets
from clothsim.plotting import draw
from clothsim.solvers import LocalGlobalSolver, StepProblem

port = datasets.locate("liu13-port") / "default-scene"

# %%
# The model, exactly as the port builds it: springs (type 1) with their stiffness and
# rest length, two penalty "attachments" (type 0), uniform masses, gravity M (0, −100, 0).
x0 = np.loadtxt(port / "x0.txt").reshape(-1, 3)
triangles = np.loadtxt(port / "triangles.txt", dtype=np.int64)
table = np.loadtxt(port / "springs.txt", comments="#")
springs, attach = table[table[:, 0] == 1], table[table[:, 0] == 0]
mesh = cs.Mesh(x0, triangles)
model = cs.Model.build(mesh, cs.Springs(spring_vertices=springs[:, 1:3].astype(int),
                                        spring_stiffness=springs[:, 3],
                                        spring_rest_length=springs[:, 4],
                                        spring_family=0), total_mass=1.0)
positions = np.loadtxt(port / "positions.txt").reshape(61, -1, 3)
h = 0.0333
problem = StepProblem(h=h, x=positions[0], v=np.zeros_like(x0),
                      f_ext=model.vertex_mass[:, None] * [0.0, -100.0, 0.0],
                      anchor_vertices=attach[:, 1].astype(int),
                      anchor_positions=x0[attach[:, 1].astype(int)],
                      anchor_stiffness=attach[:, 3])

# %%
# One step, 10 iterations from y = x + h v, as the port does it.
x1 = LocalGlobalSolver(model, iterations=10).solve(problem).x
difference = np.abs(x1 - positions[1]).max()
print(f"largest difference from the port's frame 1: {difference:.1e} m "
      f"(the step moved the sheet by {np.abs(positions[1] - positions[0]).max():.2f} m)")
assert difference < 1e-9

fig, axes = plt.subplots(1, 2, figsize=(8, 4))
draw(axes[0], mesh, positions[10])
axes[0].set_title("the port, frame 10", fontsize=9)
axes[1].semilogy(np.abs(x1 - positions[1]).max(axis=1), ".")
axes[1].set(xlabel="vertex", ylabel="|clothsim − port| [m]", title="one step")
fig.tight_layout()
