"""Everything a port needs to be checked against clothsim, in open formats.

:func:`export_port` writes into one folder (the layout is listed in its ``manifest.json`` and
in docs/ports.md):

matrices
    Matrix Market, sparse, %.17g; 3n rows interleaved: row 3 i + c is coordinate c of
    vertex i. ``M.mtx``; ``L.mtx`` = (Σ k_i A_i A_iᵀ + Σ_pins k_p e_p e_pᵀ) ⊗ I3 —
    **with** the penalty pins, as solved; ``L_springs.mtx`` without them; ``J.mtx``
    (3n × 3s, springs only); ``A.mtx`` = M + h² L (3n, with pins) and ``A_scalar.mtx``
    (its n × n block).
model (plain text)
    ``vertices.txt`` (n lines x y z), ``x0.txt`` (one line of 3n), ``triangles.txt``,
    ``springs.txt`` (a b k r [damping], 0-based), ``masses.txt``, ``pins.txt`` (vertex
    method stiffness x y z; stiffness 0 for exact pins), ``forces.txt`` (external force at
    t = 0, n lines), ``settings.txt`` (``key value`` lines: h, iterations, tolerance,
    initial_guess, method, frames, precision, damping).
trajectory
    ``trajectory.npz`` (positions, velocities (frames, n, 3), time); ``positions.txt``,
    ``velocities.txt`` (one frame a line of 3n numbers, %.17g); ``positions.f64``,
    ``velocities.f64`` (raw little-endian float64, frame after frame, x y z per vertex).
contacts (scenes with obstacles in ``"hold"`` mode)
    ``contacts.txt`` (``step vertex nx ny nz offset`` a line: in step k, frame k → k + 1,
    the vertex is held on the plane n · x = offset) and ``contacts.npz`` (the same columns
    as arrays ``step``, ``vertex``, ``normal``, ``offset``).
iterates
    ``iterates/step_KKKK.npz`` for the first steps: ``x`` (K + 1, n, 3) the local/global
    iterates x_0 (the initial guess) … x_K, ``d`` (K + 1, s, 3) with d_k = local step of
    x_k (so x_{k+1} = global step of d_k), ``gradient_norm`` (K + 1), ``y``, ``f_ext``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from .. import io, matrices
from ..io.outfolder import OutputFolder
from ..io.runfiles import read_json
from ..solvers.local_global import LocalGlobalSolver
from .check import as_simulation, system_condition_number
from .contact_planes import held_planes, write_held_planes
from .model_folder import damping_text

LAYOUT = ("x in R^{3n} is stacked per vertex (x0 y0 z0 x1 y1 z1 ...): index 3*i + c; "
          "d in R^{3s} per spring likewise; raw files are little-endian float64 in the same "
          "order, frame after frame")


def export_matrices(model, h: float, out_dir, *, pinned=None, anchor_vertices=(),
                    anchor_stiffness=()) -> dict:
    """Write only the matrices and model vectors of a bare model (no simulation needed).

    Parameters
    ----------
    model : Model
    h : float
        Time step [s] of the system matrix.
    out_dir : path
    pinned : array_like of int, optional
        Exactly pinned vertices, recorded in the manifest (the matrices are the full ones).
    anchor_vertices, anchor_stiffness : array_like, optional
        Penalty pins [N/m]: they enter ``L.mtx``, ``A.mtx`` and ``A_scalar.mtx``.

    Returns
    -------
    dict
        The manifest (also ``manifest.json``).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    av = np.asarray(anchor_vertices, np.int64).reshape(-1)
    ak = np.broadcast_to(np.asarray(anchor_stiffness, np.float64), av.shape)
    n = model.vertex_count
    K = sp.csr_matrix((np.bincount(av, ak, minlength=n), (np.arange(n), np.arange(n))),
                      shape=(n, n))
    A_s = matrices.system_matrix(model, h, anchor_vertices=av, anchor_stiffness=ak)
    files = {
        "M.mtx": (matrices.mass_matrix(model), "M = diag(m) kron I3, 3n x 3n [kg]"),
        "L.mtx": (matrices.expand3(matrices.stiffness_matrix(model, expand=False) + K),
                  "L with penalty pins, 3n x 3n [N/m]"),
        "J.mtx": (matrices.spring_matrix(model), "J = (sum k_i A_i S_i^T) kron I3, 3n x 3s"),
        "A.mtx": (matrices.expand3(A_s), "M + h^2 L (penalty pins in), 3n x 3n [kg]"),
        "A_scalar.mtx": (A_s, "M_s + h^2 L_s (penalty pins in), n x n [kg]"),
    }
    for name, (A, _) in files.items():
        io.write_matrix(out / name, sp.csr_matrix(A))
    vectors = {"x0.txt": model.mesh.vertices.ravel(), "vertex_mass.txt": model.vertex_mass,
               "spring_stiffness.txt": model.springs.spring_stiffness,
               "spring_rest_length.txt": model.springs.spring_rest_length}
    for name, v in vectors.items():
        io.write_vector(out / name, v)
    np.savetxt(out / "spring_vertices.txt", model.springs.spring_vertices, fmt="%d",
               header="a_i b_i (0-based vertex indices)")
    manifest = {"layout": LAYOUT, "h": float(h), "vertex_count": n,
                "spring_count": model.spring_count,
                "pinned_vertices": [] if pinned is None else [int(i) for i in np.ravel(pinned)],
                "files": {name: desc for name, (_, desc) in files.items()}
                | {name: "one number a line" for name in vectors}
                | {"spring_vertices.txt": "a_i b_i per spring, 0-based"}}
    (out / "manifest.json").write_text(json.dumps(manifest, indent=2))
    return manifest


def write_springs(path, springs) -> None:
    """Write ``a b k r`` per spring (0-based), and a fifth column ``damping`` when any is damped.

    Parameters
    ----------
    path : path
    springs : Springs
    """
    cols = [springs.spring_vertices, springs.spring_stiffness, springs.spring_rest_length]
    fmt, header = ["%d", "%d", "%.17g", "%.17g"], "a b k r (0-based vertices)"
    if springs.spring_damping.any():
        cols.append(springs.spring_damping)
        fmt, header = fmt + ["%.17g"], "a b k r damping (0-based vertices) [-, -, N/m, m, N s/m]"
    np.savetxt(path, np.column_stack(cols), fmt=fmt, header=header)


def settings(sim, frames: int) -> dict:
    """The step settings a port must match: what ``settings.txt`` holds.

    Parameters
    ----------
    sim : Simulation
    frames : int
        Steps of the reference trajectory.

    Returns
    -------
    dict
        ``h`` [s], ``iterations``, ``tolerance`` (0 when the count is fixed),
        ``initial_guess`` (y | x_n), ``method``, ``frames``, ``precision`` (float64),
        ``damping`` (the velocity damping effects, ``model:coefficient,…`` or none).
    """
    return {"h": sim.h, "iterations": sim.solver.iterations,
            "tolerance": sim.solver.tolerance or 0.0, "initial_guess": sim.initial_guess,
            "method": sim.solver.name, "frames": frames, "precision": "float64",
            "damping": damping_text(sim.effects)}


def write_settings(path, sim, frames: int) -> None:
    """Write :func:`settings` as ``key value`` lines (numbers as %.17g).

    Parameters
    ----------
    path : path
    sim : Simulation
    frames : int
    """
    lines = ["# clothsim step settings: key value"]
    for key, value in settings(sim, frames).items():
        lines.append(f"{key} {value:.17g}" if isinstance(value, float) else f"{key} {value}")
    Path(path).write_text("\n".join(lines) + "\n")


def pin_table(sim) -> np.ndarray:
    """Rows (vertex, method code, stiffness, x, y, z) of the pins acting in the first step.

    Method code 0 = exact (constraint, stiffness 0), 1 = penalty.

    Parameters
    ----------
    sim : Simulation
        At the state whose next step's pins are listed.

    Returns
    -------
    ndarray, shape (p, 6)
        Vertex, method code, stiffness [N/m], target position x y z [m].
    """
    p = sim.problem(sim.state)
    rows = [(v, 0, 0.0, *q) for v, q in zip(p.fixed_vertices, p.fixed_positions)]
    rows += [(v, 1, k, *q) for v, q, k in zip(p.anchor_vertices, p.anchor_positions,
                                               p.anchor_stiffness)]
    return np.array(rows, dtype=np.float64).reshape(-1, 6)


class _RecordingSolver(LocalGlobalSolver):
    """Local/global solver that keeps a copy of every iterate x_k and its local step d_k."""

    def iterates(self, problem, x0=None):
        for it in super().iterates(problem, x0):
            self.record.append((it.x.copy(), it.d.copy(), it.gradient_norm))
            yield it


def record_iterates(sim, steps: int) -> list[dict]:
    """Local/global iterates (x_k, d_k) of the next ``steps`` steps, advancing ``sim``.

    A separate local/global solver with the simulation's iteration count and tolerance (so
    the same stop rule) records them; the simulation's own solver is untouched.

    Parameters
    ----------
    sim : Simulation
        Advanced by ``steps`` steps.
    steps : int
        Number of steps to record.

    Returns
    -------
    list of dict
        Per step: ``x`` (K + 1, n, 3) iterates [m], ``d`` (K + 1, s, 3) local steps
        d_i = r_i p_i/|p_i| of each iterate [m], ``gradient_norm`` (K + 1,) [N·s²], and
        the step's ``y`` [m] and ``f_ext`` [N].
    """
    solver = _RecordingSolver(sim.model, iterations=sim.solver.iterations,
                              tolerance=sim.solver.tolerance)
    out = []
    for _ in range(steps):
        problem = sim.problem(sim.state)
        solver.record = []
        solver.solve(problem)
        xs, ds, gs = zip(*solver.record)
        out.append({"x": np.stack(xs), "d": np.stack(ds), "gradient_norm": np.array(gs),
                    "y": problem.y, "f_ext": (np.zeros_like(problem.y) if problem.f_ext is None
                                              else problem.f_ext)})
        sim.step()
    return out


def export_port(source, out_dir, *, frames: int = 60, iterate_steps: int = 3,
                force: bool = False) -> dict:
    """Write matrices, model, settings, reference trajectory and iterates to ``out_dir``.

    Parameters
    ----------
    source : Scene, Simulation or callable returning a Simulation
    out_dir : path
        Created if missing.
    frames : int, default 60
        Steps of the reference trajectory (frames 0 … frames are written).
    iterate_steps : int, default 3
        Steps whose local/global iterates are written.
    force : bool
        Write into a folder clothsim does not own; without it only a missing or empty folder
        or an earlier export is written into (:func:`clothsim.io.folders.claim_folder`).

    Returns
    -------
    dict
        The manifest (also ``manifest.json``).

    Raises
    ------
    InputError
        The folder is not clothsim's export folder (and not ``force``), or another clothsim
        process (a run, an export) holds its lock.
    """
    sim = as_simulation(source)
    with OutputFolder(out_dir, "export", force=force) as folder:
        stale = _earlier_export(folder)
        # the folder is an export folder being written before any file is removed or written
        folder.mark("writing", {"layout": LAYOUT})
        for p in stale:  # no file of another scene's export stays beside this one's
            p.unlink(missing_ok=True)
        manifest = _export_locked(source, sim, folder, frames, iterate_steps)
        manifest["status"] = "complete"
        folder.mark("complete", manifest)
        return manifest


def _earlier_export(folder: OutputFolder) -> list[Path]:
    """The files an earlier export there listed in its manifest, and its iterates."""
    if folder.earlier.kind != "export":
        return []
    listed = (read_json(folder.path / "manifest.json") or {}).get("files", {})
    names = [n for n in listed if isinstance(n, str) and "/" not in n and n != "manifest.json"]
    stale = [folder.path / n for n in names] + sorted(folder.path.glob("iterates/step_*.npz"))
    return [p for p in stale if p.is_file() and not p.is_symlink()]


def _export_locked(source, sim, folder: OutputFolder, frames: int, iterate_steps: int) -> dict:
    model, h = sim.model, sim.h
    (folder.path / "iterates").mkdir(parents=True, exist_ok=True)
    p = sim.problem(sim.state)
    kappa = system_condition_number(sim)  # of the first step's system, pins included
    n = model.vertex_count
    K = sp.csr_matrix((np.bincount(p.anchor_vertices, p.anchor_stiffness, minlength=n),
                       (np.arange(n), np.arange(n))), shape=(n, n))
    Ls = matrices.stiffness_matrix(model, expand=False)
    A_s = matrices.system_matrix(model, h, anchor_vertices=p.anchor_vertices,
                                 anchor_stiffness=p.anchor_stiffness)
    files = {}
    pins = pin_table(sim)

    def put(name, write, *args, **kwargs):  # atomically, an error naming the file
        with folder.file(name) as tmp:
            write(tmp, *args, **kwargs)

    def mtx(name, A, desc):
        put(name, io.write_matrix, sp.csr_matrix(A))
        files[name] = desc

    mtx("M.mtx", matrices.mass_matrix(model), "M = diag(m) kron I3, 3n x 3n [kg]")
    mtx("L.mtx", matrices.expand3(Ls + K), "L with penalty pins, 3n x 3n [N/m]")
    mtx("L_springs.mtx", matrices.expand3(Ls), "L of the springs only, 3n x 3n [N/m]")
    mtx("J.mtx", matrices.spring_matrix(model), "J = (sum k_i A_i S_i^T) kron I3, 3n x 3s")
    mtx("A.mtx", matrices.expand3(A_s), "M + h^2 L (penalty pins in), 3n x 3n [kg]")
    mtx("A_scalar.mtx", A_s, "M_s + h^2 L_s (penalty pins in), n x n [kg]")
    x0 = model.mesh.vertices
    put("vertices.txt", np.savetxt, x0, fmt="%.17g")
    put("x0.txt", np.savetxt, x0.reshape(1, -1), fmt="%.17g")
    put("triangles.txt", np.savetxt, model.mesh.triangles, fmt="%d")
    put("springs.txt", write_springs, model.springs)
    put("masses.txt", io.write_vector, model.vertex_mass)
    put("pins.txt", np.savetxt, pins, fmt=["%d", "%d", "%.17g", "%.17g", "%.17g", "%.17g"],
        header="vertex method(0 exact, 1 penalty) stiffness x y z")
    put("forces.txt", np.savetxt, np.zeros((n, 3)) if p.f_ext is None else p.f_ext,
        fmt="%.17g", header="external force at t = 0 [N], one vertex a line")
    files.update({
        "vertices.txt": "initial positions, n lines x y z [m]",
        "x0.txt": "initial positions, one line of 3n [m]",
        "triangles.txt": "three 0-based vertex indices a line",
        "springs.txt": "a b k r per spring (0-based) [-, -, N/m, m]",
        "masses.txt": "m_i per vertex [kg]",
        "pins.txt": "vertex method(0 exact, 1 penalty) stiffness x y z [-, -, N/m, m]",
        "forces.txt": "external force per vertex at t = 0 [N]",
        "settings.txt": "key value lines: h, iterations, tolerance, initial_guess, method, "
                        "frames, precision, damping"})
    put("settings.txt", write_settings, sim, frames)
    steps = record_iterates(sim, min(iterate_steps, frames))
    for k, it in enumerate(steps):
        put(f"iterates/step_{k:04d}.npz", lambda tmp, it=it: np.savez(tmp, **it))
    files["iterates/step_KKKK.npz"] = ("x (K+1, n, 3) iterates, d (K+1, s, 3) local steps, "
                                       "gradient_norm, y, f_ext of step K -> K+1")
    xs, vs = [None] * (frames + 1), [None] * (frames + 1)
    # the iterate steps already advanced the simulation: replay from the start
    sim = as_simulation(source)
    holding = [e for e in sim.effects if getattr(e, "contact", None) == "hold"]
    held = []
    xs[0], vs[0] = sim.state.positions.copy(), sim.state.velocities.copy()
    for f in range(1, frames + 1):
        if holding:
            held.append(held_planes(holding, f - 1, sim.state.time + h))
        sim.step()
        xs[f], vs[f] = sim.state.positions.copy(), sim.state.velocities.copy()
    X, V = np.stack(xs), np.stack(vs)
    if holding:
        write_held_planes(put, files, held)
    put("trajectory.npz", lambda tmp: np.savez(tmp, positions=X, velocities=V,
                                               time=h * np.arange(frames + 1)))
    for name, arr in (("positions", X), ("velocities", V)):
        put(f"{name}.txt", np.savetxt, arr.reshape(len(arr), -1), fmt="%.17g")
        put(f"{name}.f64", arr.astype("<f8").tofile)
        files[f"{name}.txt"] = f"{name}, one frame a line of 3n numbers"
        files[f"{name}.f64"] = f"{name}, raw little-endian float64 (frames, n, 3)"
    files["trajectory.npz"] = "positions, velocities (frames, n, 3), time (frames,)"
    solver = sim.solver
    manifest = {
        "layout": LAYOUT, "h": h, "vertex_count": n, "spring_count": model.spring_count,
        "frames": frames + 1,
        "source": str(getattr(source, "source", "")) if hasattr(source, "to_dict") else "",
        "scene": source.to_dict() if hasattr(source, "to_dict") else None,
        "solver": {"method": solver.name, "iterations": solver.iterations,
                   "tolerance": solver.tolerance,
                   "initial_guess": sim.initial_guess},
        "effects": [e.describe() for e in sim.effects],
        "pinned_vertices": [int(r[0]) for r in pins],
        "pins": [{"vertex": int(r[0]), "method": "penalty" if r[1] else "constraint",
                  "stiffness": float(r[2]) if r[1] else None, "position": r[3:].tolist()}
                 for r in pins],
        "condition_number": kappa,
        "iterate_steps": len(steps),
        "files": files,
    }
    return manifest
