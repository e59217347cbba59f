"""Clothsim's step under a changed model: the replays behind a fitted cause.

:func:`variant` applies a hypothesis' parameters θ (:mod:`clothsim.ports.hypotheses`) to a
step's model and problem; :func:`replay` runs clothsim's step on it with the check's
solver settings; :func:`approach` measures how far the port's answer went towards the
changed model's minimizer (found by Newton's method) and towards the scene's.
:class:`Factors` keeps the factors of M + h² L a check's replays share.
"""

from __future__ import annotations

import dataclasses
import hashlib
from collections import OrderedDict

import numpy as np

from ..errors import ClothsimError
from ..model import Model
from ..solvers.held import held_start
from ..springs import FAMILIES, Springs
from .hypotheses import ADDING, REPLACING, StepData

#: Factors of M + h² L a check's replays keep (the least recently used is dropped first) ...
SHARED = 4
#: ... and their vertices in all, at most (one is kept whatever the cloth's size: a 513²
#: cloth's factor is hundreds of MB).
SHARED_VERTICES = 200_000


class Factors:
    """The factors of M + h² L (and of a held step's constrained system) that a check's
    replays share.

    The matrices depend only on the masses, stiffnesses, springs, h, pins and held
    contacts: a changed force (gravity, a force per vertex, a force field) or rest length,
    and every step of the same h, pins and contacts, replay on the same ones, and a fitted
    θ is replayed again on each fitted step. Each replay still runs a fresh solver (its
    carried state, e.g. a spring's direction or Chebyshev's ρ, is its own); only the
    factors its first solve would make are taken from an earlier replay of the same
    matrices, so the replays are bit for bit those of unshared factors.

    Parameters
    ----------
    size : int, default :data:`SHARED`
        Factors kept, at most :data:`SHARED_VERTICES` vertices' worth (at least one).
    """

    def __init__(self, size: int = SHARED):
        self.size = size
        self._kept: OrderedDict = OrderedDict()

    def solve(self, solver, model, problem):
        """``solver.solve(problem)`` on the shared factors of ``model``'s matrices.

        Parameters
        ----------
        solver : Solver
            A fresh solver of ``model`` (one without ``adopt_system``, e.g. Newton's,
            factors what it needs itself).
        model : Model
        problem : StepProblem

        Returns
        -------
        StepResult
        """
        adopt = getattr(solver, "adopt_system", None)
        if adopt is not None and self.size > 0:
            key = _matrix_key(model, problem)
            kept = self._kept.get(key)
            if kept is None:   # the factors the solver's first solve makes, kept
                self._kept[key] = (solver.system(problem), held_start(solver, problem)[0]
                                   if problem.has_contacts else None)
                keep = max(1, min(self.size, SHARED_VERTICES // max(model.vertex_count, 1)))
                while len(self._kept) > keep:
                    self._kept.popitem(last=False)
            else:
                adopt(problem, *kept)
                self._kept.move_to_end(key)
        return solver.solve(problem)


def _matrix_key(model: Model, problem) -> bytes:
    """A digest of what M + h² L over the free vertices and the held contacts' system are
    made of."""
    sp = model.springs
    digest = hashlib.blake2b(digest_size=32)
    for a in (model.vertex_mass, sp.spring_stiffness, sp.spring_vertices,
              np.float64(problem.h), problem.fixed_vertices, problem.anchor_vertices,
              problem.anchor_stiffness, problem.contact_vertices, problem.contact_normals):
        a = np.ascontiguousarray(a)
        digest.update(f"{a.dtype.str}{a.shape}".encode())
        digest.update(a.tobytes())
    return digest.digest()


def variant(step: StepData, hypothesis: str, theta) -> tuple:
    """The step's (model, problem) with the hypothesis' parameters θ applied.

    Parameters
    ----------
    step : StepData
    hypothesis : str
    theta : ndarray

    Returns
    -------
    (Model, StepProblem)
    """
    model, p = step.model, step.problem
    sp = model.springs
    k, r, mass = sp.spring_stiffness, sp.spring_rest_length, model.vertex_mass
    one = 1.0 + float(np.ravel(theta)[0])
    if hypothesis == "stiffness":
        k = max(one, 0.0) * k
    elif hypothesis == "rest lengths":
        r = max(one, 0.0) * r
    elif hypothesis == "stiffness and rest lengths":
        k, r = max(one, 0.0) * k, max((1.0 + theta[1]) / one, 0.0) * r
    elif hypothesis.startswith("family "):
        mask = sp.spring_family == FAMILIES.index(hypothesis.split()[1])
        k = np.where(mask, max(one, 0.0) * k, k)
    elif hypothesis.startswith("rest lengths "):
        mask = sp.spring_family == FAMILIES.index(hypothesis.split()[-1])
        r = np.where(mask, max(one, 0.0) * r, r)
    elif hypothesis == "inertia":
        mass = max(one, 0.0) * mass
    elif hypothesis == "vertex mass":   # θ per vertex: its mass and its (gravity) force
        scale = np.maximum(1.0 + np.asarray(theta), 0.0)
        mass = scale * mass
        f = np.zeros_like(step.x_port) if p.f_ext is None else p.f_ext
        p = dataclasses.replace(p, f_ext=f * scale[:, None])
    elif hypothesis == "time step":   # θ: h' / h − 1; the inertial target y moves with h
        h = max(one, 1e-6) * p.h       # (not with velocities derived as Δx / h: y = 2 x_k − x_k−1)
        p = dataclasses.replace(p, h=h, y=p.y if step.derived else p.x + (h / p.h) * (p.y - p.x))
    elif hypothesis == "pins":
        p = dataclasses.replace(p, anchor_stiffness=max(one, 0.0) * p.anchor_stiffness)
    else:
        f = np.zeros_like(step.x_port) if p.f_ext is None else p.f_ext
        if hypothesis == "vertex force":
            f = f * (1.0 + np.asarray(theta))[:, None]
        elif hypothesis == "force field":   # θ: the force added per vertex (n, 3) [N]
            f = f + np.asarray(theta).reshape(f.shape)
        elif hypothesis in ADDING:   # θ: the change of gravity [m/s²]
            f = f + mass[:, None] * np.asarray(theta)[None, :]
        else:   # REPLACING: θ is the force per vertex or per unit mass
            weight = np.ones(len(f)) if hypothesis == "force per vertex" else mass
            f = weight[:, None] * np.asarray(theta)[None, :]
        p = dataclasses.replace(p, f_ext=f)
    springs = Springs(sp.spring_vertices, k, r, sp.spring_family, sp.vertex_count,
                      sp.spring_damping)
    return Model(model.mesh, springs, mass), p


def replay(step: StepData, hypothesis: str, theta, *, positions: bool = False):
    """Clothsim's step under the changed model, with the check's solver settings.

    Parameters
    ----------
    step : StepData
    hypothesis : str
    theta : ndarray
    positions : bool, default False
        Return the positions instead of their distance from the port's answer.

    Returns
    -------
    float or ndarray
        max |x − x_port| [m] (inf without a solver, or when the step cannot be solved);
        with ``positions``, x (n, 3) [m] or None.
    """
    x = None
    if step.solve is not None:
        try:
            x = step.solve(*variant(step, hypothesis, theta))
        except (ClothsimError, ArithmeticError, ValueError, RuntimeError):
            x = None                          # a model that cannot be solved reproduces nothing
    if positions:
        return x
    return float("inf") if x is None else _distance(x - step.x_port)


def _distance(x_minus_port: np.ndarray) -> float:
    """max |x − x_port| over the vertices [m], inf where a replay went non-finite."""
    d = np.linalg.norm(x_minus_port, axis=1)
    return float(np.max(np.where(np.isfinite(d), d, np.inf)))


def approach(step: StepData, hypothesis: str, theta) -> tuple[float, float]:
    """How far the port's answer went towards the minimizer of the changed g, and of the scene's.

    Newton's method from the port's answer finds the minimizer x* of each; the ratio is
    max |x_port − x*| / max |x₀ − x*| (x₀ the step's initial guess): 0 at x*, 1 where the
    step started.

    Parameters
    ----------
    step : StepData
    hypothesis : str
    theta : ndarray

    Returns
    -------
    (float, float)
        The ratio for the changed model and for the scene's (inf when Newton fails).
    """
    import warnings

    from ..solvers.newton import NewtonSolver

    def ratio(model, problem) -> float:
        try:
            with warnings.catch_warnings():   # a minimizer near enough to compare with
                warnings.simplefilter("ignore")
                x = NewtonSolver(model, iterations=20, tolerance=1e-8).solve(
                    problem, step.x_port).x
        except (ClothsimError, ArithmeticError, ValueError, RuntimeError):
            return float("inf")
        start = float(np.linalg.norm(problem.initial_guess() - x, axis=1).max())
        went = float(np.linalg.norm(step.x_port - x, axis=1).max())
        return went / start if start > 0 else float("inf")

    if "scene" not in step.cache:
        step.cache["scene"] = ratio(step.model, step.problem)
    return ratio(*variant(step, hypothesis, theta)), step.cache["scene"]


def refine(fitted, hyp, theta, iterations: int, *, distances: bool = False):
    """θ that brings clothsim's replayed steps nearest the port's answers (Gauss–Newton,
    finite differences): the least-squares θ of an unconverged port is biased.

    Parameters
    ----------
    fitted : list of StepData
    hyp : str
    theta : ndarray
        The start (the gradient's least-squares θ).
    iterations : int
        Gauss–Newton iterations at most (each costs 1 + len(θ) replays per step).
    distances : bool, default False
        Also return what :func:`replay` gives for each fitted step at the returned θ, from
        the replays the refinement made there (no replay more).

    Returns
    -------
    ndarray
        θ; a scale of a hypothesis not in :data:`REPLACING` stays >= −1.
    dict
        With ``distances``: step k → max |x − x_port| at θ [m]; empty when a replay
        there failed (:func:`replay` would give inf: replay it to know which).
    """
    theta = np.array(theta, dtype=np.float64)

    def misfit(th):
        xs = [replay(s, hyp, th, positions=True) for s in fitted]
        if any(x is None for x in xs):
            return None
        return np.concatenate([(x - s.x_port).ravel() for x, s in zip(xs, fitted)])

    r = misfit(theta)
    for _ in range(iterations if r is not None and np.all(np.isfinite(r)) else 0):
        delta = 1e-6 * np.maximum(1.0, np.abs(theta))
        columns_ = []
        for j in range(len(theta)):
            step_ = theta.copy()
            step_[j] += delta[j]
            rj = misfit(step_)
            if rj is None:
                return (theta, _distances(fitted, r)) if distances else theta
            columns_.append((rj - r) / delta[j])
        change, *_ = np.linalg.lstsq(np.stack(columns_, 1), -r, rcond=None)
        if hyp not in REPLACING + ADDING:   # a scale stays >= 0 (the replay clamps it)
            change = np.maximum(theta + change, -1.0) - theta
        trial = misfit(theta + change)
        if trial is None or np.linalg.norm(trial) >= np.linalg.norm(r):
            break
        theta, r = theta + change, trial
        if np.all(np.abs(change) <= 1e-9 * np.maximum(1.0, np.abs(theta))):
            break
    return (theta, _distances(fitted, r)) if distances else theta


def _distances(fitted, r) -> dict:
    """Step k → :func:`replay`'s distance, from the misfit r of the fitted steps."""
    if r is None:
        return {}
    out, start = {}, 0
    for s in fitted:
        out[s.k] = _distance(r[start:start + s.x_port.size].reshape(s.x_port.shape))
        start += s.x_port.size
    return out
