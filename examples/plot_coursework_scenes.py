"""
The coursework scenes
=====================

clothsim ships scenes that read the mass-spring assignment's own files (A. Jacobson's
mass-spring-systems assignment: a single spring, a chain, a net, a flag, a skirt). The files
are not part of clothsim: they are read from the data directory, ``$CLOTHSIM_DATA`` or
``../shared/data/jacobson-a8`` beside the repository (:func:`clothsim.scene.data_dir`).
This lesson runs the three small ones and checks that implicit Euler only loses energy.
When the data is absent it says so and stops.
"""

import matplotlib.pyplot as plt
import numpy as np

from clothsim.energy import gravity_energy, kinetic_energy, spring_energy
from clothsim.plotting import draw
from clothsim.scene import data_dir, load_scene

SCENES = ["jacobson-spring", "jacobson-chain", "jacobson-net"]
G = np.array([0.0, -9.8, 0.0])

if not data_dir().is_dir():
    print(f"coursework data not found in {data_dir()}; set CLOTHSIM_DATA to run this lesson")
    fig, ax = plt.subplots(figsize=(4, 1))
    ax.text(0.5, 0.5, "coursework data not found", ha="center", va="center")
    ax.set_axis_off()
else:
    fig, axes = plt.subplots(1, len(SCENES), figsize=(10, 3.6))
    for ax, name in zip(axes, SCENES):
        scene = load_scene(name)
        model = scene.build_model()
        sim = scene.build_simulation(model)
        pinned = sim.pinned_vertices(0.0)
        x_pins = sim.state.positions[pinned].copy()

        def total_energy(state, model=model):
            return (kinetic_energy(model, state.velocities)
                    + spring_energy(model, state.positions)
                    + gravity_energy(model, state.positions, G))

        e0 = total_energy(sim.state)
        sim.run(60)
        e1 = total_energy(sim.state)
        print(f"{name}: {model.vertex_count} vertices, {model.spring_count} springs; "
              f"energy {e0:.3f} J -> {e1:.3f} J after 2 s")
        # the pins hold (the assignment's penalty w = 1e10 N/m gives by load / w, far below
        # a micrometre), and implicit Euler dissipates: never more energy than at the start
        assert np.abs(sim.state.positions[pinned] - x_pins).max() < 1e-6
        assert e1 < e0
        draw(ax, model.mesh, sim.state.positions, effects=sim.effects, t=sim.state.time)
        ax.set_title(name, fontsize=9)
    fig.tight_layout()
