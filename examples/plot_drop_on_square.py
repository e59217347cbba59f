"""
The student report's first demo: a cloth dropped on a square
============================================================

The built-in scene ``drop-on-square`` (``.venv/bin/clothsim run`` runs it into
``out/drop-on-square``): a 1 m square cloth, 25 × 25 vertices, falls from 1 m onto a fixed
0.5 m box standing on the floor, h = 1/30 s, each step solved by 30 iterations of
local/global with Anderson acceleration (so that the cloth comes to rest within the scene's
4 s: docs/effects.md, "Coming to rest"). The box and the floor hold the vertices they push
on their contact planes during the next solve (``[contact] mode = "hold"``, the default;
docs/effects.md), so the cloth folds over the box's edges without tearing.
Here we run its first 1.5 s in memory, draw three moments with
:func:`clothsim.plotting.draw`, and compare the seed's projection after the solve.
"""

import matplotlib.pyplot as plt
import numpy as np

from clothsim import energy
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
# The cloth's centre rests on the box top (0.5 m), held its contact thickness above it
# (``thickness = "auto"``: 1.1 × ℓ/√2 = 0.032 m for the spacing ℓ = 1/24 m, so that no
# triangle between a vertex on the top and one on a side cuts the box's edge; see
# docs/effects.md); its corners hang below it.
print(f"contact thickness of the box: {box.margin:.4f} m")
assert abs(box.margin - 1.1 * (1 / 24) / np.sqrt(2)) < 1e-12
centre = np.argmin(np.linalg.norm(model.mesh.vertices[:, [0, 2]], axis=1))
x = frames[45]
assert abs(x[centre, 1] - (box.max[1] + box.margin)) < 0.01
assert x[:, 1].min() < box.max[1] - 0.15               # its corners hang well below it

fig, axes = plt.subplots(1, 3, figsize=(11, 3.8))
for ax, (k, xk) in zip(axes, frames.items()):
    draw(ax, model.mesh, xk, effects=sim.effects, frame_on=np.vstack(list(frames.values())))
    ax.set_title(f"t = {k / scene.fps:.2f} s", fontsize=9)
fig.tight_layout()

# %%
# Every spring stays near its rest length, also over the box's edges. The seed's
# projection after the solve (``[contact] mode = "post-solve"``, here with the seed's 10
# local/global iterations and without the scene's damping) puts a vertex that
# entered through a side face on that face while its neighbour stays on the top: the
# next solve pulls the pair into the box and the projection separates them again, a
# rim of springs stretched to more than twice their length.
seed = load_scene("drop-on-square", ["contact.mode=post-solve", "solver.method=local-global",
                                     "solver.iterations=10", "effects[3].coefficient=0"])
seed = seed.build_simulation(model)
seed.run(45)
rest = model.springs.spring_rest_length
held = energy.spring_lengths(model, x) / rest
projected = energy.spring_lengths(model, seed.state.positions) / rest
print(f"largest stretch at t = 1.5 s: held {held.max():.2f}, projected {projected.max():.2f}")
assert held.max() < 1.3 < 2.0 < projected.max()

fig, axes = plt.subplots(1, 2, figsize=(8, 3.8))
for ax, xk, ratio, label in ((axes[0], x, held, "held (default)"),
                             (axes[1], seed.state.positions, projected, "post-solve (seed)")):
    draw(ax, model.mesh, xk, effects=sim.effects)
    ax.set_title(f"{label}: largest stretch {ratio.max():.2f}", fontsize=9)
fig.tight_layout()
