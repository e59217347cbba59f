"""Check NVIDIA newton's cloth solvers (VBD, XPBD) step by step against clothsim.

A springs-only 11 x 11 cloth is built in newton (particles and springs with
``newton.ModelBuilder``), stepped by ``newton.solvers.SolverVBD`` or ``SolverXPBD``, and
the same model is exported exactly (every float32 number newton uses, written so that the
float64 clothsim reads is that float32 value) as a clothsim scene of shape ``"files"``. Each
of newton's steps is then judged by :func:`clothsim.ports.check.check_steps`.

Needs the ``newton`` extra (``pip install -e ".[newton]"``); runs on the CPU.

    python examples/engines/newton_vbd.py            # the checks of docs/howto/check-an-engine.md
    python examples/engines/newton_vbd.py --steps 5  # fewer steps

newton's colouring pitfall: ``ModelBuilder.color()`` builds its graph from triangles,
bending edges and tetrahedra only, so for a springs-only model it puts every particle in
one colour and VBD's Gauss-Seidel sweep becomes a Jacobi sweep. :func:`spring_colouring`
colours the particles so that no spring joins two of one colour, and
:func:`build_model` hands it to ``ModelBuilder.set_coloring`` (SolverVBD reads
``model.particle_color_groups`` and ``model.particle_colors``).
"""

from __future__ import annotations

import argparse
import tempfile
import warnings
from pathlib import Path

import numpy as np

from clothsim.errors import ClothsimWarning

#: The cloth: GRID x GRID particles SPACING apart, hanging in the x-z plane (newton's up
#: axis is z), its two top corners pinned (mass 0).
GRID = 11
SPACING = 0.1  # m
PARTICLE_MASS = 0.01  # kg
KE = 1000.0  # N/m, structural and shear springs
KE_BEND = 100.0  # N/m, bending springs (every other particle)
DT = 1.0 / 60.0  # s


def grid_springs(n: int = GRID) -> list[tuple[int, int, float]]:
    """Structural, shear and bending springs of an n x n grid (particle i * n + j).

    Parameters
    ----------
    n : int
        Particles per side.

    Returns
    -------
    list of (int, int, float)
        (a, b, stiffness [N/m]) per spring.
    """
    out = []
    for i in range(n):
        for j in range(n):
            p = i * n + j
            if j + 1 < n:
                out.append((p, p + 1, KE))
            if i + 1 < n:
                out.append((p, p + n, KE))
            if i + 1 < n and j + 1 < n:
                out.append((p, p + n + 1, KE))
                out.append((p + 1, p + n, KE))
            if j + 2 < n:
                out.append((p, p + 2, KE_BEND))
            if i + 2 < n:
                out.append((p, p + 2 * n, KE_BEND))
    return out


def spring_colouring(count: int, springs) -> list[np.ndarray]:
    """Greedy colouring of the particles: no spring joins two particles of one colour.

    Parameters
    ----------
    count : int
        Number of particles.
    springs : iterable of (int, int, ...)
        The springs' particle pairs.

    Returns
    -------
    list of ndarray of int
        The particles of each colour (``ModelBuilder.set_coloring``'s argument).
    """
    neighbours = [set() for _ in range(count)]
    for a, b, *_ in springs:
        neighbours[a].add(b)
        neighbours[b].add(a)
    colour = np.full(count, -1)
    for p in sorted(range(count), key=lambda q: -len(neighbours[q])):
        used = {colour[q] for q in neighbours[p]}
        colour[p] = next(c for c in range(count) if c not in used)
    return [np.flatnonzero(colour == c) for c in range(colour.max() + 1)]


def build_model(kd: float = 0.0, colouring: str = "springs"):
    """The newton model: GRID x GRID particles, springs, two pinned corners.

    Parameters
    ----------
    kd : float
        Damping coefficient of every spring [N·s/m] (newton's ``spring_kd``).
    colouring : {"springs", "newton"}
        ``"springs"``: :func:`spring_colouring`; ``"newton"``: ``ModelBuilder.color()``
        (the pitfall: one colour for a springs-only model).

    Returns
    -------
    newton.Model
    """
    import newton

    builder = newton.ModelBuilder()  # up axis z, gravity (0, 0, -9.81) m/s²
    n = GRID
    top = {(n - 1) * n, n * n - 1}  # row n - 1 is at the top
    for i in range(n):
        for j in range(n):
            p = i * n + j
            builder.add_particle((j * SPACING, 0.0, 1.0 + i * SPACING), (0.0, 0.0, 0.0),
                                 0.0 if p in top else PARTICLE_MASS, radius=0.0)
    springs = grid_springs(n)
    for a, b, ke in springs:
        builder.add_spring(a, b, ke, kd, control=0.0)
    if colouring == "springs":
        builder.set_coloring(spring_colouring(n * n, springs))
    else:
        builder.color()
    return builder.finalize(device="cpu")


def simulate(model, solver: str = "vbd", iterations: int = 1000, steps: int = 10):
    """Step the model with newton's solver; record x_k and v_k of every frame.

    Parameters
    ----------
    model : newton.Model
    solver : {"vbd", "xpbd"}
    iterations : int
        The solver's iterations per step.
    steps : int
        Steps taken.

    Returns
    -------
    positions, velocities : ndarray, shape (steps + 1, n, 3), float32
        [m] and [m/s]; frame 0 is the initial state.
    """
    import newton

    cls = newton.solvers.SolverVBD if solver == "vbd" else newton.solvers.SolverXPBD
    sim = cls(model, iterations=iterations)
    s0, s1 = model.state(), model.state()
    control = model.control()
    xs, vs = [s0.particle_q.numpy().copy()], [s0.particle_qd.numpy().copy()]
    for _ in range(steps):
        s0.clear_forces()
        sim.step(s0, s1, control, None, DT)
        s0, s1 = s1, s0
        xs.append(s0.particle_q.numpy().copy())
        vs.append(s0.particle_qd.numpy().copy())
    return np.array(xs), np.array(vs)


def _exact(v) -> str:
    """A float32 value written so that it reads back as exactly that value (in float64)."""
    return repr(float(np.float32(v)))


def export_scene(model, folder, method: str = "newton", iterations: int = 50) -> Path:
    """Write the newton model as a clothsim scene (shape "files") and its data files.

    Every number is newton's float32 value, written exactly: initial positions, masses
    (mass 0 = pinned exactly, as newton's inverse mass 0), spring pairs, stiffness, rest
    length (newton computes it in float32) and damping, gravity (newton's per-world vector,
    a force m g) and h (the float32 dt newton's kernels use).

    Parameters
    ----------
    model : newton.Model
    folder : str or Path
        Where scene.toml, vertices.txt, masses.txt and springs.txt are written.
    method, iterations : str, int
        clothsim's solver for the step it compares with (converged by default).

    Returns
    -------
    Path
        The scene file.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    x = model.particle_q.numpy()
    (folder / "vertices.txt").write_text(
        "".join(" ".join(_exact(c) for c in p) + "\n" for p in x))
    masses = model.particle_mass.numpy()
    (folder / "masses.txt").write_text("".join(_exact(m) + "\n" for m in masses))
    pairs = model.spring_indices.numpy().reshape(-1, 2)
    cols = zip(pairs, model.spring_stiffness.numpy(), model.spring_rest_length.numpy(),
               model.spring_damping.numpy())
    (folder / "springs.txt").write_text("".join(
        f"{a} {b} {_exact(k)} {_exact(r)} {_exact(c)}\n" for (a, b), k, r, c in cols))
    g = model.gravity.numpy()[0]
    scene = f"""# newton's model, exported by examples/engines/newton_vbd.py
[scene]
name = "newton-springs"
frames = 10
h = {_exact(DT)}

[cloth]
shape = "files"
vertices = "vertices.txt"
vertex_mass = "masses.txt"

[springs]
table = "springs.txt"
columns = ["a", "b", "stiffness", "rest", "damping"]

[solver]
method = "{method}"
iterations = {iterations}

[[effects]]
kind = "gravity"
acceleration = [{", ".join(_exact(c) for c in g)}]
"""
    path = folder / "scene.toml"
    path.write_text(scene)
    return path


def check(solver: str = "vbd", iterations: int = 1000, steps: int = 10, kd: float = 0.0,
          colouring: str = "springs", folder=None):
    """Run newton and check every step with clothsim (float32 tolerances).

    Parameters
    ----------
    solver, iterations, steps, kd, colouring
        As :func:`simulate` and :func:`build_model`.
    folder : str or Path, optional
        Where the scene is written (default: a temporary folder).

    Returns
    -------
    report : clothsim.ports.check.CheckReport
    gap : float
        Step 0 -> 1: distance [m] between clothsim's answer and the minimizer Newton's
        method reaches from newton's answer (about 1e-16 m: newton's answer lies in the basin
        of clothsim's minimizer, i.e. it is heading there).
    """
    from clothsim.ports.check import as_simulation, check_steps
    from clothsim.ports.judge import refine
    from clothsim.scene import load_scene
    from clothsim.simulation import State

    model = build_model(kd=kd, colouring=colouring)
    xs, vs = simulate(model, solver, iterations, steps)
    with tempfile.TemporaryDirectory() as tmp:
        scene = load_scene(export_scene(model, folder or tmp))
        report = check_steps(scene, xs, vs, precision="float32")
        sim = as_simulation(scene)
        sim.state = State(xs[0].astype(float), vs[0].astype(float), 0.0, 0)
        problem, step_model = sim.problem(sim.state), sim.step_model(sim.state)
        sim.step()
        x_min = refine(step_model, problem, xs[1].astype(float))
        gap = float(np.linalg.norm(x_min - sim.state.positions, axis=1).max())
    return report, gap


def save(folder, iterations=(200, 1000), steps: int = 10) -> Path:
    """Write the exported scene and VBD's trajectories, so they can be checked without newton.

    ``folder/scene.toml`` (with its data files) and ``folder/vbd-K.npz`` per iteration count
    K, holding newton's float32 ``positions`` and ``velocities`` (steps + 1 frames). The copy
    in examples/engines/newton-springs is this function's output; tests/ports checks it.

    Parameters
    ----------
    folder : str or Path
    iterations : sequence of int
        VBD's iterations per step, one trajectory each.
    steps : int
        Steps per trajectory.

    Returns
    -------
    Path
        The scene file.
    """
    model = build_model()
    path = export_scene(model, folder)
    for k in iterations:
        xs, vs = simulate(model, "vbd", k, steps)
        np.savez_compressed(Path(folder) / f"vbd-{k}.npz", positions=xs, velocities=vs)
    return path


CASES = [  # (label, solver, iterations, spring damping kd [N·s/m], colouring)
    ("VBD, 1000 iterations", "vbd", 1000, 0.0, "springs"),
    ("VBD, 1000 iterations, kd = 2", "vbd", 1000, 2.0, "springs"),
    ("VBD, 200 iterations", "vbd", 200, 0.0, "springs"),
    ("VBD, 10 iterations", "vbd", 10, 0.0, "springs"),
    ("VBD, 1000 iterations, ModelBuilder.color()", "vbd", 1000, 0.0, "newton"),
    ("VBD, 10 iterations, ModelBuilder.color()", "vbd", 10, 0.0, "newton"),
    ("XPBD, 2 iterations (newton's default)", "xpbd", 2, 0.0, "springs"),
    ("XPBD, 10 iterations", "xpbd", 10, 0.0, "springs"),
]


def main(argv=None) -> None:
    """Print the summary of each case of :data:`CASES` (docs/howto/check-an-engine.md)."""
    import warp as wp

    wp.config.log_level = wp.LOG_WARNING  # no banner or kernel-load lines
    import newton

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=10, help="steps per case (default 10)")
    ap.add_argument("--save", metavar="DIR", default=None,
                    help="only write the scene and VBD's 200- and 1000-iteration runs to DIR")
    args = ap.parse_args(argv)
    if args.save:
        print(f"written: {save(args.save, steps=args.steps)}")
        return
    warnings.simplefilter("ignore", ClothsimWarning)  # Newton from a diverged XPBD answer
    colours = spring_colouring(GRID * GRID, grid_springs())
    print(f"newton {newton.__version__}, warp {wp.__version__}; {GRID}x{GRID} particles, "
          f"{len(grid_springs())} springs, h = {_exact(DT)} s, {args.steps} steps")
    print(f"colours: {len(colours)} (spring_colouring), "
          f"{len(build_model(colouring='newton').particle_color_groups)} (ModelBuilder.color())")
    for label, solver, iterations, kd, colouring in CASES:
        report, gap = check(solver, iterations, args.steps, kd, colouring)
        print(f"{label}: {report.summary()}")
        if not report.passed:
            print(f"    step 0 -> 1: Newton's method from newton's answer reaches a minimizer "
                  f"{gap:.1e} m from clothsim's answer")


if __name__ == "__main__":
    main()
