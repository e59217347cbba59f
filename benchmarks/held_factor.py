"""What a held-contact frame costs: the tangent-coordinate factor against the 3n system.

Run from the repository root::

    .venv/bin/python -m benchmarks held_factor                       # 65², 129² (minutes)
    .venv/bin/python -m benchmarks.held_factor --sizes 257 --scenes drop-on-square

For each built-in obstacle scene and size, two measurements, both in thread CPU seconds
(the solver runs single-threaded, so on a shared machine CPU time is steadier than wall
time; wall seconds are in docs/data/contact.md):

1. **One frame's parts** (:func:`frame_parts`), on the step of frame 45 (the cloth lies on
   the obstacle and slides): assembling and factoring the held global step's matrix and one
   solve, for the 3n system P A P + α D (the seed of hold mode: kron of the whole matrix,
   supernodal CHOLMOD) and for the tangent-coordinate system the solver uses
   (:mod:`clothsim.solvers.tangent_system`), beside one three-column solve of the
   unconstrained n × n factor that post-solve mode uses. The two held steps' largest
   difference [m] shows they solve the same problem.
2. **Whole runs** (:func:`run_cpu`): CPU seconds per frame over the scene's 90 frames in
   ``[contact] mode = "hold"`` and ``"post-solve"``, their ratio, and how many times hold
   mode factored.

Rows are stored in ``docs/data/held-factor.json`` (a run replaces the row of its scene and
size) and ``docs/data/held-factor.md`` is rewritten from all rows.
"""

from __future__ import annotations

import argparse
import json
import os
import time
import tomllib
import warnings

import numpy as np
import scipy.sparse as sp

from clothsim import contacts
from clothsim.factorization import Factor, single_threaded
from clothsim.scene import Scene, builtin_scene_text
from clothsim.solvers import held as held_module
from clothsim.solvers.held import HeldSystem, held_start

from . import ROOT
from .iteration_cost import commit

SCENES = ("drop-on-square", "drape-sphere")
DEFAULT_SIZES = (65, 129)
FRAME = 45
JSON = ROOT / "docs" / "data" / "held-factor.json"
PAGE = ROOT / "docs" / "data" / "held-factor.md"


def _simulation(scene: str, n: int, mode: str):
    doc = tomllib.loads(builtin_scene_text(scene))
    doc["cloth"]["resolution"] = [n, n]
    doc["contact"] = {"mode": mode}
    sc = Scene.from_dict(doc, source=f"{scene}.toml")
    sim = sc.build_simulation()
    sim.expect_steps(sc.frames * sc.substeps)
    return sc, sim


def _cpu(f, repeats: int = 3):
    """The least thread CPU seconds of ``repeats`` calls of f, and f's last result."""
    best, out = np.inf, None
    for _ in range(repeats):
        t = time.thread_time()
        out = f()
        best = min(best, time.thread_time() - t)
    return best, out


class SeedHeldSystem(held_module.HeldSystem):
    """Hold mode's global step before the tangent coordinates, for comparison: the 3n
    matrix P A P + α D in the fixed pattern of (M_s + h² L_s) ⊗ ones(3, 3) (so that its
    symbolic analysis is reused and only the numeric factorization runs per contact set),
    supernodal CHOLMOD."""

    def __init__(self, solver, problem, previous=None):
        sysf = solver.system(problem)
        n = solver.model.vertex_count
        self.As = A = sp.csr_matrix(sysf.A)
        self.free, self.fixed = sysf.free, sysf.fixed
        self.basis = problem.contact_basis()
        self.held, self.blocks = held_module.projector_blocks(problem.contact_vertices,
                                                              self.basis)
        P, D = contacts.projector(n, self.basis)
        self.alpha = float(A.diagonal().mean())
        pattern = sp.kron(A, np.ones((3, 3)), format="csr")
        pattern.data[:] = 1e-300
        K = (P @ sp.kron(A, sp.identity(3), format="csr") @ P + self.alpha * D + pattern).tocsr()
        self.dofs = (3 * self.free[:, None] + np.arange(3)).ravel()
        self.seed_factor = Factor(K[self.dofs][:, self.dofs], backend=solver.backend_requested,
                                  check_conditioning=False, cholmod_mode="supernodal",
                                  reuse=getattr(previous, "seed_factor", None))
        self.oblique = np.zeros(0, np.int64)
        self.tangent_factor = self.seed_factor

    def solve(self, r):
        u = np.zeros((len(self.As.indptr) - 1, 3))
        u[self.free] = self.seed_factor.solve(
            np.ascontiguousarray(r[self.free]).reshape(-1)).reshape(-1, 3)
        return u


def frame_parts(scene: str, n: int) -> dict:
    """CPU seconds of the parts of frame :data:`FRAME`'s held step (see the module doc)."""
    sc, sim = _simulation(scene, n, "hold")
    for _ in range(FRAME * sc.substeps):
        sim.step()
    p, solver = sim.problem(), sim.solver
    with single_threaded():
        held, x = held_start(solver, p)
        rhs = solver.displacement_right_hand_side(p, solver.local_step(x))
        z, Az = held.prepare(p)
        t_new, held = _cpu(lambda: HeldSystem(solver, p))
        s_new, x_new = _cpu(lambda: held.global_step(p, rhs.copy(), z, Az), 10)
        seed = SeedHeldSystem(solver, p)            # the pattern's analysis, not timed
        t_old, seed = _cpu(lambda: SeedHeldSystem(solver, p, previous=seed))
        s_old, x_old = _cpu(lambda: seed.global_step(p, rhs.copy(), z, Az), 10)
        unconstrained = solver.system(p).A_FF_factor
        B = np.ones((3, unconstrained.shape[0]))
        s_n, _ = _cpu(lambda: unconstrained.solve_columns(B), 10)
    return {"held": int(len(held.held)), "oblique": int(len(held.oblique)),
            "unknowns_3n": int(len(seed.dofs)), "unknowns": int(held.tangent_factor.shape[0]),
            "factor_3n": t_old, "solve_3n": s_old, "factor": t_new, "solve": s_new,
            "solve_n": s_n, "difference": float(np.abs(x_new - x_old).max())}


def run_cpu(scene: str, n: int, mode: str, *, seed: bool = False) -> tuple[float, int]:
    """Thread CPU seconds per frame over the scene's run in ``mode`` (``seed``: hold mode
    with :class:`SeedHeldSystem`); factorizations."""
    sc, sim = _simulation(scene, n, mode)
    t = time.thread_time()
    held_module.HeldSystem = SeedHeldSystem if seed else HeldSystem
    try:
        for _ in range(sc.frames * sc.substeps):
            sim.step()
    finally:
        held_module.HeldSystem = HeldSystem
    return (time.thread_time() - t) / sc.frames, int(sim.solver.factor_count)


def measure(scene: str, n: int) -> dict:
    """:func:`frame_parts` and :func:`run_cpu` in both modes for one scene and size."""
    row = {"scene": scene, "resolution": n, **frame_parts(scene, n)}
    row["hold"], row["factorizations"] = run_cpu(scene, n, "hold")
    row["hold_3n"], _ = run_cpu(scene, n, "hold", seed=True)
    row["post_solve"], _ = run_cpu(scene, n, "post-solve")
    return row


def page(rows: list[dict]) -> str:
    """The Markdown tables of ``rows``."""
    rows = sorted(rows, key=lambda r: (SCENES.index(r["scene"]), r["resolution"]))
    out = ["Printed by `.venv/bin/python -m benchmarks held_factor` (sizes run separately "
           "with `.venv/bin/python -m benchmarks.held_factor --sizes N`); thread CPU seconds, "
           "each row at the commit it names.", "",
           f"One held step of frame {FRAME}: the 3n system P A P + α D (its numeric "
           "factorization in the fixed pattern) against the tangent coordinates (assembly "
           "with analysis and factorization), one solve of each, and the unconstrained "
           "n × n factor's three-column solve (post-solve mode's).", "",
           "| scene | n² | held (oblique) | unknowns 3n → tangent | factor 3n [s] | "
           "factor tangent [s] | solve 3n [ms] | solve tangent [ms] | solve n × n, 3 rhs "
           "[ms] | steps differ by [m] |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['scene']} | {r['resolution']}² | {r['held']} ({r['oblique']}) | "
                   f"{r['unknowns_3n']} → {r['unknowns']} | {r['factor_3n']:.3f} | "
                   f"{r['factor']:.3f} | {1e3 * r['solve_3n']:.2f} | {1e3 * r['solve']:.2f} | "
                   f"{1e3 * r['solve_n']:.2f} | {r['difference']:.1e} |")
    out += ["", "Whole runs (90 frames): CPU seconds per frame in each contact mode; hold "
            "mode with the 3n system as it was, and with the tangent coordinates.", "",
            "| scene | n² | hold, 3n [s/frame] | hold [s/frame] | post-solve [s/frame] | "
            "hold / post-solve (3n) | hold / post-solve | factorizations (hold) | commit |",
            "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['scene']} | {r['resolution']}² | {r['hold_3n']:.3f} | "
                   f"{r['hold']:.3f} | {r['post_solve']:.3f} | "
                   f"{r['hold_3n'] / r['post_solve']:.2f} | "
                   f"{r['hold'] / r['post_solve']:.2f} | {r['factorizations']} | "
                   f"{r['commit']} |")
    return "\n".join(out) + "\n"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=list(DEFAULT_SIZES))
    parser.add_argument("--scenes", nargs="+", choices=SCENES, default=list(SCENES))
    args = parser.parse_args([] if argv is None else argv)
    warnings.simplefilter("ignore")
    from clothsim.io.common import atomic_path

    rows = json.loads(JSON.read_text(encoding="utf-8"))["rows"] if JSON.is_file() else []
    where = commit()
    for n in args.sizes:
        for scene in args.scenes:
            r = measure(scene, n)
            r["commit"], r["load"] = where, round(os.getloadavg()[0], 2)
            print(f"{scene} {n}^2: factor 3n {r['factor_3n']:.3f} s -> tangent "
                  f"{r['factor']:.3f} s; solve {1e3 * r['solve_3n']:.2f} -> "
                  f"{1e3 * r['solve']:.2f} ms (n x n 3 rhs {1e3 * r['solve_n']:.2f} ms); "
                  f"CPU per frame hold {r['hold_3n']:.3f} s (3n) {r['hold']:.3f} s, "
                  f"post-solve {r['post_solve']:.3f} s "
                  f"(ratio {r['hold'] / r['post_solve']:.2f})", flush=True)
            rows = [q for q in rows if (q["scene"], q["resolution"]) != (scene, n)] + [r]
            with atomic_path(JSON) as tmp:
                tmp.write_text(json.dumps({"rows": rows}, indent=1) + "\n", encoding="utf-8")
            with atomic_path(PAGE) as tmp:
                tmp.write_text(page(rows), encoding="utf-8")


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])
