"""A spring topology that differs: springs missing, or counted twice, named from the port's step.

A topology is no parameter of the model, so the hypotheses of
:mod:`clothsim.ports.replayed` (a stiffness scale of all springs, or of one family) cannot
reproduce a port that left out one shear diagonal of each quad, or that added a few
springs twice. The port's forces still tell which springs: a spring i of stiffness
k_i (1 + θ_i) instead of k_i adds the force −θ_i k_i (p_i − r_i p_i / |p_i|) at its vertex
a and the opposite at b (p_i = x_a − x_b), and the step's gradient of the scene's g at the
port's answer and at clothsim's replay of the step differ by about h² times the force
that moves one to the other (as in :mod:`clothsim.ports.force_field`). That force
difference is fitted, in least squares, with a few springs' scales:

- per group of springs that share a family and a rest direction (the two shear diagonals
  of a grid, its horizontal and vertical structural springs): a group whose scale is
  clearly −1 (left out) or +1 (counted twice), the others about 0;
- else per spring: the springs whose forces best match it are chosen one at a time
  (orthogonal matching pursuit, up to :data:`MOST`), as many next best matches join them,
  and each of those springs' doubling is replayed alone; the port's answer, taken as
  linear in those replays, gives each spring's scale (a spring near its rest length
  exerts little force but still stiffens the step: the replays see it, the forces hardly).

Each scale is rounded to a whole number of copies (−1 missing, +1 twice), and clothsim's
step is replayed with those springs removed or doubled; the topology is named only when
that replay reproduces the port's answer on the fitted steps (as any replayed cause). Up
to :data:`ROUNDS` rounds refit the force difference left after the springs found so far
(each one replay, and one per spring new to the pool), while each comes at least twice as
near the port's answer as the one before.
"""

from __future__ import annotations

import dataclasses
from functools import partial

import numpy as np
import scipy.sparse as sp

from ..errors import ClothsimError
from ..model import Model
from ..springs import FAMILIES, Springs
from .force_field import reproduced
from .hypotheses import residual

__all__ = ["topology_cause"]

#: Most single springs named (beyond them a group or nothing).
MOST = 40
#: A group's or spring's scale within this of a whole number of copies is that number.
WHOLE = 0.25
#: A group of springs sharing a family and a direction holds at least this many springs.
GROUP = 4
#: Most groups whose removal or doubling is replayed one by one.
MOST_GROUPS = 12
#: A topology that reproduces a step within this share of its tolerance is not refined
#: further (a coarse printing's tolerance would take a spring beside the right one).
NEAR = 0.1
#: Rounds of fit and replay (each one replay per fitted step).
ROUNDS = 6
#: Springs beside the chosen ones whose doubling or removal is replayed.
EXTRA = 4
#: Matching pursuit stops when the force left is below this share of the force difference.
LEFT = 0.02


def _solve(step, scale):
    """clothsim's step with spring i's stiffness × (1 + scale_i); None when it fails."""
    model = step.model
    s = model.springs
    k = np.maximum(1.0 + scale, 0.0) * s.spring_stiffness
    springs = Springs(s.spring_vertices, k, s.spring_rest_length, s.spring_family,
                      s.vertex_count, s.spring_damping)
    try:
        x = step.solve(Model(model.mesh, springs, model.vertex_mass), step.problem)
    except (ClothsimError, ArithmeticError, ValueError, RuntimeError):
        return None
    return x if np.isfinite(x).all() else None


def _distance(step, x) -> float:
    return float("inf") if x is None else float(np.linalg.norm(x - step.x_port, axis=1).max())


def _columns(step, free):
    """Per spring, over the free vertices' coordinates (3 n_free × s, sparse): the force
    its unit scale adds at the port's answer, −k_i (p_i − r_i p_i / |p_i|) at a and the
    opposite at b; and the pull of its linear part on the step's displacement,
    −k_i (p_i(x_port) − p_i(x_k)) (an iteration that stops short resists a spring's turn
    too: a spring near its rest length shows there, not in its force)."""
    s = step.model.springs
    x = step.x_port
    a, b = s.spring_vertices.T
    vec = x[a] - x[b]
    length = np.linalg.norm(vec, axis=1)
    unit = vec / np.where(length > 0, length, 1.0)[:, None]
    k = s.spring_stiffness[:, None]
    moved = vec - (step.problem.x[a] - step.problem.x[b])
    return [_scattered(-k * (vec - s.spring_rest_length[:, None] * unit), a, b, free),
            _scattered(-k * moved, a, b, free)]


def _scattered(per_spring, a, b, free):
    row = np.cumsum(free) - 1                   # free vertex → its row block
    springs = np.arange(len(a))
    rows, cols, vals = [], [], []
    for end, sign in ((a, 1.0), (b, -1.0)):
        keep = free[end]
        for c in range(3):
            rows.append(3 * row[end[keep]] + c)
            cols.append(springs[keep])
            vals.append(sign * per_spring[keep, c])
    return sp.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(3 * int(free.sum()), len(a)))


def _groups(step) -> list[tuple[str, np.ndarray]]:
    """(name, springs) of each family and rest direction shared by :data:`GROUP` springs."""
    s = step.model.springs
    x0 = step.model.mesh.vertices
    a, b = s.spring_vertices.T
    d = x0[b] - x0[a]
    d = d / np.maximum(np.linalg.norm(d, axis=1), 1e-300)[:, None]
    first = np.argmax(np.abs(d) > 1e-9, axis=1)     # the direction up to its sign
    d = d * np.sign(d[np.arange(len(d)), first])[:, None]
    key = np.round(d, 6)
    out = []
    for f in np.unique(s.spring_family):
        in_family = s.spring_family == f
        directions, inverse = np.unique(key[in_family], axis=0, return_inverse=True)
        members = np.flatnonzero(in_family)
        for j, u in enumerate(directions):
            which = members[inverse.ravel() == j]
            if len(which) >= GROUP and len(directions) > 1:
                out.append((f"the {FAMILIES[f]} springs along ({_vec(u)})", which))
    return out


def _vec(u) -> str:
    return ", ".join(f"{c:.3g}" if abs(c) > 1e-9 else "0" for c in u)


def _difference(step, x_replay, free):
    """The force difference (3 n_free,) [N] that moves the replay to the port's answer."""
    h2 = step.problem.h ** 2
    there = dataclasses.replace(step, x_port=x_replay, cache={})
    return ((residual(step) - residual(there))[free] / h2).ravel()


def _whole(theta):
    r = np.round(theta)
    return np.where(np.abs(theta - r) <= WHOLE, r, np.nan)


def _by_groups(step, x0, B, df, groups, replayed: bool):
    """Spring scales of whole groups: each group's scale fitted to the force difference
    (``replayed``: to the port's answer on one replay per group, the group removed or
    doubled as its force fit's sign says), rounded as :func:`_rounded`; None unless
    some group comes out whole and not 0."""
    if not groups or (replayed and len(groups) > MOST_GROUPS):
        return None
    G = np.stack([np.asarray(B[:, w].sum(axis=1)).ravel() for _, w in groups], axis=1)
    theta = np.linalg.lstsq(G, df, rcond=None)[0]
    if replayed:
        signs = np.where(theta < 0, -1.0, 1.0)
        cols = []
        for (_, w), sign in zip(groups, signs):
            e = np.zeros(B.shape[1])
            e[w] = sign
            x = _solve(step, e)
            if x is None:
                return None
            cols.append((x - x0).ravel())
        theta = signs * np.linalg.lstsq(np.stack(cols, axis=1), (step.x_port - x0).ravel(),
                                        rcond=None)[0]
    whole = _whole(theta)
    if np.isnan(whole).any() or not np.any(whole):
        return None
    scale = np.zeros(B.shape[1])
    for (_, w), t in zip(groups, whole):
        scale[w] = max(t, -1.0)
    return scale


def _score(B, r):
    """|B_iᵀ r| / |B_i| per column (0 for a column of nothing)."""
    norms = np.sqrt(np.asarray(B.multiply(B).sum(axis=0)).ravel())
    seen = norms > 1e-12 * max(float(norms.max(initial=0.0)), 1e-300)
    return np.abs(B.T @ r) / np.where(seen, norms, np.inf), norms


def _pursuit(B, D, df):
    """The springs whose forces (columns of ``B``) explain the force difference, chosen
    one at a time (orthogonal matching pursuit) while each comes out a whole copy; and
    the next best matches of what is left, by force and by the pull on the step's
    displacement (``D``), at least :data:`EXTRA` of each: {spring: fitted scale} of both."""
    chosen: list[int] = []
    r, theta = df.copy(), np.zeros(0)
    while len(chosen) < MOST and np.linalg.norm(r) > LEFT * np.linalg.norm(df):
        score, _ = _score(B, r)
        score[chosen] = 0.0
        i = int(np.argmax(score))
        if score[i] <= 0:
            break
        Bc = B[:, chosen + [i]].toarray()
        fit = np.linalg.lstsq(Bc, df, rcond=None)[0]
        if np.isnan(_whole(fit[-1:]))[0] or round(fit[-1]) == 0:
            break          # no whole copy more: what is left is the linearization's
        chosen.append(i)
        theta, r = fit, df - Bc @ fit
    more = {}
    for C in (B, D):
        score, norms = _score(C, r)
        score[chosen] = 0.0
        for i in np.argsort(score)[::-1][:max(len(chosen), EXTRA)]:
            if score[i] > 0 and int(i) not in more:
                more[int(i)] = float((C[:, i].T @ r)[0]) / norms[i] ** 2
    return dict(zip(chosen, theta)), more


def _rounded(scale, added: dict):
    """``scale`` with whole scales of the springs added; None when most are not whole or
    all are 0."""
    if not added:
        return None
    whole = _whole(np.array(list(added.values())))
    if not np.any(np.nan_to_num(whole)) or np.isnan(whole).mean() > 0.5:
        return None
    out = scale.copy()
    out[list(added)] += np.nan_to_num(whole)
    return np.maximum(out, -1.0)


def _by_replays(step, x0, pool: dict, columns: dict):
    """Spring scales of the pool fitted to the port's answer on replays: each spring
    removed (fitted scale < 0) or doubled alone and replayed (cached in ``columns``), the
    answer taken as linear in those; rounded as :func:`_rounded`."""
    size = len(step.model.springs.spring_stiffness)
    use = {}
    for j, t in pool.items():
        sign = -1.0 if t < 0 else 1.0
        if (j, sign) not in columns:
            e = np.zeros(size)
            e[j] = sign
            x = _solve(step, e)
            columns[j, sign] = None if x is None else (x - x0).ravel()
        if columns[j, sign] is not None:
            use[j] = sign
    if not use:
        return None
    J = np.stack([columns[j, sign] for j, sign in use.items()], axis=1)
    theta = np.linalg.lstsq(J, (step.x_port - x0).ravel(), rcond=None)[0]
    return _rounded(np.zeros(size), {j: t * use[j] for j, t in zip(use, theta)})


def topology_cause(steps, reproduces, fitted: int = 2):
    """Springs missing or counted twice whose replays reproduce the fitted steps.

    Parameters
    ----------
    steps : list of StepData
        The failing steps: the first is fitted, the first ``fitted`` must be reproduced,
        the later ones are replayed and explained when reproduced.
    reproduces : callable
        ``reproduces(step, distance) -> bool``.
    fitted : int, default 2

    Returns
    -------
    (str, str, dict) or None
        The topology in words, the hypothesis' name and step k → the replay's distance
        [m] of the steps it reproduces.
    """
    first = steps[0]
    if first.solve is None:
        return None
    free = first.problem.free_mask(len(first.x_port))
    B, D = _columns(first, free)
    groups = _groups(first)
    scale = np.zeros(B.shape[1])
    x0 = x = _solve(first, scale)
    if x is None:
        return None
    pool: dict = {}
    columns: dict = {}
    tried, named, previous = [], None, None
    for round_ in range(ROUNDS):   # the difference the springs found so far leave:
        df = _difference(first, x, free)   # springs added to them
        if not np.any(df):
            break
        forces, more = _pursuit(B, D, df)
        pool.update({j: t + scale[j] for j, t in (more | forces).items()})
        fits = [] if round_ else [   # whole groups (on the forces, on replays), the
            partial(_by_groups, first, x0, B, df, groups, False),   # springs' forces'
            partial(_by_groups, first, x0, B, df, groups, True)]    # scales, the replays'
        fits += [partial(_rounded, scale, forces),
                 partial(_by_replays, first, x0, pool, columns)]
        best = None
        for fit in fits:
            found = fit()
            if found is None or any(np.array_equal(found, t) for t in tried):
                continue
            tried.append(found)
            xf = _solve(first, found)
            d = _distance(first, xf)
            if best is None or d < best[0]:
                best = (d, found, xf)
            if reproduces(first, d) and d <= NEAR * first.tolerance:
                break
        if best is None:
            break
        d, scale, x = best
        if reproduces(first, d):   # and a round more while it is not well within the tolerance
            better = named is None or d <= 0.5 * named[0]
            if named is None or d < named[0]:
                named = (d, scale)
            if d <= NEAR * first.tolerance or not better:
                break
        elif previous is not None and d > 0.5 * previous:
            break       # a round that comes no nearer: the springs do not explain it
        previous = d
    if named is None:
        return None
    found = reproduced(steps, fitted, reproduces,
                       lambda s: _distance(s, _solve(s, named[1])))
    return None if found is None else (_words(first, named[1], groups), "topology", found)


def _words(step, scale, groups) -> str:
    s = step.model.springs
    parts = []
    for name, w in groups:
        if len(w) and np.all(scale[w] == scale[w[0]]) and scale[w[0]] != 0:
            parts.append(f"{name} {_copies(scale[w[0]])} ({len(w)} springs: "
                         f"{_ranges(w)})")
            scale = scale.copy()
            scale[w] = 0
    for t in np.unique(scale[scale != 0]):
        which = np.flatnonzero(scale == t)
        pairs = ", ".join(f"{a}-{b}" for a, b in s.spring_vertices[which[:6]])
        parts.append(f"{len(which)} spring{'s' if len(which) > 1 else ''} {_copies(t)}: "
                     f"spring{'s' if len(which) > 1 else ''} {_ranges(which)} (vertices "
                     f"{pairs}{', …' if len(which) > 6 else ''})")
    return "a spring topology that differs: " + "; ".join(parts)


def _copies(t) -> str:
    t = int(t)
    if t == -1:
        return "missing"
    if t == 1:
        return "counted twice"
    return f"counted {t + 1} times" if t > 0 else "missing"


def _ranges(index, limit=8) -> str:
    index = np.sort(np.asarray(index))
    runs, start = [], 0
    for i in range(1, len(index) + 1):
        if i == len(index) or index[i] != index[i - 1] + 1:
            a, b = index[start], index[i - 1]
            runs.append(f"{a}" if a == b else f"{a}-{b}")
            start = i
    return ", ".join(runs[:limit]) + (f", … ({len(runs)} runs)" if len(runs) > limit else "")
