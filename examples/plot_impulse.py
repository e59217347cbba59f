"""
The student report's second demo: a push on a falling cloth
===========================================================

The built-in scene ``impulse``: a square cloth falls; from 0.1 s to 0.4 s a force of 6 N
pushes a disk of radius 15 cm at its centre straight up (an :class:`clothsim.Impulse`
effect). The solver settings are in the scene: local/global, 20 iterations per frame,
h = 1/30 s. We measure how far the disk rises above the surrounding cloth.
"""

import matplotlib.pyplot as plt
import numpy as np

from clothsim.plotting import draw
from clothsim.scene import load_scene

scene = load_scene("impulse")
model = scene.build_model()
sim = scene.build_simulation(model)
push = next(e for e in sim.effects if e.kind == "impulse")
q = model.mesh.vertices - push.center
dist = np.hypot(q[:, 0], q[:, 2])
disk, surrounding = dist <= push.radius, dist >= 2 * push.radius

lift, snapshots = [], {}
for k in range(1, 21):
    sim.step()
    y = sim.state.positions[:, 1]
    lift.append(y[disk].mean() - np.median(y[surrounding]))
    if k in (6, 12):
        snapshots[k] = sim.state.positions.copy()
print(f"largest lift of the disk above the surrounding cloth: {max(lift) * 100:.1f} cm")

# %%
# The push is clearly visible: the disk rises at least 5 cm above the cloth around it.
assert max(lift) >= 0.05

fig = plt.figure(figsize=(11, 3.8))
axes = [fig.add_subplot(1, 3, i + 1) for i in range(3)]
for ax, (k, xk) in zip(axes, snapshots.items()):
    draw(ax, model.mesh, xk, effects=sim.effects)
    ax.set_title(f"t = {k / scene.fps:.2f} s", fontsize=9)
axes[2].plot(np.arange(1, 21) / scene.fps, np.array(lift) * 100)
axes[2].set(xlabel="time [s]", ylabel="disk above surroundings [cm]")
fig.tight_layout()
