"""The numerical stability suite's measurements (docs/stability.md), shared by its tests
(tests/test_stability_{solver,exact,contact}.py assert on them) and by
``python -m benchmarks.stability_figures`` (prints them), so the two cannot drift apart.

Every ``measure_*`` function builds its scene from the public API, runs it and returns plain
numbers (floats, dicts of floats); none asserts anything. The long run of the flag scene
is in :mod:`benchmarks.measure_long_run`.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.sparse as sp
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

import clothsim as cs
from clothsim import energy, matrices
from clothsim.effects import Sphere
from clothsim.errors import ConvergenceWarning
from clothsim.gallery import GRAVITY
from clothsim.gallery import grid_cloth as make_grid_model
from clothsim.solvers import LocalGlobalSolver, NewtonSolver, augmented_objective

# ==== solver: stiffness, energy, degenerate springs, extreme stretch, masses ==========
STIFFNESSES = [1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8]


# -- case 1: stiffness sweep -------------------------------------------------------------------
def one_step(k: float, *, iterations: int, tolerance: float = 1e-6):
    """One step of a 4 × 4 horizontal cloth pinned at two corners, h = 1/30 s."""
    model = make_grid_model(4, k=k)
    sim = cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(GRAVITY), cs.Pin([0, 3])],
                        iterations=iterations, tolerance=tolerance)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ConvergenceWarning)
        record = sim.step()
    return sim, record, [w for w in caught if issubclass(w.category, ConvergenceWarning)]


def measure_stiffness_sweep(iterations: int = 1000) -> list[dict]:
    """Iterations to reach a relative residual of 1e-6 for k = 1e2 … 1e8 [N/m]."""
    rows = []
    for k in STIFFNESSES:
        sim, rec, caught = one_step(k, iterations=iterations)
        rows.append({"k": k, "iterations": rec.iterations, "residual": rec.residual,
                     "converged": rec.converged, "warnings": [str(w.message) for w in caught],
                     "finite": bool(np.isfinite(sim.state.positions).all())})
    return rows


# -- case 2: large time steps, energy --------------------------------------------------------
def total_energy(model, x, v) -> float:
    """Kinetic + spring + gravity energy [J]."""
    return (energy.kinetic_energy(model, v) + energy.spring_energy(model, x)
            + energy.gravity_energy(model, x, GRAVITY))


def measure_energy_increase(h: float, steps: int = 20) -> dict:
    """Largest per-step energy change / max |E| of a converged (Newton, 1e-12) run."""
    model = make_grid_model(5)
    sim = cs.Simulation(model, h=h, effects=[cs.Gravity(GRAVITY), cs.Pin([0, 4])],
                        solver="newton", iterations=50, tolerance=1e-12)
    E = [total_energy(model, sim.state.positions, sim.state.velocities)]
    for _ in range(steps):
        sim.step()
        E.append(total_energy(model, sim.state.positions, sim.state.velocities))
    E = np.array(E)
    return {"h": h, "max_relative_increase": float(np.max(np.diff(E)) / np.max(np.abs(E))),
            "energy_lost": float(E[0] - E[-1]), "finite": bool(np.isfinite(E).all())}


# -- case 3: coincident vertices and zero rest lengths ---------------------------------------
def degenerate_model():
    """A 4 × 4 grid whose vertex 5 sits on vertex 6 (zero-rest springs 5–6) and whose
    start shape also puts vertex 9 on vertex 10 (a spring with r > 0 and coincident ends)."""
    mesh = cs.grid(4, 4, size=(1.0, 1.0), plane="xz")
    v = mesh.vertices.copy()
    v[5] = v[6]
    mesh = cs.Mesh(v, mesh.triangles, grid_shape=mesh.grid_shape)
    springs = cs.grid_springs(mesh, structural=500.0, shear=500.0, bending=50.0)
    model = cs.Model.build(mesh, springs, total_mass=1.0)
    x0 = v.copy()
    x0[9] = x0[10]
    return model, x0


def measure_degenerate_monotone(steps: int = 5, iterations: int = 20) -> dict:
    """Largest increase of ĝ over any half step (local or global), relative to |ĝ|."""
    model, x0 = degenerate_model()
    assert np.sum(model.springs.spring_rest_length == 0) >= 1
    sim = cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(GRAVITY), cs.Pin([0, 3])],
                        state=cs.State(x0, np.zeros_like(x0)))
    solver = LocalGlobalSolver(model)
    worst = -np.inf
    for _ in range(steps):
        problem = sim.problem()
        x = problem.initial_guess()
        d = solver.local_step(x)
        g_prev = augmented_objective(model, problem, x, d)
        for _ in range(iterations):
            x = solver.global_step(problem, d)
            g_glob = augmented_objective(model, problem, x, d)
            d = solver.local_step(x)
            g_loc = augmented_objective(model, problem, x, d)
            for a, b in ((g_prev, g_glob), (g_glob, g_loc)):
                worst = max(worst, (b - a) / max(abs(a), 1e-300))
            g_prev = g_loc
            assert np.isfinite(x).all() and np.isfinite(d).all()
        sim.state = cs.State(x, (x - sim.state.positions) / sim.h, sim.state.time + sim.h,
                             sim.state.step + 1)
    return {"max_relative_increase": float(worst)}


def measure_zero_rest_collapse(steps: int = 12) -> float:
    """Length [m] of an unloaded zero-rest spring (two 1 kg vertices 1 m apart, k = 1e3 N/m,
    h = 1 s) after ``steps`` steps."""
    mesh = cs.Mesh(np.array([[0.0, 0.0, 0.0], [1.0, 0.3, -0.2]]), strands=[[0, 1]])
    springs = cs.Springs([[0, 1]], [1e3], [0.0], [0])
    model = cs.Model.build(mesh, springs, vertex_mass=[1.0, 1.0])
    sim = cs.Simulation(model, h=1.0)
    sim.run(steps)
    assert np.isfinite(sim.state.positions).all()
    return float(energy.spring_lengths(model, sim.state.positions)[0])


# -- case 4: extreme deformation -------------------------------------------------------------
def measure_release(scale: float, *, seed: int = 1, steps: int = 200) -> dict:
    """Max |l/r − 1| after releasing a 5 × 5 cloth scaled by ``scale`` about its centre and
    jittered (3 % of its size, in 3-D), with velocity damping c = 0.1, h = 1/30 s."""
    from clothsim.effects.damping import Damping

    model = make_grid_model(5)
    rng = np.random.default_rng(seed)
    v = model.mesh.vertices
    c = v.mean(axis=0)
    x0 = c + scale * (v - c + 0.03 * 0.25 * rng.standard_normal(v.shape))
    sim = cs.Simulation(model, h=1 / 30, effects=[Damping("velocity", 0.1)],
                        state=cs.State(x0, np.zeros_like(x0)))
    start = float(np.max(np.abs(energy.spring_strain(model, x0))))
    sim.run(steps)
    x = sim.state.positions
    return {"scale": scale, "start_strain": start, "finite": bool(np.isfinite(x).all()),
            "strain": float(np.max(np.abs(energy.spring_strain(model, x))))}


# -- case 5: mass extremes and conditioning --------------------------------------------------
def exact_condition(model, h):
    A = matrices.system_matrix(model, h).toarray()
    return float(np.linalg.cond(A, 1))


def measure_mass_extremes() -> list[dict]:
    """Exact cond₁(M + h²L), h = 1/30 s, for extreme vertex masses on a 4 × 4 cloth."""
    rows = []
    for mass, k in ((1e-9, 800.0), (1e-9, 1e5), (1e3, 800.0)):
        rows.append({"vertex_mass": mass, "k": k,
                     "cond": exact_condition(make_grid_model(4, k=k, vertex_mass=mass), 1 / 30)})
    return rows


# -- case 13: system matrix and factorization ------------------------------------------------
def measure_symmetry() -> float:
    """max |A − Aᵀ| / max |A| over the scalar and 3n system matrices (with anchors) and a
    Newton Hessian of a deformed cloth."""
    model = make_grid_model(5)
    worst = 0.0
    mats = [matrices.system_matrix(model, 1 / 30),
            matrices.system_matrix(model, 0.1, expand=True, anchor_vertices=[0, 4],
                                   anchor_stiffness=1e5)]
    x = model.mesh.vertices + 0.05 * np.random.default_rng(0).standard_normal((25, 3))
    problem = cs.StepProblem(1 / 30, x, np.zeros_like(x))
    mats.append(NewtonSolver(model).hessian(problem, x))
    for A in mats:
        A = sp.csr_matrix(A)
        worst = max(worst, abs(A - A.T).max() / abs(A).max())
    return float(worst)


# ==== exact solutions: free fall, pin release, invariance, oscillator, order ==========
# -- case 6: free fall, full pinning, pin release --------------------------------------------
def measure_free_fall(solver: str = "local-global", steps: int = 60, h: float = 1 / 30) -> float:
    """Max |x_n − (x_0 + h² g n(n+1)/2)| [m] over all steps of an unpinned, stress-free cloth.

    Implicit Euler with forces m g only: v_{n+1} = v_n + h g, x_{n+1} = x_n + h v_{n+1}; with
    v_0 = 0, v_n = n h g and x_n = x_0 + h² g (1 + 2 + … + n) = x_0 + h² g n(n+1)/2. The
    springs stay at rest length (a translation), so they add nothing.
    """
    model = make_grid_model(5)
    sim = cs.Simulation(model, h=h, effects=[cs.Gravity(GRAVITY)], solver=solver)
    x0 = model.mesh.vertices
    worst = 0.0
    for n in range(1, steps + 1):
        sim.step()
        expected = x0 + h * h * GRAVITY * n * (n + 1) / 2
        worst = max(worst, float(np.abs(sim.state.positions - expected).max()))
    return worst


def measure_release_vs_refactor(steps_pinned: int = 6, steps_after: int = 12) -> float:
    """Max |Δx| [m] between a Pin(release=t_r) run and a pinned run restarted without the pin
    (a fresh solver and factor) at t_r, 12 steps after the release."""
    h = 1 / 30
    t_r = steps_pinned * h
    model = make_grid_model(5, plane="xy")
    a = cs.Simulation(model, h=h, effects=[cs.Gravity(GRAVITY), cs.Pin([20, 24], release=t_r)])
    a.run(steps_pinned + steps_after)
    b = cs.Simulation(model, h=h, effects=[cs.Gravity(GRAVITY), cs.Pin([20, 24])])
    b.run(steps_pinned)
    c = cs.Simulation(model, h=h, effects=[cs.Gravity(GRAVITY)], state=b.state.copy())
    c.run(steps_after)
    assert a.solver.factor_count == 2 and c.solver.factor_count == 1
    assert abs(a.state.time - c.state.time) < 1e-12
    return float(np.abs(a.state.positions - c.state.positions).max())


# -- case 10: rotation and translation invariance ------------------------------------------
def run_scene(R=np.eye(3), t=np.zeros(3), steps: int = 10, solver: str = "local-global"):
    """A 5 × 5 cloth pinned at two corners falling for ``steps`` steps, moved rigidly
    (x → R x + t, gravity → R g)."""
    base = cs.grid(5, 5, size=(1.0, 1.0), plane="xz")
    mesh = cs.Mesh(base.vertices @ R.T + t, base.triangles, grid_shape=base.grid_shape)
    springs = cs.grid_springs(mesh, structural=800.0, shear=800.0, bending=80.0)
    model = cs.Model.build(mesh, springs, total_mass=1.0)
    sim = cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(R @ GRAVITY), cs.Pin([0, 4])],
                        solver=solver)
    sim.run(steps)
    return sim.state.positions


_BASE: dict = {}


def base_positions(solver="local-global"):
    if solver not in _BASE:
        _BASE[solver] = run_scene(solver=solver)
    return _BASE[solver]


def measure_invariance(samples: int = 10, seed: int = 0) -> dict:
    """Worst rotation error [m] and worst translation error / max(1, |t|) over random
    rotations and translations with |t| up to 1e3 m."""
    rng = np.random.default_rng(seed)
    x = base_positions()
    rot, tra = 0.0, 0.0
    for _ in range(samples):
        R = Rotation.random(random_state=rng).as_matrix()
        rot = max(rot, float(np.abs(run_scene(R) - x @ R.T).max()))
        t = rng.standard_normal(3)
        t *= 10.0 ** rng.uniform(-1, 3) / np.linalg.norm(t)
        tra = max(tra, float(np.abs(run_scene(t=t) - (x + t)).max()) / max(1.0, np.linalg.norm(t)))
    return {"rotation": rot, "translation_per_metre": tra}


# -- case 11: analytic oscillator ------------------------------------------------------------
def measure_oscillator(steps: int = 200, *, m=1.0, k=100.0, r=1.0, amplitude=0.5,
                       h=0.05) -> float:
    """Max |x_n − x_n^recurrence| [m] of a pinned 1-D spring over ``steps`` steps.

    Vertex 0 is pinned at a = 0, vertex 1 (mass m) starts at rest at a + r + amplitude on
    the x axis; no gravity. While the spring does not flip (0 < x − a), its energy
    ½ k (x − a − r)² is quadratic in x, so implicit Euler,
    m (x_{n+1} − 2 x_n + x_{n−1}) = −h² k (x_{n+1} − a − r), is the linear recurrence
    (m + h² k) x_{n+1} = m (2 x_n − x_{n−1}) + h² k (a + r), with x_{−1} = x_0 (v_0 = 0).
    """
    a = 0.0
    mesh = cs.Mesh(np.array([[a, 0.0, 0.0], [a + r, 0.0, 0.0]]), strands=[[0, 1]])
    model = cs.Model.build(mesh, cs.mesh_springs(mesh, structural=k), vertex_mass=[m, m])
    x0 = mesh.vertices.copy()
    x0[1, 0] += amplitude
    sim = cs.Simulation(model, h=h, effects=[cs.Pin([0])], state=cs.State(x0, np.zeros((2, 3))))
    prev, cur = x0[1, 0], x0[1, 0]
    worst = 0.0
    for _ in range(steps):
        sim.step()
        prev, cur = cur, (m * (2 * cur - prev) + h * h * k * (a + r)) / (m + h * h * k)
        assert cur - a > 0  # the spring never flips, so the recurrence stays exact
        p = sim.state.positions
        worst = max(worst, abs(p[1, 0] - cur), float(np.abs(p[1, 1:]).max()))
    return worst


# -- case 12: first order in h ---------------------------------------------------------------
def measure_convergence_order(Ns=(25, 50, 100, 200), T: float = 0.25) -> dict:
    """Log-log slope of the error at time T against a fine ODE reference.

    A 3 × 3 hanging cloth (k = 5 N/m, 1 kg, two top corners pinned) under gravity; the
    reference integrates m x'' = −∇E(x) + m g with scipy's DOP853 at rtol = atol = 1e-12.
    Steps solved by local/global to a relative residual of 1e-10.
    """
    mesh = cs.grid(3, 3, size=(1.0, 1.0), plane="xy")
    model = cs.Model.build(mesh, cs.grid_springs(mesh, structural=5.0, shear=5.0, bending=0.5),
                           total_mass=1.0)
    pins = [6, 8]
    m = model.vertex_mass[:, None]

    def rhs(_, z):
        x, v = z[:27].reshape(9, 3), z[27:].reshape(9, 3)
        acc = -energy.spring_gradient(model, x) / m + GRAVITY
        acc[pins] = 0.0
        return np.concatenate([v.ravel(), acc.ravel()])

    z0 = np.concatenate([mesh.vertices.ravel(), np.zeros(27)])
    ref = solve_ivp(rhs, (0.0, T), z0, method="DOP853", rtol=1e-12, atol=1e-12)
    x_ref = ref.y[:27, -1].reshape(9, 3)
    errors = []
    for N in Ns:
        sim = cs.Simulation(model, h=T / N, effects=[cs.Gravity(GRAVITY), cs.Pin(pins)],
                            iterations=200, tolerance=1e-10)
        sim.run(N)
        errors.append(float(np.abs(sim.state.positions - x_ref).max()))
    slope = float(np.polyfit(np.log(T / np.array(Ns)), np.log(errors), 1)[0])
    return {"slope": slope, "errors": errors}


# ==== contact: a small sphere hit at speed ============================================
CONTACT_H = 1 / 30
SPHERE_RADIUS = 0.01                      # sphere radius [m]
SPHERE_SPEED = 5 * 2 * SPHERE_RADIUS / CONTACT_H         # 5 diameters per step: 3 m/s


def measure_sphere_tunnelling(friction: float = 0.0, *, steps: int = 8,
                              thickness="auto") -> dict:
    """Drop the cloth on the small sphere; record the depth and the contacts of every step.

    Returns
    -------
    dict
        ``max_depth`` [m]: largest SPHERE_RADIUS − |x − c| over all vertices and steps (≤ 0: never
        inside); ``contacts``: contact vertex count per step; ``caught`` (vertex indices
        caught on the crossing step); ``caught_height``: their lowest y after that step [m];
        ``would_end`` (their y without the sphere, same step) [m]; ``caught_gap``: their
        distance beyond the contact surface, radius + the sphere's contact thickness [m];
        ``margin``: that thickness [m].
    """
    mesh = cs.grid(6, 6, size=(0.05, 0.05), center=(0.0, 0.06, 0.0), plane="xz")
    springs = cs.grid_springs(mesh, structural=50.0, shear=50.0, bending=5.0)
    model = cs.Model.build(mesh, springs, total_mass=0.01)
    v0 = np.tile([0.0, -SPHERE_SPEED, 0.0], (model.vertex_count, 1))
    sphere = Sphere((0.0, 0.0, 0.0), SPHERE_RADIUS, friction=friction, thickness=thickness)
    sims = {name: cs.Simulation(model, h=CONTACT_H, effects=effects,
                                state=cs.State(mesh.vertices.copy(), v0.copy()))
            for name, effects in (("sphere", [cs.Gravity(), sphere]), ("free", [cs.Gravity()]))}
    out = {"max_depth": -np.inf, "contacts": [], "caught": None}
    for _ in range(steps):
        for sim in sims.values():
            sim.step()
        x = sims["sphere"].state.positions
        depth = float((SPHERE_RADIUS - np.linalg.norm(x, axis=1)).max())
        out["max_depth"] = max(out["max_depth"], depth)
        out["contacts"].append(len(sphere.contact_vertices))
        if out["caught"] is None and len(sphere.contact_vertices):
            out["caught"] = sphere.contact_vertices.copy()
            out["caught_height"] = float(x[out["caught"], 1].min())
            out["caught_gap"] = (np.linalg.norm(x[out["caught"]], axis=1) - SPHERE_RADIUS
                                 - sphere.margin)
            out["margin"] = sphere.margin
            out["would_end"] = float(sims["free"].state.positions[out["caught"], 1].max())
    return out


# ==== contact: strain in contact (case 8) ===================================================
def measure_contact_strain(resolution: int = 25) -> list[dict]:
    """Both built-in obstacle scenes at ``resolution``² in both contact modes ("hold" as
    shipped, "post-solve" as the seed ran it, :data:`benchmarks.contact.AS_RUN`): largest
    spring stretch over the last second, max depth inside, max |v|
    (:func:`benchmarks.contact.measure_contact`)."""
    from .contact import AS_RUN, MODES, SCENES, measure_contact

    return [measure_contact(scene, resolution, mode, **AS_RUN[mode])
            for scene in SCENES for mode in MODES]
