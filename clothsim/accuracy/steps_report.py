"""steps.md: the class legend, a count per class and one line per recorded step."""

from __future__ import annotations

from collections.abc import Sequence

from .study import KINDS, StudyStep

STEP_CLASSES = """Step classes (by certificate; a certified minimum has ‖∇g‖ at its rounding
floor and a Hessian that factors without shift, λ_min > 0):

- unique: Newton from y, from x_n and from converged local/global reach one certified
  minimum x*; measured by the solver error ‖x − x*‖ / ‖x* − x_n‖.
- several-minima: the starts reach several certified minima; measured by the relative
  objective gap (g(x) − g(x_best)) / (g(y) − g(x_best)), x_best the lowest of them.
- saddle: Newton from y stopped at a stationary point with an indefinite Hessian; never
  reported as a minimum, not measured.
- reference-failed: Newton from y did not reach its rounding floor; not measured.
- trivial: one local/global iteration is already within 1e-12 (free fall); not measured.
- at-rest: ‖∇g(y)‖ within 1e3 of its rounding floor; not measured.

Column 'recorded': whether the recording run's Newton met its tolerance on the step.
Column 'own limits': per method, the objective gap of the minimum it converges to on its
own (run to its rounding floor, then certified by Newton): "x_best" when that is the
lowest certified minimum; "(not converged)" when it stopped at its cap, "(uncertified)"
when the end point is not a certified minimum."""


def steps_table(steps: Sequence[StudyStep]) -> str:
    """One line per recorded step: class, rest ratio, one-iteration error, certificate.

    Parameters
    ----------
    steps : sequence of StudyStep
        The classified steps.

    Returns
    -------
    str
        The class legend (:data:`STEP_CLASSES`), a count per class and a Markdown table.
    """
    kinds = [s.kind for s in steps]
    counts = ", ".join(f"{k} {kinds.count(k)}" for k in KINDS)
    lines = [STEP_CLASSES, "", f"Steps per class: {counts}.", "",
             "| step | t [s] | recorded | kind | ‖∇g(y)‖/floor | 1-iteration error "
             "| Newton residual | certified | λ_min(H)/m_min | minima | uncertainty "
             "| g(x_best) − g(x*) | rho_local_global | own limits |",
             "|---" * 14 + "|"]
    for s in steps:
        ref = s.reference
        cert = ("| | | | | | | | |" if ref is None else
                f"| {ref.residual:.1e} | {'yes' if ref.certified else 'no'} "
                f"| {ref.min_eigenvalue:.3g} | {ref.minima} | {ref.uncertainty:.1e} "
                f"| {ref.objective_difference:.2e} | {s.rho:.4f} | {_limits(s)} |")
        rec = {True: "converged", False: "missed tolerance", None: "–"}[s.step.converged]
        lines.append(f"| {s.step.index} | {s.step.time:.4g} | {rec} | {s.kind} "
                     f"| {s.rest_ratio:.2e} | {s.one_iteration_error:.2e} {cert}")
    return "\n".join(lines)


def _limits(step: StudyStep) -> str:
    """'method: gap' per method's own limit ("x_best": same minimum as x_best)."""
    cells = []
    for lim in step.limits.values():
        gap = "x_best" if lim.same_as_best else f"{lim.gap:.1e}"
        flags = ("" if lim.converged else " (not converged)") + \
            ("" if lim.certified else " (uncertified)")
        cells.append(f"{lim.method}: {gap}{flags}")
    return "; ".join(cells) or "–"
