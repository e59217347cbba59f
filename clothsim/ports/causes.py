"""Why a port's step differs: the model under which the port's answer *is* the step.

A port that solves another problem than the scene's still solves *a* problem: its answer
x_{k+1} makes the gradient of that problem's g vanish. ∇g at a fixed x is linear in the
external force, a stiffness scale, a rest-length scale, the pin stiffness and 1/h²
(:mod:`clothsim.ports.hypotheses`), so each hypothesis is a small least-squares problem
on the port's own steps. :func:`infer_cause` fits them on the first failing steps jointly
(then on the first alone) and keeps the simplest that explains every fitted step:

- **minimizes**: the port's relative gradient under the fitted model is within the
  optimality tolerance of ``check`` (a converged port of another model);
- **reproduces**: it is lowered to at most :data:`GAIN` of the scene's, and clothsim's own
  step with the fitted model and the check's solver settings lands within the tolerance of
  the port's answer, or within :data:`REPLAY` of the distance clothsim's step of the
  scene's model has (a port that stops where clothsim stops, for another model).

Global fits first (one parameter: stiffness, rest lengths, 1/h², pins; two: stiffness and
rest lengths; three: the force per vertex or per unit mass), then per spring family, then
a force scaled per vertex on a minority of the vertices. When none explains the steps,
the verdict says so (with the closest fit, as a measurement) and names no cause.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from .hypotheses import (
    StepData,
    applicable,
    approach,
    columns,
    fit,
    fit_vertex_force,
    relative,
    replay,
)

log = logging.getLogger(__name__)

__all__ = ["Cause", "StepData", "closest", "infer_cause", "name_cause"]

#: A fitted model must lower the port's relative gradient to this share of the scene's ...
GAIN = 0.25
#: ... and clothsim's step with it must land this much nearer the port's answer than
#: clothsim's step of the scene's model (or within the tolerance).
REPLAY = 0.01
#: ... or the port's answer must be this much nearer the fitted model's minimizer than its
#: start was (and no nearer the scene's minimizer than its start).
APPROACH = 0.5
#: Failing steps fitted jointly (later ones are tested with the fitted parameters).
JOINT = 3
#: Steps replayed to test the fitted model on later steps (a long run stays quick).
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

    def explains(self, step: StepData, replays: bool = True) -> bool:
        """True when the fitted parameters also explain ``step`` (another failing step).

        Parameters
        ----------
        step : StepData
        replays : bool, default True
            Allow replaying clothsim's step (else only "minimizes" can explain it).

        Returns
        -------
        bool
            Records the step's gradient and evidence in :attr:`gradients`, :attr:`evidence`.
        """
        return _explains(step, self.hypothesis, self.parameters, self.gradients,
                         self.evidence, replays)


def _explains(step, hyp, theta, gradients, evidence, replays=True) -> bool:
    """The criteria of the module docstring; records the step's gradient and evidence."""
    r = relative(step, columns(step, hyp), theta)
    gradients[step.k] = r
    if r <= step.optimality:
        evidence[step.k] = ("minimizes", r)
        return True
    if not replays or r > GAIN * relative(step, [], ()):
        return False
    d = replay(step, hyp, theta)
    if d <= max(step.tolerance, REPLAY * step.error):
        evidence[step.k] = ("reproduces", d)
        return True
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
            if all(_explains(s, hyp, theta, gradients, evidence) for s in fitted):
                return Cause(_text(fitted, hyp, theta, gradients, evidence), hyp, theta,
                             gradients, evidence)
    return _vertex_force_cause(steps[0])


def _candidates(fitted) -> list:
    """(hypothesis, θ, worst relative gradient), fewest parameters first, then best fit."""
    out = []
    for hyp in applicable(fitted):
        theta = fit(fitted, hyp)
        if theta is not None:
            worst = max(relative(s, columns(s, hyp), theta) for s in fitted)
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
    c = fit_vertex_force(step)
    changed = np.flatnonzero(np.abs(c) > 1e-3)
    if not 0 < len(changed) <= 0.5 * len(c):
        return None
    gradients, evidence = {}, {}
    if not _explains(step, "vertex force", c, gradients, evidence):
        return None
    scale = 1 + c[changed]
    what = ("no external force" if np.allclose(scale, 0, atol=1e-2)
            else f"the external force × {_span(scale)}")
    text = (f"{_head(evidence)} {what} on {len(changed)} of {len(c)} vertices "
            f"({_listing(changed)}), the scene's force on the others"
            f"{_evidence([step], gradients, evidence)}")
    return Cause(text, "vertex force", c, gradients, evidence)


def _text(steps, hyp, theta, gradients, evidence) -> str:
    return (f"{_head(evidence)} {describe(steps, hyp, theta)}"
            f"{_evidence(steps, gradients, evidence)}")


def _weakest(evidence) -> str:
    kinds = {how for how, _ in evidence.values()}
    return next(how for how in ("approaches", "reproduces", "minimizes") if how in kinds)


def _head(evidence) -> str:
    return {"minimizes": "the port's steps minimize g with",
            "reproduces": "the port's steps are clothsim's steps with",
            "approaches": "the port's steps head for the minimizer of g with"}[
        _weakest(evidence)]


def _evidence(steps, gradients, evidence) -> str:
    ks = [s.k for s in steps]
    before = min(relative(s, [], ()) for s in steps)
    where = (f"step {ks[0]} -> {ks[0] + 1}" if len(ks) == 1 else
             "steps " + ", ".join(f"{k} -> {k + 1}" for k in ks) + " fitted jointly")
    text = (f": relative gradient at most {max(gradients[k] for k in ks):.1e} under that "
            f"model, at least {before:.1e} under the scene's ({where}")
    how = _weakest(evidence)
    worst = max(evidence[k][1] for k in ks if evidence[k][0] == how)
    if how == "reproduces":
        text += (f"; clothsim's step with that model is within {worst:.1e} m of the port's "
                 f"answer, with the scene's {max(s.error for s in steps):.1e} m")
    elif how == "approaches":
        text += (f"; the port's answer covers at least {1 - worst:.0%} of the way from the "
                 f"step's start to that model's minimizer and no nearer the scene's: it "
                 f"stops short, but more iterations would not make it clothsim's")
    return text + ")"


def _span(values) -> str:
    lo, hi = float(np.min(values)), float(np.max(values))
    return f"{lo:.3g}" if np.isclose(lo, hi, rtol=1e-3) else f"{lo:.3g} to {hi:.3g}"


def _listing(items, limit=6) -> str:
    items = [str(int(i)) for i in items]
    return ", ".join(items[:limit]) + (f", … {len(items)} in all" if len(items) > limit else "")


def _vector(v) -> str:
    """(+0.1, -9.8, 0): three digits; a component below 1e-6 of the largest is fit noise."""
    big = max(float(np.abs(v).max()), 1e-300)
    return "(" + ", ".join("0" if abs(c) < 1e-6 * big else f"{c:+.3g}" for c in v) + ")"


def _force_text(steps, hyp, theta) -> str:
    s = steps[0]
    f = np.zeros_like(s.x_port) if s.problem.f_ext is None else s.problem.f_ext
    m = s.model.vertex_mass
    if hyp == "force per vertex":
        scene = f[0] if np.allclose(f, f[0]) else None
        new = (scene if scene is not None else 0.0) + theta
        unit = "N per vertex"
    else:
        with np.errstate(divide="ignore", invalid="ignore"):
            g = f / m[:, None]
        scene = g[0] if np.all(m > 0) and np.allclose(g, g[0]) else None
        new = (scene if scene is not None else 0.0) + theta
        unit = "m/s² per unit mass"
    if scene is None:
        return f"an added external force {_vector(theta)} {unit} on top of the scene's"
    if not np.any(scene):
        return f"an external force {_vector(new)} {unit} the scene does not have"
    return f"the external force {_vector(new)} {unit} instead of {_vector(scene)}"


def _scale_text(what: str, value: float, none: str, springs: str, hint: str = "") -> str:
    if abs(value) < 5e-3:
        return f"{none} ({what} × {abs(value):.3f}, {springs}{hint})"
    if abs(value) < 0.05 and none.endswith("no force"):
        return (f"{none.replace('no force', 'almost no force')} ({what} × {value:.3f}, "
                f"{springs}{hint})")
    if what == "stiffness" and abs(value - 2) < 5e-3:
        return f"springs twice as stiff ({what} × {value:.2f}, {springs})"
    return f"{what} × {value:.3f} ({springs})"


def describe(steps, hyp, theta) -> str:
    """The fitted model in words.

    Parameters
    ----------
    steps : list of StepData
        The fitted steps (the first supplies the scene's force, pins and h).
    hyp : str
    theta : ndarray

    Returns
    -------
    str
        E.g. "rest lengths × 0.900 (all springs)".
    """
    one = float(1 + theta[0])
    s = steps[0]
    if hyp == "stiffness":
        what = _scale_text("stiffness", one, "springs that exert no force", "all springs",
                           "; e.g. a local step that does not normalize d to the rest length")
    elif hyp == "rest lengths":
        what = _scale_text("rest lengths", one, "zero-length springs", "all springs")
    elif hyp == "stiffness and rest lengths":
        what = (f"stiffness × {one:.3f} and rest lengths × {(1 + theta[1]) / one:.3f} "
                f"(all springs)")
    elif hyp.startswith("family "):
        family = hyp.split()[1]
        what = _scale_text("stiffness", one, "springs that exert no force",
                           f"the {family} springs only")
    elif hyp == "pins":
        w = s.problem.anchor_stiffness
        w = f"{float(w[0]):.3g} N/m" if np.allclose(w, w[0]) else "the scene's stiffness"
        what = ("pins that exert no force (the penalty pins missing: stiffness × 0.000)"
                if abs(one) < 5e-3 else f"penalty pins × {one:.3g} (the scene's are {w})")
    elif hyp == "inertia":
        h = s.problem.h
        what = (f"the inertia term M (x − y) / h² × {one:.3f} (as if h were "
                f"{h / np.sqrt(one):.4g} s there, not {h:.4g} s)" if one > 0 else
                f"the inertia term M (x − y) / h² × {one:.3f}")
    else:
        what = _force_text(steps, hyp, theta)
    return what


#: The verdicts a fitted model may replace: a port that solves another problem gets them.
FITTED = ("not converged", "not a minimizer", "model differs")


def name_cause(checks: dict, steps: list[StepData], others=()) -> Cause | None:
    """Fit a cause to the failing steps and write it into their verdicts.

    The steps the fitted model explains become ``model differs`` with the cause as their
    note (their vertex stays the one of largest error). When no model fits, the first
    step's note says so if its verdict is ``not a minimizer`` or ``model differs``;
    unconverged verdicts keep their explanation.

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
    cause = infer_cause(steps)
    if cause is None:
        if steps and checks[steps[0].k].status in ("not a minimizer", "model differs"):
            near = closest(steps[0])
            checks[steps[0].k].note += ("; no single model parameter explains the port's "
                                        "answer (fitted: external force, stiffness, rest "
                                        "lengths, pins, 1/h², per spring family"
                                        + (f"; {near}" if near else "") + ")")
        return None
    first = steps[0].k
    fitted = list(cause.gradients)
    replays = MAX_REPLAYS
    for s in sorted(steps + list(others), key=lambda s: s.k):
        if s.k in fitted or cause.explains(s, replays > 0):
            replays -= s.k in cause.evidence and s.k not in fitted
            check = checks[s.k]
            check.status = "model differs"
            check.note = (cause.text if s.k == first else
                          f"the model fitted at step {first} -> {first + 1} explains it "
                          f"(relative gradient {cause.gradients[s.k]:.1e} under it)")
    return cause
