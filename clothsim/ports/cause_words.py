"""The words of :mod:`clothsim.ports.causes`: a fitted model and its evidence, as a verdict says it.

:func:`describe` names the fitted model ("rest lengths × 0.900 (all springs)", "the
external force (0, +9.8, 0) N per vertex instead of (0, -9.8, 0)"); :func:`cause_text`
adds how it explains the port's steps (minimizes, reproduces, approaches) and the numbers.
"""

from __future__ import annotations

import numpy as np

from ..model import MASS_LUMPINGS, Model
from .hypotheses import relative


def cause_text(steps, hyp, theta, gradients, evidence) -> str:
    """The verdict's note: how the fitted model explains the steps, and the evidence.

    Parameters
    ----------
    steps : list of StepData
        The fitted steps.
    hyp : str
    theta : ndarray
    gradients : dict
        Step k → the port's relative gradient under the fitted model.
    evidence : dict
        Step k → (how, number), as :class:`clothsim.ports.causes.Cause` keeps it.

    Returns
    -------
    str
    """
    return (f"{head(evidence)} {describe(steps, hyp, theta)}"
            f"{evidence_text(steps, gradients, evidence)}")


def _weakest(evidence) -> str:
    kinds = {how for how, _ in evidence.values()}
    return next(how for how in ("approaches", "reproduces", "minimizes") if how in kinds)


def head(evidence) -> str:
    """The note's opening for the weakest kind of evidence.

    Parameters
    ----------
    evidence : dict
        Step k → (how, number).

    Returns
    -------
    str
        "the port's steps minimize g with", "… are clothsim's steps with" or "… head for
        the minimizer of g with".
    """
    return {"minimizes": "the port's steps minimize g with",
            "reproduces": "the port's steps are clothsim's steps with",
            "approaches": "the port's steps head for the minimizer of g with"}[
        _weakest(evidence)]


def evidence_text(steps, gradients, evidence) -> str:
    """The numbers behind a cause.

    Parameters
    ----------
    steps : list of StepData
    gradients, evidence : dict
        As :func:`cause_text` takes them.

    Returns
    -------
    str
        ": relative gradient at most … under that model, at least … under the scene's
        (steps …; …)".
    """
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


def span(values) -> str:
    """"0.5" or "0.5 to 0.7": the range of fitted values.

    Parameters
    ----------
    values : array_like

    Returns
    -------
    str
    """
    lo, hi = float(np.min(values)), float(np.max(values))
    return f"{lo:.3g}" if np.isclose(lo, hi, rtol=1e-3) else f"{lo:.3g} to {hi:.3g}"


def listing(items, limit=6) -> str:
    """"1, 2, 3" or "1, 2, …, 7, … 40 in all": the first vertices of a set.

    Parameters
    ----------
    items : iterable of int
    limit : int, default 6

    Returns
    -------
    str
    """
    items = [str(int(i)) for i in items]
    return ", ".join(items[:limit]) + (f", … {len(items)} in all" if len(items) > limit else "")


def _vector(v, digits: int = 3, scale: float = 0.0) -> str:
    """(+0.1, -9.8, 0): three digits; a component below 1e-6 of the largest (of ``v``, or
    ``scale`` when larger) is fit noise."""
    big = max(float(np.abs(v).max()), scale, 1e-300)
    return "(" + ", ".join("0" if abs(c) < 1e-6 * big else f"{c:+.{digits}g}" for c in v) + ")"


def _vectors(a, b) -> tuple[str, str]:
    """Two vectors with the fewest digits (at least 3) that tell them apart: a port's
    gravity of 9.8 beside the scene's 9.81 is not printed as the same (-9.8) twice; each
    component below 1e-6 of the larger vector is 0 (a still cloth fits a force of 1e-15 N,
    which is none)."""
    scale = max(float(np.abs(a).max()), float(np.abs(b).max()))
    for digits in range(3, 10):
        ta, tb = _vector(a, digits, scale), _vector(b, digits, scale)
        if ta != tb:
            break
    return ta, tb


def _force_text(steps, hyp, theta) -> str:
    """The fitted force (θ replaces the scene's) beside the scene's, in the same form."""
    text = _force_words(steps, hyp, theta)
    g = steps[0].gravity
    if hyp == "force per unit mass" and g is not None and np.any(g) and \
            np.linalg.norm(np.asarray(theta) - g) <= 1e-3 * np.linalg.norm(g):
        text += " (gravity alone: the scene's other external forces, e.g. a wind, left out)"
    return text


def _force_words(steps, hyp, theta) -> str:
    s = steps[0]
    f = np.zeros_like(s.x_port) if s.problem.f_ext is None else s.problem.f_ext
    m = s.model.vertex_mass
    unit = "N per vertex" if hyp == "force per vertex" else "m/s² × m on each vertex"
    if not np.any(f):
        return f"an external force {_vector(theta)} {unit} the scene does not have"
    if np.allclose(f, f[0]) and hyp != "force per vertex" and np.all(m > 0) \
            and np.allclose(m, m[0]):   # per unit mass beside the scene's, in m/s² too
        port, scene = _vectors(theta, f[0] / m[0])
        return f"the external force {port} {unit} instead of {scene} m/s² × m"
    if np.allclose(f, f[0]):
        port, scene = _vectors(theta, f[0])
        text = f"the external force {port} {unit} instead of {scene} N per vertex"
        if hyp == "force per vertex" and np.all(m > 0) and np.allclose(m, m[0]) \
                and not np.isclose(m[0], 1.0):   # equal masses: m·g fits as well; say g
            port, scene = _vectors(np.asarray(theta) / m[0], f[0] / m[0])
            text += (f" (the vertices' masses are equal, {m[0]:.3g} kg: the acceleration "
                     f"{port} m/s² instead of {scene} m/s²)")
        return text
    with np.errstate(divide="ignore", invalid="ignore"):
        g = f / m[:, None]
    if np.all(m > 0) and np.allclose(g, g[0]):
        port, scene = _vectors(theta, g[0])
        return f"the external force {port} {unit} instead of {scene} m/s² × m"
    return f"the external force {_vector(theta)} {unit} instead of the scene's"


#: A fitted pin stiffness below this share of the scene's is no pin (a 1e10 N/m pin fitted
#: to a port without pins leaves 1e-16 of it; a port's 1e7 N/m pin is 1e-3).
PINS_OFF = 1e-8
#: What a negative rest-length scale means in the code.
NEGATIVE = ("; a negative rest length: the springs' d term enters the right-hand side "
            "with the wrong sign")


def _scale_text(what: str, value: float, none: str, springs: str, hint: str = "") -> str:
    if abs(value) < 5e-3:
        return f"{none} ({what} × {abs(value):.3f}, {springs}{hint})"
    if abs(value) < 0.05 and none.endswith("no force"):
        return (f"{none.replace('no force', 'almost no force')} ({what} × {value:.3f}, "
                f"{springs}{hint})")
    if what == "stiffness" and abs(value - 2) < 5e-3:
        return f"springs twice as stiff ({what} × {value:.2f}, {springs})"
    return f"{what} × {value:.3f} ({springs})"


def _mass_scale(s, one: float) -> str:
    """All stiffnesses × c make the same steps as all masses × 1 / c when the external
    force is m·g (divide g's gradient by c): the two cannot be told apart, so both are said."""
    if one < 5e-3 or abs(one - 1) < 5e-3:
        return ""
    m = s.model.vertex_mass
    f = np.zeros_like(s.x_port) if s.problem.f_ext is None else s.problem.f_ext
    with np.errstate(divide="ignore", invalid="ignore"):
        g = f / m[:, None]
    if not (np.all(m > 0) and np.allclose(g, g[0])):
        return ""
    return (f", or, the same steps, every vertex mass × {1 / one:.3f} (the external force "
            f"m·g scaled with it)")


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
        what += _mass_scale(s, one)
    elif hyp == "rest lengths":
        what = _scale_text("rest lengths", one, "zero-length springs", "all springs")
        what = what[:-1] + NEGATIVE + ")" if one < 0 else what
    elif hyp == "stiffness and rest lengths":
        rest = float((1 + theta[1]) / one)
        what = (f"zero-length springs of stiffness × {one:.3f} (rest lengths × "
                f"{abs(rest):.3f}, all springs; e.g. a local step d = r (x_a − x_b), not "
                f"normalized)" if abs(rest) < 5e-3 else
                f"stiffness × {one:.3f} and rest lengths × {rest:.3f} (all springs"
                f"{NEGATIVE if rest < 0 else ''})")
    elif hyp.startswith("family "):
        family = hyp.split()[1]
        what = _scale_text("stiffness", one, "springs that exert no force",
                           f"the {family} springs only")
    elif hyp == "gravity":
        port, scene = _vectors(np.asarray(s.gravity) + theta, s.gravity)
        what = (f"gravity {port} m/s² instead of {scene} m/s² (the scene's other external "
                f"forces kept)")
    elif hyp.startswith("rest lengths "):
        what = _scale_text("rest lengths", one, "zero-length springs",
                           f"the {hyp.split()[-1]} springs only")
    elif hyp == "pins":
        w = s.problem.anchor_stiffness
        same = bool(np.allclose(w, w[0]))
        if one < PINS_OFF:
            what = "pins that exert no force (the penalty pins missing)"
        elif same:
            what = (f"penalty pins of {one * float(w[0]):.3g} N/m instead of "
                    f"{float(w[0]):.3g} N/m")
        else:
            what = f"penalty pins × {one:.3g} (the scene's stiffnesses)"
    elif hyp == "inertia":
        h = s.problem.h
        what = (f"the inertia term M (x − y) / h² × {one:.3f} (as if h were "
                f"{h / np.sqrt(one):.4g} s there, not {h:.4g} s)" if one > 0 else
                f"the inertia term M (x − y) / h² × {one:.3f}")
    else:
        what = _force_text(steps, hyp, theta)
    return what


def lumpings(model) -> list:
    """Each mass lumping's vertex masses for a total of 1 kg on the model's mesh.

    Parameters
    ----------
    model : Model

    Returns
    -------
    list of (str, ndarray)
        (lumping, masses [kg], shape (n,)); a lumping the mesh cannot take is left out.
    """
    out = []
    for lumping in MASS_LUMPINGS:
        try:
            out.append((lumping, Model.build(model.mesh, model.springs, total_mass=1.0,
                                             mass_lumping=lumping).vertex_mass))
        except ValueError:
            continue
    return out


def masses_text(step, fitted: np.ndarray, free: np.ndarray) -> str:
    """The fitted masses in words: a mass lumping's when they are spread as it spreads
    them (on the free vertices, the only ones the step shows), else their range.

    Parameters
    ----------
    step : StepData
    fitted : ndarray, shape (n,)
        The port's vertex masses [kg].
    free : ndarray, shape (n,), bool
        The vertices the step shows (free, of positive mass).

    Returns
    -------
    str
    """
    m = step.model.vertex_mass
    for lumping, unit in lumpings(step.model):
        u = unit[free]
        total = float(fitted[free] @ u / (u @ u))     # the port's total mass, least squares
        lumped = total * unit
        if np.allclose(fitted[free], lumped[free], rtol=1e-3, atol=0) and \
                not np.allclose(m[free], lumped[free], rtol=1e-3, atol=0):
            return (f"those of mass_lumping = \"{lumping}\" ({total:.4g} kg in all), not the "
                    f"scene's masses ({m.sum():.4g} kg in all; clothsim diff-model compares them)")
    changed = free & (np.abs(fitted - m) > 1e-3 * m)
    return (f"the scene's × {span(fitted[changed] / m[changed])} on {int(changed.sum())} of "
            f"{len(m)} vertices ({listing(np.flatnonzero(changed))})")
