"""The contact planes a simulation holds, per step, as ``clothsim export`` writes them.

In ``[contact] mode = "hold"`` each step keeps some vertices on planes n · x = offset
(:mod:`clothsim.contacts`); a port implementing that mode reads them from the export's
``contacts.txt`` / ``contacts.npz`` and solves the same constrained steps.
"""

from __future__ import annotations

import numpy as np


def held_planes(obstacles, step: int, t: float) -> np.ndarray:
    """The contact planes ``obstacles`` hold in the step ending at ``t``, one row each.

    Parameters
    ----------
    obstacles : list of Obstacle
        In ``"hold"`` mode (``hold_contacts`` does not change them).
    step : int
        The step's index k (frame k → k + 1).
    t : float
        Time at the end of the step [s].

    Returns
    -------
    ndarray, shape (c, 6)
        ``step vertex nx ny nz offset``: the vertex stays on n · x = offset [m] in the step.
    """
    rows = [np.zeros((0, 6))]
    for e in obstacles:
        c = e.hold_contacts(t)
        rows.append(np.column_stack([np.full(len(c), step), c.vertices, c.normals, c.offsets]))
    return np.concatenate(rows)


def write_held_planes(put, files: dict, held: list) -> None:
    """Write ``contacts.txt`` and ``contacts.npz`` from the rows of :func:`held_planes`.

    Parameters
    ----------
    put : callable
        ``put(name, write, *args)``: the export folder's atomic writer.
    files : dict
        The manifest's file descriptions, added to.
    held : list of ndarray, shape (c_k, 6)
        One :func:`held_planes` per step.

    Returns
    -------
    None
    """
    H = np.concatenate([np.zeros((0, 6))] + held)
    put("contacts.txt", np.savetxt, H, fmt=["%d", "%d", "%.17g", "%.17g", "%.17g", "%.17g"],
        header="step vertex nx ny nz offset: in step k (frame k -> k+1) vertex stays "
               "on n . x = offset [m]")
    put("contacts.npz", lambda tmp: np.savez(tmp, step=H[:, 0].astype(np.int64),
                                             vertex=H[:, 1].astype(np.int64),
                                             normal=H[:, 2:5], offset=H[:, 5]))
    files["contacts.txt"] = ("held contact planes per step: step vertex nx ny nz offset "
                             "(obstacles in hold mode)")
    files["contacts.npz"] = "the same: step, vertex (c,), normal (c, 3), offset (c,)"


__all__ = ["held_planes", "write_held_planes"]
