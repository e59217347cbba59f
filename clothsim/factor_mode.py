"""Which CHOLMOD mode factors the global step's matrix, and when to change it.

For the global step's n × n matrix with three right-hand sides (x, y, z), simplicial
CHOLMOD solves faster than supernodal on small and mid-sized cloths, while supernodal
factors faster, by more the larger the cloth. Which one costs less therefore depends on
how many solves the factor serves, and that count is often not known in advance: an API
user calls :meth:`~clothsim.Simulation.run` a few steps at a time, or steps by hand.

:func:`choose_cholmod_mode` predicts both modes' factorization F and solve s from the free
vertices (:data:`MODE_COSTS`, measured) and decides:

- **a known count** N (``clothsim run``: frames × substeps × iterations) is the whole run:
  the mode with the smaller F + N s, final;
- **an unknown count**, or only a lower bound L (``Simulation.run(steps)``, stepping by
  hand): the *ski-rental rule*. When one mode both factors and solves faster, it, final.
  Otherwise the factor is made in the mode cheaper to factor (a), and the solver refactors
  in the mode with the faster solves (b) once this factor has served
  N* = ⌈F_b / (s_a − s_b)⌉ solves (:func:`switch_point`): the extra solve time paid then
  equals the factorization it saved (rent until the rent paid reaches the price of
  buying). When L alone already reaches the *break-even* (:func:`break_even`: the count
  from which b factored at once costs less), b at once, final.

**The bound.** For any number N of solves that follows, a factor chosen this way costs at
most F_a + F_b (plus the extra solve time of the step in which N* falls: counts come in
whole steps) more than the better of the two modes factored once for exactly N solves,
i.e. at most (2 + F_a / F_b) times it, under 3 times, and close to 2 on large cloths
where F_a ≪ F_b; before N* it costs at most F_a more (0 when a was the better mode), and
from N* on every solve is the faster one. No rule that cannot see the future guarantees a
ratio below 2. The bound is by the cost model: the predicted F and s, not the machine's.
Everything is decided from counts, never from timings, so a run repeats bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .errors import InputError
from .factorization import CHOLMOD_MODES

#: Cost model of the two CHOLMOD modes on the global step's matrix: for each mode, the
#: factorization's and one three-column solve's CPU seconds as power laws c · n^p of the
#: free vertices n, ``{mode: ((c_factor, p_factor), (c_solve, p_solve))}``. Fitted on the
#: ``hanging`` cloth's matrices from 65² to 513² by ``python -m benchmarks.scale_ladder
#: --mode-sizes 65,129,193,257,385,513`` (docs/data/cholmod-modes.md, which prints these fits;
#: tests/test_cholmod_mode.py checks they agree). scikit-sparse 0.4.16's symbolic analysis
#: (``cholmod.analyze``) exposes only the fill-reducing permutation, not CHOLMOD's nonzero
#: and flop counts of the factor, so the model predicts from n. The supernodal factor is
#: ordered by AMD alone: on the cloth grids it factored faster than CHOLMOD's
#: default (which also tries METIS) at 513² and 1025², and its solves are as fast.
MODE_COSTS = {"simplicial": ((1.296e-08, 1.676), (1.675e-08, 1.269)),
              "supernodal": ((8.604e-07, 1.194), (3.626e-08, 1.218))}
OTHER = {"simplicial": "supernodal", "supernodal": "simplicial"}


@dataclass(frozen=True)
class ModeChoice:
    """CHOLMOD's mode for one factorization, why, and when to change it.

    Attributes
    ----------
    mode : {"simplicial", "supernodal"}
        The mode to factor in.
    reason : str
        One line with the predicted seconds of both modes.
    switch_after : int or None
        The ski-rental point (:func:`switch_point`): the solver refactors in ``switch_to``
        once this factor has served as many solves. None when the choice is final (a known
        count, a request, a mode that both factors and solves faster, or a lower bound past
        the break-even).
    switch_to : str or None
        The mode with the faster solves, when ``switch_after`` is set.
    """

    mode: str
    reason: str
    switch_after: int | None = None
    switch_to: str | None = None


def predicted_costs(n: int, costs: dict | None = None) -> dict[str, tuple[float, float]]:
    """Predicted CPU seconds of each CHOLMOD mode for an n × n global-step matrix.

    Parameters
    ----------
    n : int
        Free vertices (the matrix's size).
    costs : dict, optional
        A cost model in the form of :data:`MODE_COSTS` (default: it).

    Returns
    -------
    dict
        ``{"simplicial": (factor [s], solve [s]), "supernodal": (factor [s], solve [s])}``,
        the solve with three right-hand sides.
    """
    costs = MODE_COSTS if costs is None else costs
    return {mode: tuple(c * float(n) ** p for c, p in pair) for mode, pair in costs.items()}


def break_even(n: int, mode: str, costs: dict | None = None) -> int | None:
    """Solves from which the other mode, factored from the start, costs less than ``mode``.

    Parameters
    ----------
    n : int
        Free vertices.
    mode : {"simplicial", "supernodal"}
        The mode factored.
    costs : dict, optional
        A cost model in the form of :data:`MODE_COSTS` (default: it).

    Returns
    -------
    int or None
        When the other mode's solves are the faster ones, the smallest solve count N with
        F_other + N s_other < F_mode + N s_mode (0 when it is cheaper for every count);
        None otherwise (the other mode is never the cheaper one).
    """
    gap = _solve_gap(n, mode, costs)
    return None if gap is None else max(0, math.floor(_settle((gap[1] - gap[0]) / gap[2])) + 1)


def _solve_gap(n: int, mode: str, costs: dict | None) -> tuple[float, float, float] | None:
    """(F_mode, F_other, s_mode − s_other), or None when the other mode's solves are not the
    faster ones."""
    pred = predicted_costs(n, costs)
    (f, s), (f_o, s_o) = pred[mode], pred[OTHER[mode]]
    return None if s_o >= s else (f, f_o, s - s_o)


def _settle(x: float) -> float:
    """x rounded to 9 significant digits: a ratio of predicted seconds that is a whole number
    in exact arithmetic stays whole (then floor and ceil agree with exact arithmetic)."""
    return float(f"{x:.9g}")


def switch_point(n: int, mode: str, costs: dict | None = None) -> int | None:
    """The ski-rental point of a factor in ``mode``: solves after which its extra solve time
    reaches the other mode's factorization, N* = ⌈F_other / (s_mode − s_other)⌉.

    Parameters
    ----------
    n : int
        Free vertices.
    mode : {"simplicial", "supernodal"}
        The mode factored.
    costs : dict, optional
        A cost model in the form of :data:`MODE_COSTS` (default: it).

    Returns
    -------
    int or None
        N* (at least 1), or None when the other mode's solves are not the faster ones.
    """
    gap = _solve_gap(n, mode, costs)
    return None if gap is None else max(1, math.ceil(_settle(gap[1] / gap[2])))


def choose_cholmod_mode(n: int, requested: str = "auto", expected_solves: int | None = None,
                        costs: dict | None = None, *, final: bool = True) -> ModeChoice:
    """CHOLMOD's mode for the global step's n × n matrix, why, and when to change it.

    "auto" decides by the predicted costs (:data:`MODE_COSTS`): with a known count, the mode
    whose factorization plus that many solves costs less, final; without one, the ski-rental
    rule of the module docstring (start in the mode cheaper to factor, switch to the mode
    with the faster solves at :func:`switch_point`), whose bound it states.

    Parameters
    ----------
    n : int
        Free vertices (the matrix's size).
    requested : {"auto", "simplicial", "supernodal"}
        ``[solver] cholmod_mode``: "auto" decides by the predicted cost.
    expected_solves : int, optional
        Solves the factor will serve: the whole run's count when ``final``, else at least
        this many (None: unknown).
    costs : dict, optional
        A cost model in the form of :data:`MODE_COSTS` (default: it).
    final : bool, default True
        Whether ``expected_solves`` is the whole run's count. When not (or when it is
        None), the count is unknown and the ski-rental rule decides.

    Returns
    -------
    ModeChoice
    """
    if requested not in CHOLMOD_MODES:
        raise InputError(f"solver.cholmod_mode: must be one of "
                         f"{', '.join(map(repr, CHOLMOD_MODES))}, got {requested!r}")
    if requested != "auto":
        return ModeChoice(requested, f"{requested}: requested by solver.cholmod_mode")
    pred = predicted_costs(n, costs)

    def cost(m: str, solves: int) -> str:
        f, s = pred[m]
        return f"factor {f:.3g} s + {solves} x {1e3 * s:.3g} ms = {f + solves * s:.3g} s"

    if final and expected_solves is not None:
        solves = int(expected_solves)
        mode = min(pred, key=lambda m: (pred[m][0] + solves * pred[m][1], m))
        return ModeChoice(mode, f"{mode}: {n} free vertices, {solves} expected solves: "
                                f"predicted {cost(mode, solves)}, {OTHER[mode]} "
                                f"{cost(OTHER[mode], solves)}")
    bound = int(expected_solves or 0)
    how = "the run's count is unknown" + (f", at least {bound}" if bound else "")
    cheap = min(pred, key=lambda m: (pred[m][0], m))
    fast = min(pred, key=lambda m: (pred[m][1], m))
    f = {m: f"{pred[m][0]:.3g} s" for m in pred}
    s = {m: f"{1e3 * pred[m][1]:.3g} ms" for m in pred}
    if cheap == fast:
        return ModeChoice(cheap, f"{cheap}: {n} free vertices, {how}: cheaper to factor and to "
                                 f"solve (predicted factor {f[cheap]} and solve {s[cheap]}, "
                                 f"{OTHER[cheap]} {f[OTHER[cheap]]} and {s[OTHER[cheap]]})")
    even = break_even(n, cheap, costs)
    if bound >= even:
        return ModeChoice(fast, f"{fast}: {n} free vertices, {how}: past the break-even "
                                f"({even} solves), predicted {cost(fast, bound)}, {cheap} "
                                f"{cost(cheap, bound)}")
    after = switch_point(n, cheap, costs)
    return ModeChoice(cheap, f"{cheap}: {n} free vertices, {how}: cheaper to factor "
                             f"(predicted {f[cheap]} against {f[fast]}); {fast} after "
                             f"{after} solves, when the extra solve time ({after} x "
                             f"({s[cheap]} - {s[fast]})) reaches its factor (ski rental)",
                      after, fast)


def switched_reason(n: int, mode: str, served: int, costs: dict | None = None) -> str:
    """The reason of a refactorization in ``mode`` at the ski-rental point.

    Parameters
    ----------
    n : int
        Free vertices.
    mode : {"simplicial", "supernodal"}
        The mode switched to.
    served : int
        Solves the previous factor served.
    costs : dict, optional
        A cost model in the form of :data:`MODE_COSTS` (default: it).

    Returns
    -------
    str
    """
    pred = predicted_costs(n, costs)
    other = OTHER[mode]
    return (f"{mode}: {n} free vertices, switched after {served} solves in {other} (ski "
            f"rental: their extra solve time reached this factor): predicted solve "
            f"{1e3 * pred[mode][1]:.3g} ms against {1e3 * pred[other][1]:.3g} ms, factor "
            f"{pred[mode][0]:.3g} s")
