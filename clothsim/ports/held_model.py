"""Model and solver settings under which clothsim's held steps are a hold-mode port's.

The replays of :mod:`clothsim.ports.replayed` solve a step with the contacts the check
holds fixed; a hold-mode step also catches vertices as they reach an obstacle and releases
them (:mod:`clothsim.ports.held_steps`), so a port with twice the gravity, or one
iteration fewer, catches others and no fixed-contact replay reproduces it: such ports
were FAIL with no cause. Here the setting is changed in clothsim's whole held steps, as
:func:`clothsim.ports.held_causes.shadow` replays an obstacle's setting (from the port's
states, the contact decisions carried), through :func:`clothsim.ports.held_causes.explain`:

- gravity × a factor s, fitted as the friction coefficient is: the replays at s = 1 (the
  scene's), 0.5 and 2, the step taken as linear in s between the two nearest the port's
  answer (a secant), refined twice;
- the solver's iteration count n ± 1 (a port that counts its iterations otherwise);
- a box wider or narrower on each side across gravity by 1, 2 or 4 cm (a box whose top
  face is where the scene's is, but wider, catches the cloth the same over its top and
  otherwise at its edges: no face's level tells, and the step changes in jumps with the
  width, so no secant fits it).

Each candidate is one replay of the step's window; the search stops at the first within
the step's tolerance.
"""

from __future__ import annotations

import numpy as np

__all__ = ["model_changes"]

#: Secant refinements of the gravity factor.
REFINE = 2
#: A box this much wider (or narrower) on each side is replayed [m], nearest first.
WIDER = (0.01, -0.01, 0.02, -0.02, 0.04, -0.04)


def _off(x, x_port) -> float:
    return float(np.linalg.norm(x - x_port, axis=1).max()) if x is not None else np.inf


def model_changes(held, x_port, x_cs, test, tol: float, change) -> None:
    """Replay gravity × a fitted factor and other iteration counts (module docstring).

    Parameters
    ----------
    held : HeldSteps
    x_port, x_cs : ndarray, shape (n, 3)
        The port's and clothsim's x_{k+1} [m].
    test : callable
        ``test(Change) -> x`` (None when the replay fails): replays and records it
        (:func:`clothsim.ports.held_causes.explain` keeps the nearest).
    tol : float
        The step's tolerance [m].
    change : type
        :class:`clothsim.ports.held_causes.Change` (made here for each setting).

    Returns
    -------
    None
        What each replay found is what ``test`` recorded.
    """
    sim = held.sim
    effects = list(sim.effects)
    gravity = next((e for e in effects if e.kind == "gravity"
                    and hasattr(e, "_force")), None)
    if gravity is not None and _gravity(change, gravity, effects.index(gravity), x_port, x_cs,
                                        test, tol):
        return
    solver = sim.solver
    n = getattr(solver, "iterations", 0)
    if not (getattr(sim, "_damped", False) or n < 2 or getattr(solver, "tolerance", None)):
        for m in (n - 1, n + 1):   # (a damped step's solver is made anew; a converged one
            fewer = change(solver, f"{m} {solver.name} iterations instead of {n}",
                           "[solver] iterations", {"iterations": m})   # stops)
            if m >= 1 and _off(test(fewer), x_port) <= tol:
                return
    for e in (e for e in effects if e.kind == "box" and e in held.obstacles):
        for d in (WIDER if gravity is not None else ()):
            if _off(test(_wider(change, e, effects.index(e), d, gravity.acceleration)),
                    x_port) <= tol:
                return


def _gravity(change, e, index, x_port, x_cs, test, tol) -> bool:
    """Gravity × a factor fitted on held replays; True when one is within ``tol``."""
    a0, f0 = e.acceleration.copy(), e._force.copy()

    def at(s):
        return change(e, f"gravity {_vec(s * a0)} m/s² instead of {_vec(a0)} m/s²",
                           f"effects[{index}].acceleration (gravity)",
                           {"acceleration": s * a0, "_force": s * f0})

    return _secant(at, (1.0, x_cs), (0.5, 2.0), x_port, test, tol, (0.0, 10.0))


def _wider(change, e, index, d, g):
    """The box ``d`` [m] wider on each side across gravity (its height kept)."""
    across = np.abs(np.asarray(g, float)) < 1e-12 * max(float(np.abs(g).max()), 1e-300)
    grow = d * across
    return change(e, f"a box {100 * d:.3g} cm {'wider' if d > 0 else 'narrower'} on each "
                     f"side (min {_vec(e.min - grow)}, max {_vec(e.max + grow)} m instead "
                     f"of {_vec(e.min)}, {_vec(e.max)} m)", f"effects[{index}].min and .max "
                  "(the box)", {"min": e.min - grow, "max": e.max + grow})


def _secant(change, scene, probes, x_port, test, tol, bounds) -> bool:
    """A setting fitted on held replays: the step taken as linear in it between the two
    replays nearest the port's answer (the scene's value and ``probes``), refined
    :data:`REFINE` times within ``bounds``; True when one is within ``tol``."""
    points = [scene] + [(s, x) for s in probes if (x := test(change(s))) is not None]
    for _ in range(REFINE + 1):
        points = sorted(points, key=lambda p: _off(p[1], x_port))[:2]
        if len(points) < 2 or _off(points[0][1], x_port) <= tol:
            break
        (a, xa), (b, xb) = points
        dx = xb - xa
        denom = float(np.sum(dx * dx))
        c = a + (b - a) * float(np.sum((x_port - xa) * dx)) / denom if denom else a
        if not bounds[0] < c <= bounds[1] or min(abs(c - a), abs(c - b)) <= 1e-6 * abs(b - a):
            break
        x = test(change(c))
        if x is None:
            break
        points.append((c, x))
    return bool(points) and _off(min(points, key=lambda p: _off(p[1], x_port))[1],
                                 x_port) <= tol


def _vec(v) -> str:
    return "(" + ", ".join(f"{c:.4g}" if abs(c) > 1e-12 else "0" for c in v) + ")"
