"""Print the measured figures of the numerical stability suite (docs/stability.md).

Run from the repository root::

    .venv/bin/python -m benchmarks.stability_figures            # everything, ~3–4 min
    .venv/bin/python -m benchmarks.stability_figures --quick    # without the full flag

The figures come from the same ``measure_*`` functions the tests assert on
(:mod:`benchmarks.measure_stability` and :mod:`benchmarks.measure_long_run`, imported by
tests/test_stability_{solver,exact,contact,long}.py), so the table and the tests cannot
drift apart. Cases 7 and 8 re-measure the set-ups of the obstacle tests
(tests/effects/test_effects.py: same cloth, same obstacles, same step counts), written here
from the public API.
"""

from __future__ import annotations

import argparse
import sys
import warnings

import numpy as np

import clothsim as cs

from . import measure_long_run as lo
from . import measure_stability as ms

H = 1 / 30


def grid_model(n: int = 8, *, size: float = 0.5, center=(0.0, 0.3, 0.0), k: float = 200.0):
    """The obstacle tests' cloth: n × n, horizontal, 0.1 kg, uniform masses."""
    mesh = cs.grid(n, n, size=(size, size), center=center, plane="xz")
    springs = cs.grid_springs(mesh, structural=k, shear=k, bending=k / 10)
    return cs.Model.build(mesh, springs, total_mass=0.1, mass_lumping="uniform")


#: The resting-contact cases (tests/effects/test_effects.py::test_resting_contact): obstacle,
#: μ, settling steps, contact mode, iterations per step. Held contacts let the 8×8 cloth's
#: skirt hang free of the sphere (the seed's projection keeps it on the sphere below the
#: equator); the skirt then swings, which implicit Euler with 20 truncated iterations damps
#: only slowly: it drags the vertices in contact along for 450 steps (measured 3e-3 m/s
#: after 300), so this case settles 600.
RESTING = (("plane", 0.0, 60, "hold", 20), ("sphere", 1.0, 600, "hold", 20),
           ("plane", 0.0, 60, "post-solve", 20), ("sphere", 1.0, 150, "post-solve", 20))


def measure_slab_in_simulation() -> dict:
    """tests/effects/test_effects.py::test_thin_box_no_tunnelling_in_simulation, measured."""
    model = grid_model(6, size=0.3, center=(0.0, 0.08, 0.0))
    box = cs.Box((-1, 0, -1), (1, 0.01, 1), thickness=0.0)   # the declared surface exactly
    x = model.mesh.vertices.copy()
    velocity = np.broadcast_to([0.0, -5 * 0.01 / H, 0.0], x.shape).copy()
    sim = cs.Simulation(model, h=H, effects=[box], state=cs.State(x, velocity))
    below, contacts = -np.inf, []
    for _ in range(6):
        sim.step()
        below = max(below, 0.01 - sim.state.positions[:, 1].min())
        contacts.append(len(box.contact_vertices))
    return {"max_below_top": below, "contacts": contacts}


def measure_small_sphere_direct() -> float:
    """tests/effects/test_effects.py::test_small_sphere_no_tunnelling: min |x − c| − R [m]."""
    rng = np.random.default_rng(2)
    c, R, k = np.array([0.1, 0.2, 0.3]), 0.005, 400
    offset = rng.uniform(-0.2 * R, 0.2 * R, (k, 2))
    x0 = c + np.column_stack([offset[:, 0], np.full(k, 0.02), offset[:, 1]])
    out = cs.Sphere(c, R).correct_positions(0.0, cs.State(x0, np.zeros_like(x0)),
                                            x0 + (0.0, -0.05, 0.0))
    return float((np.linalg.norm(out - c, axis=1) - R).min())


def measure_resting_contact(name: str, friction: float, settle: int,
                            contact: str = "hold", iterations: int = 20) -> dict:
    """tests/effects/test_effects.py::test_resting_contact, measured: an 8×8 cloth settled on
    a plane (y = 0) or a sphere (centre 0, radius 0.2 m) for ``settle`` steps, then over one
    more second the max speed [m/s] of all vertices and of those in contact, and the max
    depth inside [m]; ``contact`` is the obstacle's contact mode, ``iterations`` the
    local/global iterations per step."""
    if name == "plane":
        obstacle = cs.Plane((0, 0, 0), (0, 1, 0), friction=friction, contact=contact)
        def depth(x):
            return -x[:, 1]
    else:
        obstacle = cs.Sphere((0, 0, 0), 0.2, friction=friction, contact=contact)
        def depth(x):
            return 0.2 - np.linalg.norm(x, axis=1)
    sim = cs.Simulation(grid_model(center=(0.0, 0.25, 0.0)), h=H,
                        effects=[cs.Gravity(), obstacle], iterations=iterations)
    sim.run(settle)
    speed, inside, touching = 0.0, -np.inf, 0.0
    for _ in range(30):
        sim.step()
        v = np.linalg.norm(sim.state.velocities, axis=1)
        speed = max(speed, v.max())
        if len(obstacle.contact_vertices):
            touching = max(touching, v[obstacle.contact_vertices].max())
        inside = max(inside, depth(sim.state.positions).max())
    return {"max_speed": speed, "max_inside": inside, "max_contact_speed": touching,
            "in_contact": len(np.unique(obstacle.contact_vertices))}


def print_long_run(label: str, r: dict) -> None:
    c, w, q = r["cpu"], r["wall"], r["normalized"]
    print(f"    {label}: {r['vertex_count']} vertices, {r['steps_done']} steps,"
          f" finite={r['finite']},"
          f" max distance to pole {r['max_pole_ratio']:.4f} W (W = {r['width']:.3g} m),"
          f" max |v| {r['max_speed']:.3g} m/s, |t - N h| {r['time_drift']:.1e} s")
    print(f"      step time median {c['median'] * 1e3:.2f} ms CPU /"
          f" {w['median'] * 1e3:.2f} ms wall,"
          f" total {r['wall_total']:.0f} s")
    print(f"      trend per 1000 steps: normalized {q['relative_slope_per_1000']:+.2%}"
          f" (the test's),"
          f" raw CPU {c['relative_slope_per_1000']:+.2%}, wall {w['relative_slope_per_1000']:+.2%};"
          f" last/first chunk normalized {q['last_over_first']:.3f}")
    print("      normalized chunk medians: "
          + " ".join(f"{m:.3f}" for m in q["chunk_medians"]))
    print("      CPU chunk medians [ms]: "
          + " ".join(f"{m * 1e3:.2f}" for m in c["chunk_medians"]))


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="skip the full 31 x 21 flag (10^4 steps, ~2-3 min)")
    args = parser.parse_args([] if argv is None else argv)
    warnings.simplefilter("ignore")
    print("case 1  stiffness sweep (4x4, h=1/30, cap 1000 iterations, tolerance 1e-6)")
    for r in ms.measure_stiffness_sweep():
        print(f"    k={r['k']:.0e}  iterations={r['iterations']:5d}  residual={r['residual']:.2e}"
              f"  warned={bool(r['warnings'])}  finite={r['finite']}")
    print("case 2  max per-step relative energy increase (Newton 1e-12, 20 steps)")
    for h in (1 / 24, 0.1, 1.0):
        r = ms.measure_energy_increase(h)
        print(f"    h={h:.4g}  {r['max_relative_increase']:.2e}  (energy lost"
              f" {r['energy_lost']:.3f} J)")
    print(f"case 3  max relative increase of g-hat over half steps: "
          f"{ms.measure_degenerate_monotone()['max_relative_increase']:.2e}")
    print(f"        zero-rest spring length after 12 steps:"
          f" {ms.measure_zero_rest_collapse():.2e} m")
    for scale in (10.0, 0.01):
        r = ms.measure_release(scale)
        print(f"case 4  scale {scale:g}: start max|l/r-1|={r['start_strain']:.3g} "
              f"-> {r['strain']:.2e} after 200 steps")
    for r in ms.measure_mass_extremes():
        print(f"case 5  m={r['vertex_mass']:.0e} k={r['k']:.0e}: cond1={r['cond']:.3g}")
    print(f"case 6  free fall max error: local-global {ms.measure_free_fall():.2e} m, "
          f"newton {ms.measure_free_fall('newton'):.2e} m")
    print(f"        release vs refactor: {ms.measure_release_vs_refactor():.2e} m")
    r = measure_slab_in_simulation()
    print(f"case 7  slab 0.01 m, 0.05 m per step: max depth below the top"
          f" {r['max_below_top']:.1e} m,"
          f" contacts per step {r['contacts']}")
    print(f"        sphere R=0.005 m, 0.05 m segments: min |x-c| - R = "
          f"{measure_small_sphere_direct():.1e} m")
    for mu in (0.0, 1.0):
        r = ms.measure_sphere_tunnelling(mu, thickness=0.0)
        print(f"        sphere R=0.01 m in a simulation, 0.1 m per step, mu={mu:g}: max depth "
              f"{r['max_depth']:.1e} m, caught {len(r['caught'])} on step 1 at y >= "
              f"{r['caught_height']:.4f} m (free: {r['would_end']:.4f} m), gap "
              f"{r['caught_gap'].max():.1e} m")
    for name, mu, settle, contact, its in RESTING:
        r = measure_resting_contact(name, mu, settle, contact, its)
        print(f"case 8  resting on {name} ({contact}, mu={mu:g}, settle {settle} steps, {its} "
              f"iterations): max |v| over 1 s {r['max_speed']:.1e} m/s, of the "
              f"{r['in_contact']} vertices in contact {r['max_contact_speed']:.1e} m/s, max "
              f"depth inside {r['max_inside']:.1e} m")
    for r in ms.measure_contact_strain():
        print(f"case 8  strain in contact, {r['scene']} {r['resolution']}^2 ({r['contact']}): "
              f"largest spring stretch over the last second {r['max_stretch']:.3f}, "
              f"max depth inside {r['max_inside']:.1e} m, max |v| {r['max_speed']:.2e} m/s "
              f"({r['max_contact_speed']:.2e} in contact), {r['below_equator']} on the sphere "
              f"below its equator")
    print("case 9  long run of the flag scene (h = 1/30 s)")
    print_long_run("coarse 7x5 (the test)", lo.measure_long_run())
    if not args.quick:
        print_long_run("full 31x21", lo.measure_long_run(resolution=None))
    r = ms.measure_invariance()
    print(f"case 10 rotation {r['rotation']:.2e} m; translation"
          f" {r['translation_per_metre']:.2e} m/m")
    print(f"case 11 oscillator max deviation: {ms.measure_oscillator():.2e} m")
    r = ms.measure_convergence_order()
    print(f"case 12 slope {r['slope']:.4f}; errors {[f'{e:.3e}' for e in r['errors']]}")
    print(f"case 13 max |A - A^T| / max |A|: {ms.measure_symmetry():.1e}")


if __name__ == "__main__":
    main(sys.argv[1:])
