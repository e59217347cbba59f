"""The project's Python solution of the mass-spring assignment, with faults to plant.

The three functions of the University of Toronto CSC317 mass-spring assignment
(A. Jacobson, "computer-graphics-mass-spring-systems"), sparse, in numpy/scipy, the
counterpart of ``examples/ports/cpp/mass_springs_solution.cpp``; :func:`run` calls them as
the assignment's ``main.cpp`` does (one k, penalty pins w = 1e10 at the rest positions,
y = 2 U_cur − U_prev, 50 iterations from U_cur) on a model folder that ``clothsim export``
or ``clothsim conformance --profile coursework`` writes, and writes the frames ``clothsim
check`` reads::

    .venv/bin/python examples/ports/mass_springs.py MODEL_DIR OUT_DIR [--fault NAME]

``--fault`` plants one of the mistakes of :data:`FAULTS` (the fault zoo of
tests/ports/test_causes.py and the examples of docs/ports.md, "What check says about a
broken port").
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

#: The planted mistakes: name -> what a student wrote.
FAULTS = {
    "gravity-sign": "l = M y / h² − f_ext: the external force with the wrong sign",
    "gravity-mass": "f_ext = m g: gravity as m (0, −9.8, 0), not the assignment's −9.8 N",
    "rest-length": "r = 0.9 |V_a − V_b|: rest lengths 10 % short",
    "stiffness": "2 k in Q and in the right-hand side: springs twice as stiff",
    "unnormalized": "d = A U (no r p / |p|): the local step not normalized",
    "unpinned": "w = 0: the pins left out",
}
W = 1e10


def signed_incidence_matrix_sparse(n: int, E: np.ndarray) -> sp.csr_matrix:
    """A (|E| × n): row e has +1 in column E[e, 0] and −1 in column E[e, 1]."""
    rows = np.repeat(np.arange(len(E)), 2)
    vals = np.tile([1.0, -1.0], len(E))
    return sp.csr_matrix((vals, (rows, E.ravel())), shape=(len(E), n))


def fast_mass_springs_precomputation_sparse(V, E, k, m, b, delta_t, fault=None):
    """r, M, A, C and the factor of k AᵀA + M / Δt² + w CᵀC (w = 1e10)."""
    n = len(V)
    r = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    if fault == "rest-length":
        r = 0.9 * r
    M = sp.diags(m)
    A = signed_incidence_matrix_sparse(n, E)
    C = sp.csr_matrix((np.ones(len(b)), (np.arange(len(b)), b)), shape=(len(b), n))
    k = 2 * k if fault == "stiffness" else k
    w = 0.0 if fault == "unpinned" else W
    Q = k * (A.T @ A) + M / delta_t**2 + w * (C.T @ C)
    return r, M, A, C, splu(sp.csc_matrix(Q))


def fast_mass_springs_step_sparse(V, E, k, b, delta_t, fext, r, M, A, C, factor, Uprev, Ucur,
                                  fault=None):
    """One step: 50 local/global iterations from U_cur, y = 2 U_cur − U_prev."""
    k = 2 * k if fault == "stiffness" else k
    w = 0.0 if fault == "unpinned" else W
    y = 2.0 * Ucur - Uprev
    f = -fext if fault == "gravity-sign" else fext
    if fault == "gravity-mass":
        f = M @ np.tile([0.0, -9.8, 0.0], (M.shape[0], 1))
    rhs = M @ y / delta_t**2 + f + w * (C.T @ (C @ V))
    U = Ucur.copy()
    for _ in range(50):
        p = A @ U
        d = p if fault == "unnormalized" else r[:, None] * p / np.linalg.norm(
            p, axis=1, keepdims=True)
        U = factor.solve(k * (A.T @ d) + rhs)
    return U


def run(model_dir, out_dir, *, fault: str | None = None, frames: int | None = None) -> Path:
    """Run the assignment on a model folder; write ``positions.txt``, ``velocities.txt``.

    Parameters
    ----------
    model_dir : path
        ``vertices.txt``, ``springs.txt``, ``masses.txt``, ``pins.txt``, ``forces.txt``,
        ``settings.txt`` (h and frames), as ``clothsim export`` writes them.
    out_dir : path
        Created if needed.
    fault : str, optional
        A key of :data:`FAULTS`.
    frames : int, optional
        Steps to take; default settings.txt's ``frames``.

    Returns
    -------
    Path
        ``out_dir``.
    """
    if fault is not None and fault not in FAULTS:
        raise ValueError(f"fault: one of {', '.join(FAULTS)}, got {fault!r}")
    d, out = Path(model_dir), Path(out_dir)
    V = np.loadtxt(d / "vertices.txt", ndmin=2)
    springs = np.loadtxt(d / "springs.txt", ndmin=2)
    E, k = springs[:, :2].astype(np.int64), float(springs[0, 2])
    m = np.loadtxt(d / "masses.txt", ndmin=1)
    pins = np.loadtxt(d / "pins.txt", ndmin=2)
    b = pins[:, 0].astype(np.int64) if pins.size else np.zeros(0, np.int64)
    fext = np.loadtxt(d / "forces.txt", ndmin=2)
    settings = dict(line.split()[:2] for line in (d / "settings.txt").read_text().splitlines()
                    if line.strip() and not line.startswith("#"))
    h = float(settings["h"])
    frames = int(settings["frames"]) if frames is None else frames
    r, M, A, C, factor = fast_mass_springs_precomputation_sparse(V, E, k, m, b, h, fault)
    Uprev, Ucur = V.copy(), V.copy()
    xs, vs = [V.copy()], [np.zeros_like(V)]
    for _ in range(frames):
        Unext = fast_mass_springs_step_sparse(V, E, k, b, h, fext, r, M, A, C, factor, Uprev,
                                              Ucur, fault)
        xs.append(Unext)
        vs.append((Unext - Ucur) / h)
        Uprev, Ucur = Ucur, Unext
    out.mkdir(parents=True, exist_ok=True)
    for name, a in (("positions", xs), ("velocities", vs)):
        np.savetxt(out / f"{name}.txt", np.stack(a).reshape(len(a), -1), fmt="%.17g")
    return out


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("model_dir")
    parser.add_argument("out_dir")
    parser.add_argument("--fault", choices=sorted(FAULTS))
    parser.add_argument("--frames", type=int)
    args = parser.parse_args()
    run(args.model_dir, args.out_dir, fault=args.fault, frames=args.frames)
