"""The evidence on an ill-conditioned step: a port that meets the optimality criterion far away.

A port's answer x_p whose relative gradient ‖∇g(x_p)‖ / ‖∇g(x_0)‖ is within ``optimality``
meets the criterion a converged solver is held to. Yet when ∇²g is nearly singular along
some direction u (a flat sheet near buckling, a light cloth on stiff springs: λ_min ≪
λ_max), the gradient says little about the position: ‖x_p − x*‖ ≈ ‖∇g(x_p)‖ / λ_min can be
centimetres at a relative gradient of 1e-7. In general ‖x_p − x*‖ ≲ ‖∇g(x_p)‖ / λ_min, so an
answer within the criterion yet beyond the tolerance is always one the criterion cannot
place: a step ill-conditioned for that criterion at that tolerance. It is not the port's
error, nor proven right: it is undecided, and :func:`flat_evidence` says what is known and
what would decide it:

- the distance of x_p from the minimizer x* (Newton's method from x_p reaches it), and the
  objective gap g(x_p) − g(x*), beside the step's whole decrease g(x_0) − g(x*);
- the flat direction: the eigenvector u of the smallest eigenvalue λ_min of ∇²g(x*) over
  the free vertices, its largest vertex, and how much of x_p − x* lies along it; the
  curvature of g along x_p − x* (its Rayleigh quotient) beside λ_min and λ_max;
- what would decide: a port gradient below λ_min · tol / ‖∇g(x_0)‖ puts the port within
  the tolerance tol (‖x_p − x*‖ ≤ ‖∇g‖ / λ_min), and a smaller ``--optimality`` than the
  port's gradient judges its stopping rule too loose.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import ArpackError, ArpackNoConvergence, eigsh

from ..objective import objective
from ..solvers.newton import NewtonSolver

#: Below this many free degrees of freedom the spectrum is computed densely.
DENSE = 1500
#: ∇²g counts as nearly singular along the difference x_p − x* when its curvature there is
#: below this fraction of its largest eigenvalue (the note says so; the verdict is the same).
FLAT = 1e-6


def extreme_eigenpairs(H: sp.spmatrix):
    """λ_min with its eigenvector, and λ_max, of a symmetric matrix.

    Parameters
    ----------
    H : sparse matrix, shape (m, m)

    Returns
    -------
    (float, ndarray, float) or None
        λ_min, its unit eigenvector (m,), λ_max; None when Lanczos does not converge.
    """
    if H.shape[0] <= DENSE:
        w, V = np.linalg.eigh(H.toarray())
        return float(w[0]), V[:, 0], float(w[-1])
    try:
        hi = eigsh(H, k=1, which="LA", return_eigenvectors=False, tol=1e-6)[0]
        lo, vec = eigsh(H.tocsc(), k=1, sigma=0.0, which="LM", tol=1e-8)
    except (ArpackError, ArpackNoConvergence, RuntimeError):
        return None
    return float(lo[0]), vec[:, 0], float(hi)


def flat_evidence(model, problem, x_port, x_min, g0: float, rp: float, tol: float) -> str:
    """What is known about a port's answer that meets ``optimality`` off the minimizer.

    Parameters
    ----------
    model : Model
        The step's model.
    problem : StepProblem
    x_port, x_min : ndarray, shape (n, 3)
        The port's answer and the minimizer Newton's method reaches from it [m].
    g0 : float
        ‖∇g(x_0)‖ at the step's initial guess [N·s²].
    rp : float
        The port's relative gradient.
    tol : float
        The step's tolerance [m].

    Returns
    -------
    str
        One note: distance, objective gap, the curvature along the difference beside
        λ_min and λ_max (nearly singular below :data:`FLAT` λ_max), the flat direction and
        what would decide.
    """
    d = x_port - x_min
    off = np.linalg.norm(d, axis=1)
    far = int(np.argmax(off))
    g_min = objective(model, problem, x_min)
    gap = objective(model, problem, x_port) - g_min
    drop = objective(model, problem, problem.initial_guess()) - g_min
    note = (f"the port's answer meets the optimality criterion (relative gradient "
            f"{rp:.2e}) yet is {off[far]:.3e} m from the minimizer at vertex {far}; g exceeds "
            f"its minimum by {gap:.3e}" + (f" ({gap / drop:.1e} of the step's decrease)"
                                          if drop > 0 else ""))
    free = np.flatnonzero(problem.free_mask(model.vertex_count))
    dofs = (3 * free[:, None] + np.arange(3)).ravel()
    H = NewtonSolver(model).hessian(problem, x_min).tocsc()[dofs][:, dofs]
    dv = d.reshape(-1)[dofs]
    rayleigh = float(dv @ (H @ dv) / (dv @ dv))
    pairs = extreme_eigenpairs(H)
    decide = (f"To decide: --optimality below {rp:.1e} judges this stopping rule too loose")
    if pairs is None:
        return (note + f"; curvature of g along the difference {rayleigh:.2e} kg (the "
                f"Hessian's spectrum not found). {decide}")
    lo, u, hi = pairs
    share = float(abs(u @ dv) / np.linalg.norm(dv))
    uv = np.zeros((model.vertex_count, 3))
    uv[free] = u.reshape(-1, 3)
    top = int(np.argmax(np.linalg.norm(uv, axis=1)))
    need = max(lo, 0.0) * tol / g0
    shape = ("∇²g is nearly singular there" if rayleigh <= FLAT * hi else
             "g is flatter there than the criterion resolves at this tolerance")
    return (note + f"; {shape}: curvature along the difference {rayleigh:.2e} kg, λ_min = "
            f"{lo:.2e} kg, λ_max = {hi:.2e} kg; the flat direction (the eigenvector of "
            f"λ_min, largest at vertex {top}) holds {share:.0%} of the difference. {decide}, "
            f"and a port converged to a relative gradient below {need:.1e} is within the "
            f"tolerance {tol:.1e} m of the minimizer")
