"""The verdicts of a hold-mode step: the port's planes, or a contact treatment, differ.

``contacts differ`` names the vertex and the face where a port's contact handling departs
from clothsim's held step (:mod:`clothsim.ports.held_steps`):

- the port wrote its planes and one differs (:func:`planes_verdict`): "vertex 48 held on
  the box's top by clothsim, free in the port", "sticks … slides …", "its sign is flipped";
- its answer is clothsim's step under another contact treatment (:func:`variant_verdict`):
  contact resolved after the solve, or held without friction.

Otherwise the step is judged as any other (:mod:`clothsim.ports.judge`), and
:func:`off_plane_note` adds the held vertex the port's answer leaves farthest off its
plane, when that is beyond the tolerance.
"""

from __future__ import annotations

import numpy as np

from .held_steps import VARIANTS, face_name
from .plane_diff import clothsim_rows, plane_differences
from .verdicts import StepCheck

#: A replayed contact treatment explains the port's step when it lands within the
#: tolerance of the port's answer, or this many times nearer than clothsim's held step.
NEARER = 10.0


def planes_verdict(k, held, port_planes, x_port_k, fixed, err, tol) -> StepCheck | None:
    """``contacts differ`` when the port's planes of step k are not clothsim's, else None.

    Parameters
    ----------
    k : int
    held : HeldSteps
        Anchored at the port's x_k.
    port_planes : PortPlanes
    x_port_k : ndarray, shape (n, 3)
        The port's x_k [m].
    fixed : ndarray of int
        Exactly pinned vertices (a plane there is dropped: the pin holds).
    err : ndarray, shape (n,)
        |x_clothsim − x_port| of the step [m].
    tol : float
        The step's tolerance [m]; plane offsets are compared with it too.

    Returns
    -------
    (StepCheck or None, list of (int, str))
        The verdict, and the changes that make clothsim's decision the port's
        (:func:`~clothsim.ports.held_margins.adopt`).
    """
    v, n, o = port_planes.step(k)
    diffs = plane_differences(clothsim_rows(held.planes()), v, n, o, x_port_k,
                              held.obstacles,
                              offset_tolerance=max(tol, port_planes.offset_rounding),
                              normal_tolerance=port_planes.normal_tolerance, skip=fixed)
    if not diffs:
        return None, []
    vertex, kind, text = diffs[0]
    more = f"; {len(diffs)} vertices' planes differ in this step" if len(diffs) > 1 else ""
    return (StepCheck(k, "contacts differ", float(err.max()), vertex, tolerance=tol,
                      note=f"{text} ({decision_numbers(held, vertex, kind)}){more} (the "
                           f"port's planes: {port_planes.path.name})"),
            [(u, kind) for u, kind, _ in diffs])


#: Where to look, per kind of plane difference (:func:`plane_differences`).
LOOK = {
    "clothsim": "look at how the port catches a vertex (entry into the obstacle grown by its "
                "thickness) and keeps it (released only when F < 0)",
    "port": "look at the port's release rule (F < 0 releases) and its obstacle's size",
    "stick": "look at the port's static friction (sticks while |F_t| <= μ F_n)",
    "slide": "look at the port's static friction (sticks while |F_t| <= μ F_n)",
    "plane": "look at the port's contact normal and offset (the obstacle's size, its "
             "thickness)",
}


#: Where to look, per contact treatment a port uses instead (:data:`VARIANTS`).
VARIANT_LOOK = {
    "post-solve": "the port's contact handling: vertices in contact held on their planes in "
                  "the solve ([contact] mode = \"hold\"), not projected after it",
    "frictionless": "the port's friction on held vertices (sticking planes, kinetic friction "
                    "μ F_n against the tangential velocity)",
    "flipped": "the sign of the port's contact normal where it reads the contact force "
               "n · grad g / h²",
}


def decision_numbers(held, v: int, kind: str) -> str:
    """The numbers behind clothsim's decision for vertex v, and where the port should look.

    Parameters
    ----------
    held : HeldSteps
        Anchored at the step.
    v : int
    kind : str
        The plane difference (:func:`clothsim.ports.plane_diff.plane_differences`).

    Returns
    -------
    str
        E.g. "clothsim's contact force 0.0123 N from step 9 -> 10 (a new contact, 1.2e-03 m
        deep), thickness 0.0326 m; look at …".
    """
    parts = []
    for e, h in held.planes():
        i = np.flatnonzero(h.vertices == v)
        if not len(i):
            continue
        f = float(h.normal_force[i[0]])
        new = not any(np.any(p.vertices == v) for _, p in held.previous_planes())
        mass = float(held.sim.model.vertex_mass[v])
        depth = (f" (a new contact, {f * held.sim.h ** 2 / mass:.2e} m deep)"
                 if new and mass > 0 else "")
        parts.append(f"clothsim's contact force on it {f:.3g} N{depth}, friction μ = "
                     f"{e.friction:g}, thickness {e.margin:.3g} m")
        break
    for e, h in held.previous_planes():
        i = np.flatnonzero(h.vertices == v)
        if len(i) and h.planes.forces is not None:
            R = h.reaction()[i[0]]
            fn = float(R @ h.normals[i[0]])
            ft = float(np.linalg.norm(R - fn * h.normals[i[0]]))
            parts.append(f"in the step before: F_n = {fn:.3g} N, |F_t| = {ft:.3g} N against "
                         f"μ F_n = {e.friction * fn:.3g} N")
            break
    return "; ".join(parts + [LOOK.get(kind, LOOK["plane"])])


def on_port_planes(err, tol) -> str:
    """What clothsim's step says of the port's solve on the port's own planes.

    Parameters
    ----------
    err : ndarray, shape (n,)
        |x_clothsim − x_port| [m], clothsim's step held on the port's planes.
    tol : float

    Returns
    -------
    str
    """
    w = int(np.argmax(err))
    if err[w] <= tol:
        return (f"on the port's own planes clothsim's step is the port's answer (max error "
                f"{err[w]:.3e} m): its solve is right, its contact decision differs")
    return (f"on the port's own planes too, its answer is {err[w]:.3e} m from clothsim's "
            f"step (vertex {w})")


def variant_verdict(k, held, state, x_port, err, tol) -> tuple[StepCheck | None, float]:
    """``contacts differ`` when another contact treatment reproduces the port's step.

    Parameters
    ----------
    k : int
    held : HeldSteps
        Anchored at the port's x_k, stepped.
    state : State
        The port's state of the step.
    x_port : ndarray, shape (n, 3)
        The port's x_{k+1} [m].
    err : ndarray, shape (n,)
        |x_clothsim − x_port| [m].
    tol : float

    Returns
    -------
    (StepCheck or None, float)
        The verdict, and how far the variant named lands from the port's answer [m]
        (inf when none is named).
    """
    rows = clothsim_rows(held.planes())
    worst = int(np.argmax(err))
    for variant, words in VARIANTS.items():
        if not rows and variant != "flipped":
            continue          # nothing held: only a decision of the step before can differ
        if variant == "frictionless" and not any(e.friction > 0 for e in held.obstacles):
            continue
        x = held.replay(state, variant)
        if x is None:
            continue
        off = float(np.linalg.norm(x - x_port, axis=1).max())
        if off <= tol or off * NEARER <= err[worst]:
            return StepCheck(k, "contacts differ", float(err[worst]), worst, tolerance=tol,
                             note=f"the port's step is clothsim's from the same state when "
                                  f"it {words} ({off:.1e} m from the port's answer, against "
                                  f"{err[worst]:.1e} m for clothsim's step); clothsim "
                                  f"{_held_words(rows, err, variant, held)}; look at "
                                  f"{VARIANT_LOOK[variant]}"), off
    return None, np.inf


def _held_words(rows, err, variant, steps) -> str:
    """What clothsim holds that the variant treats otherwise, naming a vertex."""
    if variant == "flipped":
        theirs = clothsim_rows(steps.replayed)
        only = [(v, "by clothsim, released by such a port") for v in set(rows) - set(theirs)]
        only += [(v, "by such a port, free in clothsim") for v in set(theirs) - set(rows)]
        if not only:
            return "and such a port hold the same vertices in this step"
        v, words = max(only, key=lambda item: (err[item[0]], -item[0]))
        r = (rows.get(v) or theirs[v])[0]
        return (f"and such a port hold {len(only)} vertices differently in this step: vertex "
                f"{v} held on {face_name(r[0], r[1])} {words}")
    held = np.array(sorted(rows))
    sticking = np.array([v for v in held if any(r[3] for r in rows[v])], np.int64)
    if variant == "frictionless" and len(sticking):
        v = int(sticking[np.argmax(err[sticking])])
        return (f"holds {len(sticking)} vertices still by static friction: vertex {v} sticks "
                f"on {face_name(rows[v][0][0], rows[v][0][1])} in clothsim, slides in the "
                f"port ({err[v]:.3e} m apart)")
    v = int(held[np.argmax(err[held])]) if err[held].max() > 0 else int(held[0])
    face = face_name(rows[v][0][0], rows[v][0][1])
    if variant == "frictionless":
        return (f"slows its {len(held)} sliding held vertices by kinetic friction (vertex {v} "
                f"on {face})")
    return (f"holds {len(held)} vertices on their contact planes in the solve: vertex {v} "
            f"held on {face} by clothsim, free in the port's solve")


def off_plane_note(held, x_port, tol) -> str:
    """The held vertex the port's answer leaves farthest off clothsim's plane, if > tol.

    Parameters
    ----------
    held : HeldSteps
    x_port : ndarray, shape (n, 3)
        The port's x_{k+1} [m].
    tol : float

    Returns
    -------
    str
        "" when every held vertex ends on its plane (as clothsim's answers do).
    """
    best, text = tol, ""
    for e, hold in held.planes():
        c, m = hold.planes, len(hold.vertices)
        if not m:
            continue
        v, n, o = c.vertices[:m], c.normals[:m], c.offsets[:m]
        gap = np.abs(np.einsum("ij,ij->i", x_port[v], n) - o)
        i = int(np.argmax(gap))
        if gap[i] > best:
            best = float(gap[i])
            text = (f"vertex {int(v[i])}, held on {face_name(e, n[i])} by clothsim, ends "
                    f"{best:.3e} m off that plane in the port's answer: the port does not "
                    f"hold it there")
    return text


__all__ = ["NEARER", "off_plane_note", "on_port_planes", "planes_verdict", "variant_verdict"]
