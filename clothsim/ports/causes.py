"""Why a port's step differs: the model under which the port's answer *is* the step.

A port that solves another problem than the scene's still solves *a* problem: its answer
x_{k+1} makes the gradient of that problem's g vanish. ∇g at a fixed x is linear in the
external force, a stiffness scale, a rest-length scale, the pin stiffness and 1/h²
(:mod:`clothsim.ports.hypotheses`), so each hypothesis is a small least-squares problem
on the port's own steps. :func:`infer_cause` fits them on the first failing steps jointly
(then on the first alone) and keeps the simplest that lowers the port's relative gradient
to at most :data:`GAIN` of the scene's on every fitted step, and explains it:

- **minimizes**: the port's relative gradient under the fitted model is within the
  optimality tolerance of ``check`` (a converged port of another model);
- **reproduces**: clothsim's own step with the fitted model (refined on the replays) and
  the check's solver settings lands within the tolerance of the port's answer, or within
  :data:`REPLAY` of the distance clothsim's step of the scene's model has (a port that
  stops where clothsim stops, for another model);
- **approaches**: the port's answer is at least half-way from the step's start to the
  fitted model's minimizer and no nearer the scene's (one-parameter models only).

``check`` fits only steps whose relative gradient under the scene's model is at least
:data:`clothsim.ports.judge.CONVERGING`: a port nearer optimal than that only stops short
(an extra force of a few centinewtons makes any such answer stationary), and keeps the
judge's explanation.

Global fits first (one parameter: stiffness, rest lengths, 1/h², pins; two: stiffness and
rest lengths; three: the force per vertex or per unit mass), then per spring family, then
a force scaled per vertex on a minority of the vertices, then the mass per vertex (another
mass lumping: the inertia and gravity's m g with it). When none explains the steps,
the verdict says so (with the closest fit, as a measurement) and names no cause.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from .cause_words import cause_text, describe, evidence_text, head, listing, masses_text, span
from .hypotheses import (
    StepData,
    applicable,
    columns,
    fit,
    fit_vertex_scale,
    relative,
)
from .replayed import replay_cause, topology_replayed
from .replays import approach, refine, replay

log = logging.getLogger(__name__)

__all__ = ["Cause", "StepData", "closest", "infer_cause", "name_cause"]

#: A fitted model must lower the port's relative gradient to this share of the scene's ...
GAIN = 0.25
#: ... and to this share for a step the judge found on its way to clothsim's minimizer:
#: stopping short towards the start looks like more inertia to first order (a float32
#: solver 2e-5 m short: × 0.18; the coursework faults: below 1e-7).
STRONG = 1e-3
#: ... and clothsim's step with it must land this much nearer the port's answer than
#: clothsim's step of the scene's model (or within the tolerance).
REPLAY = 0.01
#: ... or the port's answer must be this much nearer the fitted model's minimizer than its
#: start was (and no nearer the scene's minimizer than its start).
APPROACH = 0.5
#: Gauss–Newton iterations that refine θ on replayed steps.
REFINE = 4
#: Failing steps fitted jointly (later ones are tested with the fitted parameters).
JOINT = 3
#: Later steps tested for "head for" (two Newton solves each: a long run stays quick).
MAX_REPLAYS = 8


@dataclass
class Cause:
    """A fitted model under which the port's steps are clothsim's.

    Attributes
    ----------
    text : str
        E.g. "the port's steps minimize g with rest lengths × 0.900 (all springs): …".
    hypothesis : str
        A hypothesis of :func:`clothsim.ports.hypotheses.applicable` or ``"vertex force"``.
    parameters : ndarray
        The fitted θ (θ = 0 is the scene's model).
    gradients : dict
        Step k → the port's relative gradient under the fitted model.
    evidence : dict
        Step k → (how, number): ("minimizes", relative gradient), ("reproduces", distance
        of clothsim's step with the fitted model from the port's answer [m]) or
        ("approaches", the :func:`~clothsim.ports.hypotheses.approach` ratio).
    """

    text: str
    hypothesis: str
    parameters: np.ndarray
    gradients: dict
    evidence: dict = field(default_factory=dict)

    @property
    def converged(self) -> bool:
        """True when the port's answers minimize the fitted g."""
        return all(how == "minimizes" for how, _ in self.evidence.values())

    def explains(self, step: StepData, replays: list | None = None) -> bool:
        """True when the fitted parameters also explain ``step`` (another failing step).

        Parameters
        ----------
        step : StepData
        replays : list of one int, optional
            The "head for" tests still allowed (two Newton solves each), decremented by one
            that is run; default: unlimited.

        Returns
        -------
        bool
            Records the step's gradient and evidence in :attr:`gradients`, :attr:`evidence`.
        """
        return _explains(step, self.hypothesis, self.parameters, self.gradients,
                         self.evidence, replays)


def _explains(step, hyp, theta, gradients, evidence, replays=None, fitted=None) -> bool:
    """The criteria of the module docstring; records the step's gradient and evidence.

    ``theta`` is refined on replayed steps (:func:`_refine`); ``fitted``, the least-squares
    θ when it differs, is what the gradient and approach criteria judge."""
    if fitted is not None and not np.array_equal(fitted, theta):
        if _explains(step, hyp, theta, {}, evidence, replays) and \
                evidence[step.k][0] != "approaches":
            gradients[step.k] = relative(step, columns(step, hyp), theta, hyp)
            return True
        theta = fitted
    r = relative(step, columns(step, hyp), theta, hyp)
    gradients[step.k] = r
    if r > (STRONG if step.approaching else GAIN) * relative(step, [], ()):
        return False                        # a cause must explain most of the gradient
    if _minimizes(step, r):
        evidence[step.k] = ("minimizes", r)
        return True
    d = replay(step, hyp, theta)   # one step's solve, as the check itself takes
    if d <= max(step.tolerance, REPLAY * step.error):
        evidence[step.k] = ("reproduces", d)
        return True
    # heading for: only the one-parameter causes, on a budget of Newton solves
    if len(np.atleast_1d(theta)) != 1 or (replays is not None and replays[0] <= 0):
        return False
    if replays is not None:
        replays[0] -= 1
    mine, scene = approach(step, hyp, theta)
    log.debug("step %d, %s: approach ratio %.3g (scene's %.3g)", step.k, hyp, mine, scene)
    if mine <= APPROACH and scene >= 1:   # a port heading for the scene's minimizer is
        # unconverged, whatever else it is: judge keeps its explanation
        evidence[step.k] = ("approaches", mine)
        return True
    return False


def infer_cause(steps: list[StepData]) -> Cause | None:
    """The simplest fitted model that explains the port's first failing steps, or None.

    Parameters
    ----------
    steps : list of StepData
        The failing steps, in order; the first :data:`JOINT` are fitted jointly, then the
        first alone.

    Returns
    -------
    Cause or None
    """
    if not steps:
        return None
    for fitted in (steps[:JOINT], steps[:1]) if len(steps) > 1 else (steps,):
        for hyp, theta, _ in _candidates(fitted):
            gradients, evidence = {}, {}
            fitted_theta = theta
            if _replayable(fitted, hyp, theta) and _promising(fitted[0], hyp, theta):
                theta = refine(fitted[:1], hyp, theta, REFINE)
            if all(_explains(s, hyp, theta, gradients, evidence, fitted=fitted_theta)
                   for s in fitted):
                return Cause(cause_text(fitted, hyp, theta, gradients, evidence) +
                             _same_steps(fitted, hyp), hyp, theta, gradients, evidence)
    return _vertex_force_cause(steps[0]) or _vertex_mass_cause(steps[0])


def _same_steps(fitted, hyp) -> str:
    """Where the springs hardly act (a free fall), the inertia term × c and the external
    force × 1 / c make the same steps: the force, fitted too, is named beside the inertia
    when it explains the same steps (gravity × 2 was named 'as if h were 0.04714 s')."""
    if hyp != "inertia":
        return ""
    for other in ("force per unit mass", "force per vertex"):
        if other not in applicable(fitted):
            continue
        theta = fit(fitted, other)
        if theta is not None and all(_explains(s, other, theta, {}, {}) for s in fitted):
            return (f"; or, the same steps (the springs hardly act in them), "
                    f"{describe(fitted, other, theta)}")
    return ""


def _minimizes(step, r: float) -> bool:
    """A relative gradient ``r`` that counts as a minimizer of the fitted g: within the
    step's optimality, unless that criterion is :attr:`StepData.blind` (it would take
    clothsim's own stopped-short answer for a minimizer too, as a coarse printing's can): it
    then tells nothing, and the replays decide."""
    return r <= step.optimality and not step.blind


def _replayable(fitted, hyp, theta) -> bool:
    """True when the fit lowers every step's gradient enough, yet not to a minimizer."""
    r = [relative(s, columns(s, hyp), theta, hyp) for s in fitted]
    return (any(not _minimizes(s, ri) for ri, s in zip(r, fitted))
            and all(ri <= GAIN * relative(s, [], ()) for ri, s in zip(r, fitted)))


def _promising(step, hyp, theta) -> bool:
    """clothsim's step with the least-squares θ lands at most half as far from the port's
    answer as the scene's step: worth refining θ on replays."""
    return replay(step, hyp, theta) <= 0.5 * step.error


def _candidates(fitted) -> list:
    """(hypothesis, θ, worst relative gradient), fewest parameters first, then best fit."""
    out = []
    for hyp in applicable(fitted):
        theta = fit(fitted, hyp)
        if theta is not None:
            worst = max(relative(s, columns(s, hyp), theta, hyp) for s in fitted)
            out.append((hyp, theta, worst))
    return sorted(out, key=lambda c: (len(c[1]), c[2]))


def closest(step: StepData) -> str:
    """The hypothesis that lowers the port's relative gradient most on ``step``, in words.

    For the note of a step no hypothesis explains: a measurement, not a cause.

    Parameters
    ----------
    step : StepData

    Returns
    -------
    str
        "" when none lowers it to half.
    """
    found = sorted(_candidates([step]), key=lambda c: c[2])
    before = relative(step, [], ())
    if not found or found[0][2] >= 0.5 * before:
        return ""
    hyp, theta, r = found[0]
    return (f"the closest, {describe([step], hyp, theta)}, lowers the port's relative "
            f"gradient from {before:.1e} to {r:.1e} only")


def _vertex_force_cause(step: StepData) -> Cause | None:
    """A force missing (or scaled) on a minority of the vertices, fitted per vertex."""
    if step.problem.f_ext is None or not np.any(step.problem.f_ext):
        return None
    c = fit_vertex_scale(step, "vertex force")
    changed = np.flatnonzero(np.abs(c) > 1e-3)
    if not 0 < len(changed) <= 0.5 * len(c):
        return None
    gradients, evidence = {}, {}
    if not _explains(step, "vertex force", c, gradients, evidence):
        return None
    scale = 1 + c[changed]
    what = ("no external force" if np.allclose(scale, 0, atol=1e-2)
            else f"the external force × {span(scale)}")
    text = (f"{head(evidence)} {what} on {len(changed)} of {len(c)} vertices "
            f"({listing(changed)}), the scene's force on the others"
            f"{evidence_text([step], gradients, evidence)}")
    return Cause(text, "vertex force", c, gradients, evidence)


def _vertex_mass_cause(step: StepData) -> Cause | None:
    """Other vertex masses (in M and in gravity's m g), fitted per vertex; named as the
    other mass lumping when the fitted masses are spread as it spreads them."""
    m = step.model.vertex_mass
    if not np.any(m > 0):
        return None
    c = fit_vertex_scale(step, "vertex mass")
    free = step.problem.free_mask(len(m)) & (m > 0)
    if not np.any(np.abs(c[free]) > 1e-3):
        return None
    gradients, evidence = {}, {}
    if not _explains(step, "vertex mass", c, gradients, evidence):
        return None
    fitted = (1 + c) * m
    text = (f"{head(evidence)} other vertex masses: {masses_text(step, fitted, free)}"
            f"{evidence_text([step], gradients, evidence)}")
    return Cause(text, "vertex mass", c, gradients, evidence)


#: The verdicts a fitted model may replace: a port that solves another problem gets them.
FITTED = ("not converged", "not a minimizer", "model differs")


def name_cause(checks: dict, steps: list[StepData], others=()) -> Cause | None:
    """Fit a cause to the failing steps and write it into their verdicts.

    The steps the fitted model explains become ``model differs`` with the cause as their
    note (their vertex stays the one of largest error). When no model fits, the first
    step's note says so if its verdict is ``not a minimizer`` or ``model differs``;
    unconverged verdicts keep their explanation. In a scene of a fixed iteration count
    (:attr:`StepData.settings`), a first failing step the gradient fits cannot take (start-
    dependent) or do not explain is explained by replays (:mod:`clothsim.ports.replayed`).

    Parameters
    ----------
    checks : dict
        Step k → its :class:`~clothsim.ports.verdicts.StepCheck` (changed in place).
    steps : list of StepData
        The failing steps with a verdict of :data:`FITTED` and no settings found.
    others : sequence of StepData
        Further failing steps (start-dependent without settings found): not fitted, but
        given the cause when the fitted model explains them too.

    Returns
    -------
    Cause or None
    """
    every = sorted(list(steps) + list(others), key=lambda s: s.k)
    cause = infer_cause(steps) if steps and steps[0] is every[0] else None
    weak = cause is None or any(how == "approaches" for how, _ in cause.evidence.values())
    if weak and every and every[0].settings and _replayed(checks, every):
        return None                 # a fixed-iteration port: its replays name the cause
    if cause is None and steps and steps[0] is not every[0]:
        cause = infer_cause(steps)
    if cause is None and steps and (found := topology_replayed(steps)) is not None:
        for k, d in found[1].items():   # springs missing or doubled: no parameter
            checks[k].status = "model differs"
            checks[k].note = found[0] if k == min(found[1]) else (
                f"the topology fitted at step {min(found[1])} -> {min(found[1]) + 1} "
                f"explains it (its replay is {d:.1e} m off the port's answer)")
        return None
    if cause is None:
        if steps and checks[steps[0].k].status in ("not a minimizer", "model differs"):
            near = closest(steps[0])
            checks[steps[0].k].note += ("; no single model parameter explains the port's "
                                        "answer (fitted: external force, stiffness, rest "
                                        "lengths, pins, 1/h², per spring family, per vertex"
                                        + (f"; {near}" if near else "") + ")")
        return None
    first = steps[0].k
    fitted = list(cause.gradients)
    replays = [MAX_REPLAYS]
    for s in sorted(steps + list(others), key=lambda s: s.k):
        if s.k in fitted or cause.explains(s, replays):
            check = checks[s.k]
            check.status = "model differs"
            check.note = (cause.text if s.k == first else
                          f"the model fitted at step {first} -> {first + 1} explains it "
                          f"(relative gradient {cause.gradients[s.k]:.1e} under it)")
    return cause


def _replayed(checks: dict, steps: list[StepData]) -> bool:
    """A fixed-iteration port: the cause whose replays reproduce its steps
    (:mod:`clothsim.ports.replayed`), written into the steps it explains, or the note
    that no single hypothesis does; True when a cause was named."""
    found = replay_cause(steps)
    if found is None:
        checks[steps[0].k].note += (
            "; no single model change reproduces the port's answer when clothsim's iteration "
            f"is replayed at {steps[0].settings} (tried: the external force, stiffness, rest "
            "lengths, pins, h, per spring family, mass lumping)")
        return False
    text, distances = found
    k0 = min(distances)
    for k, d in distances.items():
        checks[k].status = "model differs"
        checks[k].note = (text if k == k0 else f"the model fitted at step {k0} -> {k0 + 1} "
                          f"explains it (its replay is {d:.1e} m off the port's answer)")
    return True
