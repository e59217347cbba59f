"""Causes for a port that stops after a fixed number of iterations: hypotheses tested by replay.

A port that runs the paper's 10 local/global iterations per step does not minimize any g,
so the gradient fits of :mod:`clothsim.ports.causes` cannot explain it. What it does is
clothsim's iteration, at the port's settings, on the port's model: each hypothesis of a
model fault is therefore tested by *replaying* clothsim's own iteration (the scene's
iteration count and start, from the port's previous state) with the hypothesised model
change. The parameters are fitted on the replays (Gauss–Newton with finite differences,
started from the gradient's least-squares θ), and a hypothesis is named when its replay
lands within the step's tolerance of the port's answer, or within :data:`REPLAY` of the
distance of clothsim's step of the scene's model, on every fitted step; of several, the
nearest (relative to the tolerance) is named, and the search stops at the first within
the tolerance. A port whose answer is its start point is left to the judge.

The hypotheses: those of :func:`clothsim.ports.hypotheses.applicable` (the inertia term's
scale replaced by another time step h, which also moves the inertial target y = x + h v),
and each other mass lumping (the scene's total mass spread as that lumping spreads it).
Two faults at once are explained by none of them: then nothing is named.
"""

from __future__ import annotations

import logging
import warnings

import numpy as np

from .cause_words import describe, lumpings, masses_text
from .force_field import force_field_cause
from .hypotheses import ADDING, REPLACING, StepData, applicable, fit
from .impulse_fit import impulse_cause
from .replays import refine, replay
from .topology import topology_cause

log = logging.getLogger(__name__)

__all__ = ["REPLAY", "replay_cause", "topology_replayed"]

#: A replay explains a step within the tolerance, or this share of the scene's distance.
REPLAY = 0.01
#: A hypothesis whose replay of the first failing step comes within this factor of
#: reproducing it, but not the next, is refined on the fitted steps jointly.
NEARLY = 10
#: Gauss–Newton iterations on the replays (each costs 1 + len(θ) replays).
REFINE = 6
#: Failing steps the hypotheses are fitted on jointly.
JOINT = 2
#: Further failing steps tested by one replay each with the fitted model.
MAX_REPLAYS = 8


def _candidates(steps) -> list:
    """(hypothesis, θ₀) to replay: fewest parameters first, then the other lumpings."""
    out = []
    for hyp in applicable(steps):
        theta = fit(steps[:1], hyp)
        if theta is None:
            continue
        if hyp == "inertia":         # M (x − y) / h² × (1 + θ): h' = h / √(1 + θ)
            one = float(1 + theta[0])
            hyp, theta = "time step", np.array([(1 / np.sqrt(one) if one > 0 else 1.0) - 1])
        out.append((hyp, np.asarray(theta, dtype=np.float64)))
    out.sort(key=lambda c: len(c[1]))
    s = steps[0]
    m = s.model.vertex_mass
    for _, unit in lumpings(s.model):
        other = unit * m.sum()
        if np.all(m > 0) and not np.allclose(other, m, rtol=1e-6, atol=0):
            out.append(("vertex mass", other / m - 1.0))
    return out


def _reproduces(step, d) -> bool:
    return d <= max(step.tolerance, REPLAY * step.error)


def replay_cause(steps: list[StepData]):
    """The single hypothesis whose replays reproduce the port's first failing steps.

    Parameters
    ----------
    steps : list of StepData
        The failing steps, in order, of a scene solved with a fixed iteration count
        (:attr:`StepData.settings` says which).

    Returns
    -------
    (str, dict) or None
        The cause's text and step k → distance of the fitted model's replay from the
        port's answer [m] for the steps it explains (the fitted ones and up to
        :data:`MAX_REPLAYS` later ones); None when no single hypothesis reproduces them.
    """
    if not steps or steps[0].solve is None:
        return None
    with warnings.catch_warnings():   # a replayed model may be badly conditioned
        warnings.simplefilter("ignore")
        return _first_reproducing(steps)


def _first_reproducing(steps):
    """The nearest reproducing hypothesis; the search stops at one within the tolerance."""
    fitted = steps[:JOINT]
    if any(float(np.linalg.norm(s.x_port - s.problem.initial_guess(), axis=1).max())
           <= s.tolerance for s in fitted):
        return None                     # a port that does not move: judge says so
    best = None
    first = fitted[0]
    for hyp, theta0 in _candidates(fitted):
        theta, d = ((np.maximum(theta0, -1.0), {}) if hyp == "vertex mass"
                    else _refined(fitted[:1], hyp, theta0))
        d[first.k] = d[first.k] if first.k in d else replay(first, hyp, theta)
        if d[first.k] > NEARLY * max(first.tolerance, REPLAY * first.error):
            log.debug("replayed %s, θ = %s: %s", hyp, theta, d)
            continue   # reproduces no step, and too far to be fitted jointly
        d.update({s.k: replay(s, hyp, theta) for s in fitted[1:]})
        if hyp != "vertex mass" and len(fitted) > 1 and not all(
                _reproduces(s, d[s.k]) for s in fitted):   # the first step alone does
            theta, d = _refined(fitted, hyp, theta)   # not place θ: a stiff cloth at rest
            # hardly sees h there; fitted on the steps jointly
            d.update({s.k: replay(s, hyp, theta) for s in fitted if s.k not in d})
        log.debug("replayed %s, θ = %s: %s", hyp, theta, d)
        if not all(_reproduces(s, d[s.k]) for s in fitted):
            continue
        score = max(d[s.k] / max(s.tolerance, 1e-300) for s in fitted)
        if best is None or score < best[0]:
            best = (score, hyp, theta, d)
        if score <= 1:                 # within the tolerance: no nearer hypothesis needed
            break
    if best is None:   # springs missing or doubled, a force on some vertices, or beside
        later = steps[:JOINT + MAX_REPLAYS]   # an impulse on another disk? gravity?
        field = (force_field_cause(later, _reproduces, len(fitted), ("others",))
                 or impulse_cause(later, _reproduces, len(fitted))
                 or topology_cause(later, _reproduces, len(fitted))
                 or force_field_cause(later, _reproduces, len(fitted), ("vertices",)))
        if field is None:
            return None
        what, hyp, d = field
        return _text(fitted, hyp, what, d), d
    _, hyp, theta, d = best
    for s in steps[JOINT:JOINT + MAX_REPLAYS]:
        dk = replay(s, hyp, theta)
        if _reproduces(s, dk):
            d[s.k] = dk
    return _text(fitted, hyp, theta, d), d


def topology_replayed(steps: list[StepData]):
    """A spring topology that differs (:mod:`clothsim.ports.topology`) whose replays at
    the scene's settings reproduce the steps: for a converged port, which no parameter
    fit explains.

    Parameters
    ----------
    steps : list of StepData

    Returns
    -------
    (str, dict) or None
        As :func:`replay_cause`.
    """
    if not steps or steps[0].solve is None:
        return None
    fitted = steps[:JOINT]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        found = topology_cause(steps[:JOINT + MAX_REPLAYS], _reproduces, len(fitted))
    return None if found is None else (_text(fitted, found[1], found[0], found[2]),
                                       found[2])


def _refined(fitted, hyp, theta):
    """:func:`~clothsim.ports.replays.refine`'s θ, a scale below −1 clamped (it is replayed
    as 0), and its replays' distances at that θ (empty when clamped or unknown)."""
    theta, d = refine(fitted, hyp, theta, REFINE, distances=True)
    if hyp not in REPLACING + ADDING and np.any(theta < -1.0):
        return np.maximum(theta, -1.0), {}
    return theta, d


def _text(fitted, hyp, theta, d) -> str:
    s = fitted[0]
    if isinstance(theta, str):   # a force fitted per vertex, in words
        what = theta
    elif hyp == "time step":
        h = s.problem.h
        what = f"h = {h * (1 + theta[0]):.4g} s instead of {h:.4g} s"
    elif hyp == "vertex mass":
        free = s.problem.free_mask(len(s.model.vertex_mass))
        masses = masses_text(s, (1 + theta) * s.model.vertex_mass, free)
        what = f"other vertex masses: {masses}"
    else:
        what = describe(fitted, hyp, theta)
    ks = [f.k for f in fitted]
    where = ", ".join(f"{k} -> {k + 1}" for k in ks)
    return (f"the port's steps are clothsim's steps with {what} (replayed at "
            f"{s.settings or 'the scene settings'}, from the port's x_k and v_k: "
            f"{max(d[k] for k in ks):.1e} m off the port's answer, against "
            f"{max(f.error for f in fitted):.1e} m for the scene's model; step"
            f"{'s' if len(ks) > 1 else ''} {where})")
