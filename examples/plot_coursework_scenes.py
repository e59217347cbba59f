"""
The coursework scenes
=====================

clothsim ships scenes that read the mass-spring assignment's own files (A. Jacobson's
mass-spring-systems assignment: a single spring, a chain, a net, a flag, a skirt). The files
are third party, not part of clothsim: the first use downloads them from the assignment's
repository, each checked against its pinned SHA-256 (``clothsim data fetch jacobson-a8``
does it now; :mod:`clothsim.datasets`). This lesson runs the three small ones and checks
that implicit Euler only loses energy. Where the files cannot be got (offline), it runs
scenes of their format made here instead, written as JSON + OBJ by
:func:`clothsim.io.assignment.write_assignment`: the same spring and chain, and a smaller
net, read and run by the same code with the assignment's settings.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from clothsim import datasets
from clothsim.energy import gravity_energy, kinetic_energy, spring_energy
from clothsim.io.assignment import write_assignment
from clothsim.plotting import draw
from clothsim.scene import load_scene

G = np.array([0.0, -9.8, 0.0])


def scenes_of_the_same_format(folder: Path) -> list[Path]:
    """The assignment's single spring and chain (k = 500 N/m, 1 kg per vertex), and a 7 x 7
    net of strands (k = 300 N/m) pinned at four points, as JSON + OBJ files."""
    chain = np.column_stack([np.linspace(0.0, 1.0, 10), np.zeros(10), np.zeros(10)])
    i, j = (a.ravel() for a in np.meshgrid(np.arange(7), np.arange(7)))
    net = np.column_stack([i / 3 - 1, np.zeros(49), j / 3 - 1])
    v = 7 * j + i
    strands = [[a, a + 1] for a in v[i < 6]] + [[a, a + 7] for a in v[j < 6]]
    return [
        write_assignment(folder / "single-spring-horizontal.json", chain[[0, 9]], [[0, 1]],
                         k=500.0, m=1.0, b=[0]),
        write_assignment(folder / "horizontal-chain.json", chain,
                         [[a, a + 1] for a in range(9)], k=500.0, m=1.0, b=[0, 9]),
        write_assignment(folder / "net.json", net, strands, k=300.0, m=1.0,
                         b=[0, 6, 42, 48]),
    ]


try:
    datasets.locate("jacobson-a8")  # downloaded on first use
    SCENES = ["jacobson-spring", "jacobson-chain", "jacobson-net"]
except datasets.DataUnavailableError as exc:
    print(f"the assignment's files cannot be got here ({str(exc).split(';')[0]}); running "
          "scenes of their format made here instead")
    made_here = tempfile.TemporaryDirectory()
    SCENES = scenes_of_the_same_format(Path(made_here.name))

fig, axes = plt.subplots(1, len(SCENES), figsize=(10, 3.6))
for ax, source in zip(axes, SCENES):
    scene = load_scene(source)
    name = scene.name if isinstance(source, str) else f"{source.name}, made here"
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
if not isinstance(SCENES[0], str):
    made_here.cleanup()
