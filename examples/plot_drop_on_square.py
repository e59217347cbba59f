"""
The student report's first demo: a cloth dropped on a square
============================================================

The built-in scene ``drop-on-square`` (``.venv/bin/clothsim run`` runs it into
``out/drop-on-square``): a 1 m square cloth, 25 × 25 vertices, falls from 1 m onto a fixed
0.5 m box standing on the floor, 10 local/global iterations per frame at h = 1/30 s. The box
and the floor act after each solve, as projections (see the lesson on collisions). Here we
run its first 1.5 s in memory and draw three moments with :func:`clothsim.plotting.draw`.
"""

import matplotlib.pyplot as plt
import numpy as np

from clothsim.plotting import draw
from clothsim.scene import load_scene

scene = load_scene("drop-on-square")
model = scene.build_model()
sim = scene.build_simulation(model)
box = next(e for e in sim.effects if e.kind == "box")
frames = {0: sim.state.positions.copy()}
for k in range(1, 46):
    sim.step()
    x = sim.state.positions
    inside = np.all((x > box.min + 1e-9) & (x < box.max - 1e-9), axis=1)
    assert not inside.any(), k                       # nothing ever inside the box
    if k in (12, 45):
        frames[k] = x.copy()

# %%
# The cloth's centre rests on the box top (0.5 m); its corners hang below it.
centre = np.argmin(np.linalg.norm(model.mesh.vertices[:, [0, 2]], axis=1))
x = frames[45]
assert abs(x[centre, 1] - box.max[1]) < 0.01
assert x[:, 1].min() < 0.3

fig, axes = plt.subplots(1, 3, figsize=(11, 3.8))
for ax, (k, xk) in zip(axes, frames.items()):
    draw(ax, model.mesh, xk, effects=sim.effects, frame_on=np.vstack(list(frames.values())))
    ax.set_title(f"t = {k / scene.fps:.2f} s", fontsize=9)
fig.tight_layout()
