"""A setting named at one step of a hold-mode port, carried on to the steps after it.

Once :func:`clothsim.ports.held_causes.explain` names an obstacle or contact setting that
reproduces a failing step within its tolerance, each later step is taken again from the
port's state with that setting, on the contact decisions its own held steps carried to
there (:func:`carry`). A failing step it reproduces says so; one it does not is a
**further difference** of the port's (:func:`followed`), not the first one again, unless
the setting reproduces the step after it again (:func:`transient`). The further
difference itself is searched for as the first was, with the named setting kept
(:func:`beyond`): a port with two faults gets both named, each at the step it shows.
"""

from __future__ import annotations

import numpy as np

from .held_causes import Change, explain, shadow

__all__ = ["beyond", "carry", "followed", "transient"]


def carry(held, change: Change, state):
    """clothsim's held step from the port's ``state`` with ``change``, on the decision its
    held steps with the change carried to here (:attr:`Change.carried`), carried further.

    Once a setting is named (:func:`explain`), each later step is taken with it, so that a
    step it does not reproduce is a further difference of the port's, not the first one
    again.

    Parameters
    ----------
    held : HeldSteps
        The check's, anchored at the step and stepped (restored afterwards).
    change : Change
        Named at an earlier step; its :attr:`~Change.carried` is advanced.
    state : State
        The port's (x_k, v_k).

    Returns
    -------
    ndarray, shape (n, 3), or None
        That step's x_{k+1} [m] (None: no decision to go on from, or the step failed).
    """
    if change.carried is None:
        return None
    xs = shadow(held, change, [(state, change.carried)])
    return xs[-1] if xs else None


def followed(held, named, state, x_port, err, tol):
    """A later step under the setting named before: reproduced, or a further difference.

    Parameters
    ----------
    held : HeldSteps
        Anchored at the step and stepped.
    named : (Change, int)
        The setting and the step it was named at, reproduced there within the tolerance.
    state : State
        The port's (x_k, v_k).
    x_port : ndarray, shape (n, 3)
        The port's x_{k+1} [m].
    err : ndarray, shape (n,)
        |x_clothsim − x_port| of the scene's step [m].
    tol : float

    Returns
    -------
    (Change or None, str, str)
        The change when it reproduces the step and the step fails, its note, and the note
        of a further difference (the change does not reproduce a failing step) or "".
    """
    change, k0 = named
    x = carry(held, change, state)
    scene = float(err.max())
    if scene <= tol or x is None:
        return None, "", ""
    off = np.linalg.norm(x - x_port, axis=1)
    d, worst = float(off.max()), int(np.argmax(off))
    if d <= tol:
        return change, (f"the port's steps are clothsim's held steps with {change.words} "
                        f"(named at step {k0} -> {k0 + 1}, its decisions carried from there: "
                        f"{d:.1e} m off the port's answer, against {scene:.1e} m with the "
                        f"scene's; look at {change.setting})"), ""
    return None, "", (f"a further difference: with {change.words} (named at step {k0} -> "
                      f"{k0 + 1}, its decisions carried from there) clothsim's held step is "
                      f"still {d:.1e} m from the port's answer at vertex {worst}, beyond the "
                      f"tolerance {tol:.1e} m (against {scene:.1e} m with the scene's): the "
                      f"port differs by something more from this step on")


def transient(steps) -> None:
    """Withdraw a further difference the named setting reproduces the step after again.

    A setting whose value is read off the port (a sphere's radius) replays the port's
    steps to rounding, and its carried decisions can still take a marginal one otherwise
    (drape-sphere with its radius 0.31: step 12 -> 13 2.6e-3 m off, step 13 -> 14 named
    again): a second fault of the port's does not end after one step and leave the
    setting reproducing it. Such a step keeps its verdict, not the further difference.

    Parameters
    ----------
    steps : list of StepCheck
        The checked steps, in order (changed in place).
    """
    for a, b in zip(steps, steps[1:], strict=False):
        if a.further and not b.further and not b.passed and "held steps with" in b.note:
            a.further = False
            a.note = a.note.replace("a further difference: with", "not a further difference "
                                    "(the setting reproduces the next step again): with", 1)


def beyond(held, change: Change, x_port, x_cs, err, tol):
    """The second setting of a further difference: the single-setting search of
    :func:`~clothsim.ports.held_causes.explain` run with ``change`` kept on its obstacle.

    Parameters
    ----------
    held : HeldSteps
        Anchored at the step and stepped.
    change : Change
        The setting named at an earlier step.
    x_port, x_cs : ndarray, shape (n, 3)
        The port's and clothsim's x_{k+1} [m].
    err : ndarray, shape (n,)
        |x_clothsim − x_port| of the scene's step [m].
    tol : float

    Returns
    -------
    (Change or None, str)
        The second setting and its words, with how near the two together come; (None, "")
        when no single further setting reproduces the step within its tolerance.
    """
    if change.rule:   # a rule changes the decision each step starts from: not kept here
        return None, ""
    with change.applied():
        second, _, d = explain(held, x_port, x_cs, err, tol)
    if second is None or d > tol or second.setting == change.setting:
        return None, ""
    return second, (f"with that setting kept, clothsim's held steps with {second.words} too "
                    f"are {d:.1e} m off the port's answer: the port differs by that as well "
                    f"(look at {second.setting})")
