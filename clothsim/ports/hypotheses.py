"""The hypotheses of :mod:`clothsim.ports.causes`: ∇g as a linear function of a model change.

At the port's answer x (fixed), the gradient of a step's objective g (Liu et al. 2013, Eq. 4)

    ∇g(x) = M (x − y) + h² [ Σ_i A_i k_i (p_i − r_i p_i / |p_i|) + Σ_j w_j (x_j − q_j) − f ]

is linear in each model parameter: the external force f, a stiffness scale s (k → s k), a
rest-length scale ρ (the r_i term × ρ), a pin-stiffness scale ω (w → ω w) and a scale μ of
the inertia term (M/h² → μ M/h²). A hypothesis is a set of such parameters θ, θ = 0 the
scene's model; R(θ) = R₀ + Σ θ_j ∂R/∂θ_j is ∇g of the changed model, and :func:`fit` is the
least-squares θ over one or several steps. The changed model itself, and clothsim's step
with it, are in :mod:`clothsim.ports.replays`.

The hypotheses (:func:`applicable`): ``stiffness``, ``rest lengths``, ``inertia``, ``pins``
(one parameter each), ``force per vertex``, ``force per unit mass`` (three),
``stiffness and rest lengths`` (two), ``gravity`` (three: a change of the scene's gravity,
its other external forces kept; only beside such forces), ``family F`` (the stiffness of one
spring family),
``rest lengths F`` (the rest lengths of one family),
and the per-vertex scales fitted one vertex at a time by :func:`fit_vertex_scale`:
``vertex force`` (a scale of the force per vertex) and ``vertex mass`` (a scale of the
mass per vertex, in the inertia term and in the force, which gravity makes m g: another
mass lumping). The two force hypotheses replace the scene's force
(:data:`REPLACING`): their θ is the new force per vertex [N], or per unit mass [m/s²].
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..springs import FAMILIES


@dataclass
class StepData:
    """One failing step, as ``check`` judged it.

    Attributes
    ----------
    k : int
        The step k → k + 1.
    model : Model
        The step's model (damping folded in).
    problem : StepProblem
    x_port : ndarray, shape (n, 3)
        The port's x_{k+1} [m].
    gradient0 : float
        ‖∇g(x₀)‖ of the scene's g at the step's initial guess [N·s²].
    optimality : float
        Relative gradient counted as a minimizer.
    gradient_clothsim : float
        Relative gradient of clothsim's answer for the scene's g.
    error : float
        max |x_clothsim − x_port| over the vertices [m].
    tolerance : float
        The step's per-vertex tolerance [m].
    solve : callable, optional
        ``solve(model, problem) -> x``: clothsim's step with the check's solver settings,
        for :func:`clothsim.ports.replays.replay`.
    approaching : bool
        The judge found the port's answer on its way to clothsim's minimizer ("not
        converged"): a cause must then explain nearly all of its gradient.
    settings : str
        The scene's fixed iteration count and start in words ("10 local/global iterations
        from y"), or "" when its steps converge: only then are hypotheses tested by replay
        alone (:mod:`clothsim.ports.replayed`).
    gravity : ndarray, shape (3,), optional
        The scene's gravity [m/s²], when it has one: with other external forces beside it
        (wind), the ``gravity`` hypothesis changes it alone.
    derived : bool
        The port wrote no velocities: v_k = (x_k − x_{k−1}) / h, so another h leaves the
        inertial target y = 2 x_k − x_{k−1} where it is.
    blind : bool
        The optimality (raised to the printing's rounding of ∇g) takes clothsim's own
        answer for a minimizer although the stated criterion does not (a fixed iteration
        count stopped short): no answer is then said to minimize a fitted g.
    effects : tuple
        The scene's effects (an impulse's disk is fitted by
        :mod:`clothsim.ports.impulse_fit`).
    time : float
        The time at the step's start [s].
    """

    k: int
    model: object
    problem: object
    x_port: np.ndarray
    gradient0: float
    optimality: float
    gradient_clothsim: float
    error: float = float("inf")
    tolerance: float = 0.0
    solve: object = None
    approaching: bool = False
    settings: str = ""
    cache: dict = dataclasses.field(default_factory=dict, repr=False)
    gravity: object = None
    derived: bool = False
    blind: bool = False
    effects: tuple = ()
    time: float = 0.0



def _scatter(model, per_spring: np.ndarray) -> np.ndarray:
    """Σ_i A_i ⊗ v_i: +v_i at a_i, −v_i at b_i, shape (n, 3)."""
    a, b = model.springs.spring_vertices.T
    out = np.zeros((model.vertex_count, 3))
    np.add.at(out, a, per_spring)
    np.add.at(out, b, -per_spring)
    return out


def terms(step: StepData, mask=None) -> dict:
    """The parts of ∇g at the port's answer.

    Parameters
    ----------
    step : StepData
    mask : ndarray, shape (s,), bool, optional
        Only these springs (the others' stiffness counts as 0).

    Returns
    -------
    dict
        ``inertia`` M (x − y), ``kp`` Σ A_i k_i p_i, ``kr`` −Σ A_i k_i r_i p_i / |p_i|,
        ``pins`` Σ w_j (x_j − q_j), ``force`` f, each (n, 3); ``mass`` m, shape (n,).
    """
    model, p, x = step.model, step.problem, step.x_port
    a, b = model.springs.spring_vertices.T
    k, r = model.springs.spring_stiffness, model.springs.spring_rest_length
    if mask is not None:
        k = np.where(mask, k, 0.0)
    vec = x[a] - x[b]
    length = np.linalg.norm(vec, axis=1)
    unit = vec / np.where(length > 0, length, 1.0)[:, None]
    pins = np.zeros_like(x)
    p.anchors.add_gradient(pins, x)
    f = np.zeros_like(x) if p.f_ext is None else p.f_ext
    return {"inertia": step.model.vertex_mass[:, None] * (x - p.y),
            "kp": _scatter(model, k[:, None] * vec),
            "kr": _scatter(model, -(k * r)[:, None] * unit),
            "pins": pins, "force": f, "mass": model.vertex_mass}


#: Hypotheses that replace the scene's external force (their θ is the new force).
REPLACING = ("force per vertex", "force per unit mass")
#: Hypotheses whose θ is added to the scene's force (θ: the change of gravity [m/s²]); like
#: :data:`REPLACING`, θ is no scale.
ADDING = ("gravity",)


def residual(step: StepData, hypothesis: str | None = None) -> np.ndarray:
    """∇g of the scene's model at the port's answer (without its force for a hypothesis
    of :data:`REPLACING`).

    Parameters
    ----------
    step : StepData
    hypothesis : str, optional

    Returns
    -------
    ndarray, shape (n, 3)
        ∇g(x_port) [N·s²], rows of exact pins included (:func:`free_rows` leaves them out).
    """
    t = terms(step)
    h2 = step.problem.h ** 2
    force = 0.0 if hypothesis in REPLACING else t["force"]
    return t["inertia"] + h2 * (t["kp"] + t["kr"] + t["pins"] - force)


def columns(step: StepData, hypothesis: str) -> list[np.ndarray]:
    """∂R/∂θ_j for each parameter θ_j of ``hypothesis`` (θ = 0 is the scene's model).

    Parameters
    ----------
    step : StepData
    hypothesis : str
        A name of :func:`applicable`, ``"vertex force"`` or ``"vertex mass"``.

    Returns
    -------
    list of ndarray, each shape (n, 3)
        One per parameter (``vertex force``, ``vertex mass``: one, scaled per vertex by θ_v).
    """
    h2 = step.problem.h ** 2
    if hypothesis.startswith(("family ", "rest lengths ")):
        family = FAMILIES.index(hypothesis.split()[-1])
        mask = step.model.springs.spring_family == family
        t = terms(step, mask)
        return [h2 * (t["kr"] if hypothesis.startswith("rest") else t["kp"] + t["kr"])]
    t = terms(step)
    n = len(step.x_port)
    if hypothesis == "stiffness":
        return [h2 * (t["kp"] + t["kr"])]
    if hypothesis == "rest lengths":
        return [h2 * t["kr"]]
    if hypothesis == "stiffness and rest lengths":
        return [h2 * t["kp"], h2 * t["kr"]]
    if hypothesis == "pins":
        return [h2 * t["pins"]]
    if hypothesis == "inertia":
        return [t["inertia"]]
    if hypothesis in REPLACING + ADDING:
        weight = np.ones(n) if hypothesis == "force per vertex" else t["mass"]
        out = []
        for c in range(3):
            col = np.zeros((n, 3))
            col[:, c] = -h2 * weight
            out.append(col)
        return out
    if hypothesis == "vertex force":   # a force scale c_v per vertex: one column per vertex
        return [-h2 * t["force"]]
    if hypothesis == "vertex mass":    # a mass scale c_v per vertex: M (x − y) − h² m g
        return [t["inertia"] - h2 * t["force"]]
    raise ValueError(hypothesis)


def free_rows(step: StepData) -> np.ndarray:
    """The vertices whose gradient counts (not exactly pinned).

    Parameters
    ----------
    step : StepData

    Returns
    -------
    ndarray, shape (n,), bool
    """
    return step.problem.free_mask(len(step.x_port))


def relative(step: StepData, cols, theta, hypothesis: str | None = None) -> float:
    """‖R(θ)‖ / ‖∇g(x₀)‖ over the free vertices: the port's relative gradient under θ.

    Parameters
    ----------
    step : StepData
    cols : list of ndarray
        :func:`columns` of the hypothesis ([] for the scene's model).
    theta : array_like
        One value per column, or per vertex for ``vertex force``.
    hypothesis : str, optional
        The hypothesis of ``cols`` (one of :data:`REPLACING` drops the scene's force).

    Returns
    -------
    float
    """
    R = residual(step, hypothesis)
    if len(cols) == 1 and np.size(theta) == len(R) > 1:
        R = R + np.asarray(theta)[:, None] * cols[0]   # per-vertex scales
    elif len(cols):
        R = R + sum(t * c for t, c in zip(np.atleast_1d(theta), cols))
    return float(np.linalg.norm(R[free_rows(step)])) / step.gradient0


def fit(steps, hypothesis):
    """Least-squares θ of ``hypothesis`` over the steps jointly.

    Parameters
    ----------
    steps : list of StepData
        Each step's residual is weighted by 1/‖∇g(x₀)‖ of that step.
    hypothesis : str

    Returns
    -------
    ndarray or None
        θ, one value per column; None when the hypothesis changes nothing (no pins).
    """
    rows, rhs = [], []
    for s in steps:
        free = free_rows(s)
        cols = columns(s, hypothesis)
        rows.append(np.stack([c[free].ravel() for c in cols], 1) / s.gradient0)
        rhs.append(-residual(s, hypothesis)[free].ravel() / s.gradient0)
    B, y = np.concatenate(rows), np.concatenate(rhs)
    if not np.any(B):
        return None
    theta, *_ = np.linalg.lstsq(B, y, rcond=None)
    return theta


def fit_vertex_scale(step: StepData, hypothesis: str = "vertex force"):
    """Per-vertex scale c_v of a one-column hypothesis: c_v minimizes |R_v + c_v col_v| on
    its own (three equations, one unknown per vertex).

    Parameters
    ----------
    step : StepData
    hypothesis : {"vertex force", "vertex mass"}

    Returns
    -------
    ndarray, shape (n,)
        c_v (0 where the column vanishes, and at exact pins): the force (``vertex force``)
        or the mass (``vertex mass``) there is (1 + c_v) times the scene's.
    """
    col = columns(step, hypothesis)[0]
    R = residual(step)
    free = free_rows(step)
    den = np.einsum("ij,ij->i", col, col)
    c = np.where((den > 0) & free, -np.einsum("ij,ij->i", R, col) / np.where(den > 0, den, 1),
                 0.0)
    return c


def applicable(steps) -> list[str]:
    """The hypotheses that can change the steps' g.

    Parameters
    ----------
    steps : list of StepData

    Returns
    -------
    list of str
        Global ones first; ``pins`` only with penalty pins; ``family F`` (stiffness) and
        ``rest lengths F`` per spring family when there are several.
    """
    s = steps[0]
    out = ["stiffness", "rest lengths", "inertia"]
    if len(s.problem.anchors):
        out.append("pins")
    out += ["force per vertex", "force per unit mass", "stiffness and rest lengths"]
    if s.gravity is not None and s.problem.f_ext is not None:   # other forces beside it?
        m = s.model.vertex_mass
        with np.errstate(divide="ignore", invalid="ignore"):
            other = s.problem.f_ext / m[:, None] - np.asarray(s.gravity)[None, :]
        if np.all(m > 0) and np.abs(other).max() > 1e-9 * np.abs(s.gravity).max():
            out.append("gravity")
    families = np.unique(s.model.springs.spring_family)
    if len(families) > 1:
        out += [f"family {FAMILIES[f]}" for f in families]
        out += [f"rest lengths {FAMILIES[f]}" for f in families]
    return out
