"""Reference data for regression-checking other ports (C++, GPU) of the method.

:func:`export_matrices` writes the paper's matrices and the model's arrays in open formats
(Matrix Market for matrices, plain text with 17 significant digits for vectors), in the
interleaved 3n layout of docs/math.md, plus a ``manifest.json`` that says what each file is.
Trajectories are exported by ``clothsim run`` (``trajectory.npz``, VTU frames) and compared by
:mod:`clothsim.compare`.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from . import io, matrices
from .model import Model

LAYOUT = ("x in R^{3n} is stacked per vertex (x0 y0 z0 x1 y1 z1 ...): index 3*i + c; "
          "d in R^{3s} per spring likewise")


def export_matrices(model: Model, h: float, out_dir, *, pinned=None) -> dict:
    """Write M, L, J, M + h²L (3n forms) and the scalar n × n forms to ``out_dir``.

    Parameters
    ----------
    model : Model
    h : float
        Time step [s] of the system matrix.
    out_dir : path
        Created if missing.
    pinned : array_like of int, optional
        Exactly pinned vertices; recorded in the manifest (the matrices are the full ones).

    Returns
    -------
    dict
        The manifest (also written as ``manifest.json``).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    files = {
        "M.mtx": (matrices.mass_matrix(model), "M = diag(m) kron I3, 3n x 3n [kg]"),
        "L.mtx": (matrices.stiffness_matrix(model),
                  "L = (sum k_i A_i A_i^T) kron I3, 3n x 3n [N/m]"),
        "J.mtx": (matrices.spring_matrix(model), "J = (sum k_i A_i S_i^T) kron I3, 3n x 3s [N/m]"),
        "A.mtx": (matrices.system_matrix(model, h, expand=True), "M + h^2 L, 3n x 3n [kg]"),
        "A_scalar.mtx": (matrices.system_matrix(model, h), "M_s + h^2 L_s, n x n [kg]"),
    }
    for name, (A, _) in files.items():
        io.write_matrix(out / name, A)
    vectors = {
        "x0.txt": (model.mesh.vertices.ravel(), "initial positions, 3n [m]"),
        "vertex_mass.txt": (model.vertex_mass, "m_i, n [kg]"),
        "spring_stiffness.txt": (model.springs.spring_stiffness, "k_i, s [N/m]"),
        "spring_rest_length.txt": (model.springs.spring_rest_length, "r_i, s [m]"),
    }
    for name, (v, _) in vectors.items():
        io.write_vector(out / name, v)
    np.savetxt(out / "spring_vertices.txt", model.springs.spring_vertices, fmt="%d",
               header="a_i b_i (0-based vertex indices)")
    manifest = {
        "layout": LAYOUT,
        "h": float(h),
        "vertex_count": model.vertex_count,
        "spring_count": model.spring_count,
        "pinned_vertices": [] if pinned is None else [int(i) for i in np.ravel(pinned)],
        "files": {name: desc for name, (_, desc) in {**files, **vectors}.items()}
        | {"spring_vertices.txt": "a_i b_i per spring, 0-based"},
    }
    (out / "manifest.json").write_text(json.dumps(manifest, indent=2))
    return manifest
