"""An external force that differs on some vertices only, or in its non-gravity part: fitted
per vertex by replays.

The hypotheses of :mod:`clothsim.ports.replayed` change a few parameters of the whole model
(a force per vertex, a stiffness, h). A port whose impulse pushes twice as hard, on a
wider disk, or whose wind drags twice as much, solves a model whose external force differs
on some vertices, or in proportion to the scene's forces other than gravity, and no few
parameters reproduce it: the step was left UNDECIDED ("start-dependent: the port iterates
otherwise").

Here the force difference Δf is fitted per vertex: with clothsim's replay x_r of the step
under f + Δf, the step's gradient under the scene's model differs at the two answers by
about the force that moves x_r to the port's answer, so Δf ← Δf + (∇g(x_port) − ∇g(x_r)) /
h² (a Newton step whose Hessian is the replayed iteration's), repeated until the replay
reproduces the port's answer. Since a force on every vertex reproduces any answer, the
fitted Δf is named only when it is

- the scene's external forces other than gravity × a factor (the replay with that
  multiple alone reproduces the step), or
- confined to a small share of the cloth (:data:`SHARE`): the replay with Δf on those
  vertices alone reproduces the step;

and, either way, reproduces every fitted step (the same factor, or the same Δf).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .hypotheses import residual
from .replays import replay

#: Newton steps on the per-vertex force (each one replay), the Anderson memory, and the
#: share of the scene's distance the rough fit stops at.
ITERATIONS = 20
MEMORY = 3
ROUGH = 0.02
#: The vertices a confined force acts on: those of at least this share of its largest.
SUPPORT = 0.05
#: Largest share of the free vertices a force confined to some vertices may act on.
SHARE = 0.25

__all__ = ["force_field_cause", "reproduced"]


def _others(step) -> np.ndarray | None:
    """The scene's external force of the step other than gravity (n, 3) [N], or None."""
    f = step.problem.f_ext
    if f is None:
        return None
    g = np.zeros(3) if step.gravity is None else np.asarray(step.gravity, float)
    return f - step.model.vertex_mass[:, None] * g[None, :]


def _fitted(step):
    """A rough per-vertex Δf (n, 3) [N]: the replays' Newton steps, Anderson-accelerated
    (the replayed iteration stops short, so it moves less than the converged Hessian says
    and plain steps converge slowly), until the replay is within :data:`ROUGH` of the
    scene's distance; None when the replays fail."""
    p = step.problem
    free = p.free_mask(len(step.x_port))[:, None]
    h2 = p.h ** 2
    r_port = residual(step)
    df = np.zeros_like(step.x_port)
    xs, gs = [], []
    for _ in range(ITERATIONS):
        x = replay(step, "force field", df, positions=True)
        if x is None or not np.isfinite(x).all():
            return None
        if float(np.linalg.norm(x - step.x_port, axis=1).max()) <= ROUGH * step.error:
            break
        g = np.where(free, r_port - residual(dataclasses.replace(step, x_port=x, cache={})),
                     0.0).ravel() / h2
        xs, gs = (xs + [df.ravel()])[-MEMORY:], (gs + [g])[-MEMORY:]
        change = g
        if len(gs) > 1:
            dG = np.diff(np.array(gs), axis=0).T
            dX = np.diff(np.array(xs), axis=0).T
            change = g - (dX + dG) @ np.linalg.lstsq(dG, g, rcond=None)[0]
        df = df + change.reshape(df.shape)
    return df


def _linear(step, basis, reproduces):
    """θ of Δf = Σ θ_j B_j fitted on the replays (the step's answer linear in the force
    near the scene's, twice: Gauss–Newton), and the replay's distance; None when the fit
    does not reproduce the step."""
    def run(field):
        x = replay(step, "force field", field, positions=True)
        return None if x is None or not np.isfinite(x).all() else x

    theta = np.zeros(len(basis))
    for _ in range(2):
        base = run(sum(t * b for t, b in zip(theta, basis)) if len(basis) else 0.0)
        cols = [run(sum(t * b for t, b in zip(theta, basis)) + b) for b in basis]
        if base is None or any(c is None for c in cols):
            return None
        A = np.stack([(c - base).ravel() for c in cols], axis=1)
        theta = theta + np.linalg.lstsq(A, (step.x_port - base).ravel(), rcond=None)[0]
        field = sum(t * b for t, b in zip(theta, basis))
        d = replay(step, "force field", field)
        if reproduces(step, d):
            return theta, field
    return None


def force_field_cause(steps, reproduces, fitted: int = 2, parts=("others", "vertices")):
    """A force difference on some vertices, or of the scene's non-gravity forces, whose
    replays reproduce the fitted steps.

    Parameters
    ----------
    steps : list of StepData
        The failing steps: the first is fitted, the first ``fitted`` must be reproduced,
        the later ones are replayed and explained when reproduced.
    reproduces : callable
        ``reproduces(step, distance) -> bool``: a replay this far from the port's answer
        reproduces it.
    fitted : int, default 2
        The steps the force must reproduce.
    parts : sequence of {"others", "vertices"}
        The forms tried: the scene's non-gravity forces × a factor (a few replays), a
        force fitted per vertex (tens).

    Returns
    -------
    (str, str, dict) or None
        The force in words, the hypothesis' name and step k → the replay's distance [m]
        of the steps it reproduces.
    """
    first = steps[0]
    others = _others(first)
    if "others" in parts and others is not None and np.any(others):   # the impulse, … × c
        fit = _linear(first, [others], reproduces)
        if fit is not None:
            c = float(fit[0][0])
            d = _reproduced(steps, fitted, reproduces, lambda s: c * _others(s))
            if d is not None:
                return (f"the scene's external forces other than gravity × {1 + c:.3f}",
                        "other forces", d)
    df = _fitted(first) if "vertices" in parts else None
    if df is None or not np.any(df):
        return None
    size = np.linalg.norm(df, axis=1)
    where = np.flatnonzero(size >= SUPPORT * size.max())
    if len(where) > SHARE * int(first.problem.free_mask(len(df)).sum()):
        return None
    units = []
    for c in range(3):
        u = np.zeros_like(df)
        u[where, c] = 1.0
        units.append(u)
    local = np.zeros_like(df)
    local[where] = df[where]
    for basis in (units, [local]):   # the same force on each of those vertices, or Δf there
        fit = _linear(first, basis, reproduces)
        if fit is None:
            continue
        field = fit[1]
        d = _reproduced(steps, fitted, reproduces, lambda s, f=field: f)
        if d is not None:
            return _words(first, where, field), "vertex forces", d
    return None


def _reproduced(steps, fitted, reproduces, field):
    """Step k → the replay's distance with ``field(step)`` added, for the steps it
    reproduces; None unless it reproduces the first ``fitted``."""
    return reproduced(steps, fitted, reproduces,
                      lambda s: replay(s, "force field", field(s)))


def reproduced(steps, fitted, reproduces, distance):
    """Step k → ``distance(step)`` (a replay's distance from the port's answer [m]) for
    the steps it reproduces.

    Parameters
    ----------
    steps : list of StepData
    fitted : int
        The first steps that must be reproduced.
    reproduces : callable
        ``reproduces(step, distance) -> bool``.
    distance : callable
        ``distance(step) -> float``.

    Returns
    -------
    dict or None
        None unless the first ``fitted`` steps are reproduced.
    """
    d = {}
    for i, s in enumerate(steps):
        dk = distance(s)
        if reproduces(s, dk):
            d[s.k] = dk
        elif i < fitted:
            return None
    return d


def _words(step, where, field) -> str:
    x = step.problem.x[where]
    centre = x.mean(axis=0)
    reach = float(np.linalg.norm(x - centre, axis=1).max())
    scene = (step.problem.f_ext[where].sum(axis=0) if step.problem.f_ext is not None
             else np.zeros(3))
    each = field[where]
    same = np.allclose(each, each[0], rtol=1e-3, atol=1e-12 * np.abs(each).max())
    return (f"an external force that differs on {len(where)} of {len(field)} vertices only "
            f"(vertices {_listing(where)}, within {reach:.3g} m of ({_vec(centre)}) m at "
            f"x_k): ({_vec(field[where].sum(axis=0))}) N more there in all"
            f"{f' (({_vec(each[0])}) N on each)' if same else ''}, beside the scene's "
            f"({_vec(scene)}) N on them")


def _vec(v) -> str:
    return ", ".join(f"{float(c):.3g}" if abs(c) > 1e-12 else "0" for c in v)


def _listing(where, limit=6) -> str:
    shown = ", ".join(str(int(i)) for i in where[:limit])
    return shown + (f", … ({len(where)} in all)" if len(where) > limit else "")
