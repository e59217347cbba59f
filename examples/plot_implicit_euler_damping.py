"""
Implicit Euler damps, and more so with a larger step
====================================================

For one mass on a linear spring (ω² = k / m) implicit Euler multiplies the amplitude by
(1 + ω² h²)^(−1/2) every step: the motion decays although there is no damping force. We
simulate a single spring with clothsim (exact solve: Newton, which is exact for a linear
spring) and compare the decay with the formula for three time steps.
"""

import matplotlib.pyplot as plt
import numpy as np

import clothsim as cs

k, m, r = 100.0, 1.0, 1.0
omega = np.sqrt(k / m)
T = 2.0


def simulate(h):
    mesh = cs.Mesh(np.array([[0.0, 0.0, 0.0], [r + 0.1, 0.0, 0.0]]), strands=[[0, 1]])
    springs = cs.Springs(spring_vertices=[[0, 1]], spring_stiffness=k, spring_rest_length=r,
                         spring_family=0)
    model = cs.Model.build(mesh, springs, vertex_mass=m)
    sim = cs.Simulation(model, h=h, effects=[cs.Pin([0])], solver="newton", iterations=30,
                        tolerance=1e-13)
    steps = int(round(T / h))
    amplitude = [0.1]
    for _ in range(steps):
        sim.step()
        x, v = sim.state.positions[1, 0] - r, sim.state.velocities[1, 0]
        amplitude.append(np.hypot(x, v / omega))      # oscillator "energy radius"
    return np.arange(steps + 1) * h, np.array(amplitude)


fig, ax = plt.subplots(figsize=(5, 3.2))
final = {}
for h in (0.01, 0.03, 0.1):
    t, a = simulate(h)
    final[h] = a[-1]
    predicted = 0.1 * (1 + omega ** 2 * h ** 2) ** (-np.arange(len(t)) / 2)
    # the measured decay matches (1 + ω²h²)^(-1/2) per step
    assert np.allclose(a, predicted, rtol=1e-6), h
    ax.semilogy(t, a, label=f"h = {h} s")
    ax.semilogy(t, predicted, "k:", lw=0.8)
    print(f"h = {h}: amplitude after {T} s = {a[-1]:.2e} m (started at 0.1 m)")

# %%
# A larger step damps more, at the same simulated time.
assert final[0.1] < final[0.03] < final[0.01]
ax.set(xlabel="time [s]", ylabel="amplitude [m]",
       title="one spring, ω = 10 rad/s (dotted: (1 + ω²h²)^(-n/2))")
ax.legend()
fig.tight_layout()
