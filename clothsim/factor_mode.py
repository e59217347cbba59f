"""Which CHOLMOD mode factors the global step's matrix, and when to change it.

For the global step's n × n matrix with three right-hand sides (x, y, z), simplicial
CHOLMOD solves faster than supernodal on small and mid-sized cloths, while supernodal
factors faster, by more the larger the cloth. Which one costs less therefore depends on
how many solves the factor serves, and that count is often not known in advance: an API
user calls :meth:`~clothsim.Simulation.run` a few steps at a time, or steps by hand.

:func:`choose_cholmod_mode` predicts both modes' factorization and solve from the free
vertices (:data:`MODE_COSTS`, measured) and picks the cheaper over a horizon:

- **a known count** (``clothsim run``: frames × substeps × iterations) is the whole run, and
  the mode is final;
- **a lower bound or nothing** (``Simulation.run(steps)``, stepping by hand): the horizon is
  the larger of the bound, :data:`ASSUMED_SOLVES` and the solves served so far (a run that
  has served many solves is expected to serve as many again). When the pick's solves are
  the slower ones, the choice records the *break-even*: the solve count after which the
  other mode, factored from the start, would have cost less. The solver refactors in the
  other mode once its factor has served that many (:class:`ModeChoice`).

By the cost model, whatever number of steps follows, a run therefore costs at most one
factorization (in the mode with the faster solves, plus the step in which the break-even
passes) more than the better of the two modes factored once would have, and from the
break-even on every solve uses the faster factor (the ski-rental rule: rent until the rent
paid reaches the price of buying; no rule that cannot see the future guarantees less than
such a bound). Everything is decided from counts, never from timings, so a run repeats bit
for bit.
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
#: ordered by AMD alone: on the cloth grids it factors about 1.5× faster than CHOLMOD's
#: default (which also tries METIS) at 513² and 1025², and its solves are as fast.
MODE_COSTS = {"simplicial": ((1.369e-08, 1.671), (1.474e-08, 1.279)),
              "supernodal": ((6.916e-07, 1.214), (2.715e-08, 1.245))}
#: Solves a factor is assumed to serve at least when the run's count is not known (an API
#: user stepping a simulation): 600, the scene defaults' run (60 frames × 1 substep × 10
#: iterations).
ASSUMED_SOLVES = 600


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
        Solves after which ``switch_to`` would have been cheaper from the start (the
        break-even): the solver refactors in that mode once this factor has served as many.
        None when the choice is final (a known count, a request, or a mode whose solves
        are not the slower ones).
    switch_to : str or None
        The other mode, when ``switch_after`` is set.
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
    """Solves after which the other mode, factored from the start, costs less than ``mode``.

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
        None otherwise (a switch to it would never pay back).
    """
    pred = predicted_costs(n, costs)
    other = "simplicial" if mode == "supernodal" else "supernodal"
    (f, s), (f_o, s_o) = pred[mode], pred[other]
    if s_o >= s:
        return None
    return max(0, math.floor((f_o - f) / (s - s_o)) + 1)


def choose_cholmod_mode(n: int, requested: str = "auto", expected_solves: int | None = None,
                        costs: dict | None = None, *, final: bool = True,
                        served: int = 0) -> ModeChoice:
    """CHOLMOD's mode for the global step's n × n matrix, why, and when to change it.

    "auto" picks the mode whose predicted factorization plus the horizon's solves costs
    less (:data:`MODE_COSTS`): simplicial's solves are faster on the smaller cloths,
    supernodal's factor is faster from about 10 000 free vertices up and gains more with
    size, so a run of few solves factors supernodal from a smaller size than a long one.

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
        None), the horizon is the largest of ``expected_solves``, :data:`ASSUMED_SOLVES`
        and ``served``, and a pick with the slower solves carries its break-even.
    served : int, default 0
        Solves the run has already served (with earlier factors).

    Returns
    -------
    ModeChoice
    """
    if requested not in CHOLMOD_MODES:
        raise InputError(f"solver.cholmod_mode: must be one of "
                         f"{', '.join(map(repr, CHOLMOD_MODES))}, got {requested!r}")
    if requested != "auto":
        return ModeChoice(requested, f"{requested}: requested by solver.cholmod_mode")
    final = final and expected_solves is not None
    if final:
        solves, how = int(expected_solves), f"{int(expected_solves)} expected solves"
    else:
        solves = max(ASSUMED_SOLVES, int(served), int(expected_solves or 0))
        how = (f"{solves} solves assumed (the run's count is unknown"
               + (f"; at least {int(expected_solves)}" if expected_solves is not None else "")
               + (f"; {int(served)} served" if served else "") + ")")
    pred = predicted_costs(n, costs)
    total = {m: f + solves * s for m, (f, s) in pred.items()}
    mode = "supernodal" if total["supernodal"] < total["simplicial"] else "simplicial"
    other = "simplicial" if mode == "supernodal" else "supernodal"

    def cost(m: str) -> str:
        f, s = pred[m]
        return f"factor {f:.3g} s + {solves} x {1e3 * s:.3g} ms = {total[m]:.3g} s"

    reason = (f"{mode}: {n} free vertices, {how}: predicted {cost(mode)}, "
              f"{other} {cost(other)}")
    after = None if final else break_even(n, mode, costs)
    if after is None:
        return ModeChoice(mode, reason)
    return ModeChoice(mode, reason + f"; {other} after {after} solves (the break-even)",
                      after, other)


def switched_reason(n: int, mode: str, served: int, costs: dict | None = None) -> str:
    """The reason of a refactorization in ``mode`` after the break-even.

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
    other = "simplicial" if mode == "supernodal" else "supernodal"
    return (f"{mode}: {n} free vertices, switched after {served} solves in {other} (the "
            f"break-even): predicted solve {1e3 * pred[mode][1]:.3g} ms against "
            f"{1e3 * pred[other][1]:.3g} ms, factor {pred[mode][0]:.3g} s")
