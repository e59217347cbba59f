"""Local/global iterations with Chebyshev semi-iterative acceleration (Wang 2015).

Plain local/global (:class:`~clothsim.solvers.LocalGlobalSolver`) is a fixed-point
iteration x ↦ G(x) that converges linearly: near the solution x* the error obeys
e_{k+1} ≈ T e_k with T = I − A⁻¹H, A = M + h² L the global-step matrix and H = ∇²g(x*).

The shifted form (why γ = 2/(2−ρ))
----------------------------------
Each spring's Hessian block k [u uᵀ + (1 − r/l)(I − u uᵀ)] is at most k I, so H ⪯ A and the
spectrum of T lies in [0, ρ] (ρ the spectral radius, the observed decay rate): it is
*non-negative* because the global step is an exact solve. Chebyshev semi-iteration is
optimal for a spectrum in a symmetric interval [−ρ', ρ']. The relaxed map
x ↦ x + γ (G(x) − x) has the linear part T_γ = γ T + (1 − γ) I, which sends λ ∈ [0, ρ] to
γ λ + 1 − γ. Asking the ends to land on −ρ' and +ρ' gives 1 − γ = −ρ' and γ ρ + 1 − γ = ρ',
hence

    γ = 2 / (2 − ρ),    ρ' = γ − 1 = ρ / (2 − ρ).

γ > 1 *over*-relaxes (Wang's γ ≈ 0.9 under-relaxes, which suits an inexact, Jacobi-type
global step whose spectrum reaches −ρ, not the exact Cholesky solve used here). The
iteration, with delay S (plain local/global steps before acceleration starts), is

    ω_k     = 1, γ_k = 1                 for k < S
    ω_S     = 2 / (2 − ρ'²)
    ω_{k+1} = 4 / (4 − ρ'² ω_k)          for k > S, γ_k = γ for k ≥ S
    x_{k+1} = ω_{k+1} (γ_k (G(x_k) − x_k) + x_k − x_{k−1}) + x_{k−1}.

No over-relaxation without acceleration: while k < S the step is plain local/global
(γ_k = 1), so a run of at most S iterations per step is local/global itself, never
local/global over-relaxed by γ ≈ 2 (which diverges: the relaxed spectrum [1 − γ, γρ + 1 − γ]
is only contracted by the Chebyshev polynomial, not by a lone relaxed step).

With ρ = 0 (γ = 1, all ω = 1) it is plain local/global, bit for bit.

Ceiling
-------
Iterations to a given error shrink by at most ln ρ / ln r, r the asymptotic Chebyshev rate.
On the symmetric interval [−ρ, ρ] (the unshifted method) r = ρ / (1 + √(1 − ρ²)) and the
gain is about √(2 / (1 − ρ)) (≈ 5× at ρ = 0.92, ≈ 14× at ρ = 0.99). The shifted form has
r = (1 − √(1 − ρ))² / ρ and in linear theory gains about 2 / √(1 − ρ) (7× at ρ = 0.92);
the nonlinear local step and a spectrum that does not fill [0, ρ] keep the measured gain
near the √(2 / (1 − ρ)) ceiling (see docs/accuracy.md). Either way the gain grows only
like (1 − ρ)^(−½): Chebyshev cannot turn a slowly converging step into a fast one.

ρ sensitivity
-------------
An eigenvalue of T above the assumed ρ maps outside [−ρ', ρ'], where the Chebyshev
polynomial grows: *underestimating* ρ makes the iteration diverge, overestimating it only
loses speed. :func:`estimate_spectral_radius` therefore fits the decay over many
(default 150) plain iterations, where the update ratio has settled on the slowest mode,
and does not shrink the estimate. docs/accuracy.md shows iterations against ρ.

References
----------
H. Wang. A Chebyshev Semi-Iterative Approach for Accelerating Projective and Position-based
Dynamics. ACM Transactions on Graphics 34(6), 246, 2015. DOI 10.1145/2816795.2818063.
G. H. Golub, R. S. Varga. Chebyshev semi-iterative methods, successive overrelaxation
iterative methods, and second order Richardson iterative methods. Numer. Math. 3, 1961.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator

import numpy as np

from ..errors import InputError, check_finite
from ..model import Model
from .base import Iterate, StepProblem, gradient_noise_floor
from .held_accel import fused_step
from .local_global import LocalGlobalSolver

log = logging.getLogger(__name__)

DEFAULT_DELAY = 2
RHO_CAP = 0.99999


def estimate_spectral_radius(model: Model, problem: StepProblem, *, iterations: int = 150,
                             fit_last: int = 50, safety: float = 1.0,
                             backend: str = "auto",
                             solver: LocalGlobalSolver | None = None) -> float:
    """Estimate the convergence rate ρ of local/global iterations on one step.

    Parameters
    ----------
    model : Model
        The cloth (masses [kg], springs [N/m, m]).
    problem : StepProblem
        A representative step of the scene (e.g. one taken mid-motion).
    iterations : int, default 150
        Plain local/global iterations to run (the update ratio needs ~100–200 iterations
        to settle on the slowest mode; fewer underestimate ρ).
    fit_last : int, default 50
        Fit ρ as the geometric mean of ‖Δx_{k+1}‖ / ‖Δx_k‖ over the last ``fit_last``
        iterations, Δx_k = x_k − x_{k−1}.
    safety : float, default 1.0
        The returned value is ``safety * ρ``, capped at 0.99999.
    backend : {"auto", "cholmod", "splu"}
        Factorization backend of the solver built when ``solver`` is not given.
    solver : LocalGlobalSolver, optional
        Reuse this solver's cached factor (its ``iterates`` are consumed; the solver's
        settings are not changed).

    Returns
    -------
    float
        ρ in [0, 1) (dimensionless); 0 when the iteration converged at once: when x_0 or
        the first update's x_1 is already at the gradient's rounding floor
        (:func:`~clothsim.objective.gradient_noise_floor`). Updates after an iterate at
        the floor are rounding noise and are not fitted.
    """
    if iterations < 3 or fit_last < 1:
        raise InputError(f"estimate_spectral_radius: need iterations >= 3 and fit_last >= 1, "
                         f"got {iterations} and {fit_last}")
    lg = solver if solver is not None else LocalGlobalSolver(model, backend=backend)
    steps = []
    x_prev = floor = None
    for it in LocalGlobalSolver.iterates(lg, problem):
        if x_prev is not None:
            steps.append(float(np.linalg.norm(it.x - x_prev)))
        else:
            floor = gradient_noise_floor(model, problem, it.x)
        # at the rounding floor the updates are noise: their ratios say nothing about ρ
        if it.k >= iterations or not it.gradient_norm > floor:
            break
        x_prev = it.x.copy()
    steps = np.asarray(steps)
    ratios = steps[1:] / np.where(steps[:-1] > 0, steps[:-1], np.inf)
    ratios = ratios[np.isfinite(ratios) & (ratios > 0)][-fit_last:]
    if len(ratios) == 0:  # converged at once: nothing to accelerate
        return 0.0
    rho = float(np.exp(np.mean(np.log(ratios))))
    rho = min(safety * rho, RHO_CAP)
    log.info("estimated local/global spectral radius rho=%.6f from %d ratios", rho, len(ratios))
    return max(rho, 0.0)


class ChebyshevSolver(LocalGlobalSolver):
    """Local/global iterations accelerated by shifted Chebyshev semi-iteration (Wang 2015).

    Parameters
    ----------
    model : Model
    iterations : int, default 10
        Iterations per step (each one local step + one global step); the maximum when
        ``tolerance`` is set.
    tolerance : float, optional
        Stop once ‖∇g(x_k)‖ / ‖∇g(x_0)‖ is at most this.
    rho : float, optional
        Spectral radius ρ ∈ [0, 1) of plain local/global for this scene and h.
        Default: estimated by :func:`estimate_spectral_radius` on the first solved step and
        kept (a one-off cost; :meth:`get_state` / :meth:`set_state` carry it over a resume).
        A step that converges at once (free fall: no spring changes length) gives ρ = 0,
        which says nothing of the scene: it serves that step only, and the next step
        estimates again (a cloth dropped onto an obstacle is accelerated once it lands).
    delay : int, default 2
        S: plain local/global iterations (ω = γ = 1) before acceleration starts (0–3 is right for
        an exact global step; Wang's S = 10 suits an inexact one).
    gamma : float, optional
        Relaxation γ ∈ (0, 2); default 2 / (2 − ρ), the shift that centres the spectrum.
    backend : {"auto", "cholmod", "splu"}
        Sparse factorization of M + h² L (:class:`~clothsim.factorization.Factor`).
    check_conditioning : bool, default True
        Warn when a new factor's condition estimate passes 1e12.

    Attributes
    ----------
    rho_estimations : int
        How many times ρ was estimated (one-off cost, reported apart from per-step cost).
    rho : float or None
        ρ in use (None until estimated).
    delay : int
        S, as given.
    gamma_option : float or None
        γ as given (None: 2 / (2 − ρ)); :attr:`gamma` is the value in use.
    """

    name = "chebyshev"

    def __init__(self, model: Model, *, iterations: int = 10, tolerance: float | None = None,
                 backend: str = "auto", check_conditioning: bool = True,
                 rho: float | None = None, delay: int = DEFAULT_DELAY,
                 gamma: float | None = None):
        super().__init__(model, iterations=iterations, tolerance=tolerance, backend=backend,
                         check_conditioning=check_conditioning)
        if rho is not None:
            rho = float(check_finite("solver.rho", rho))
            if not 0.0 <= rho < 1.0:
                raise InputError(f"solver.rho: must be in [0, 1), got {rho!r}")
        if not isinstance(delay, (int, np.integer)) or delay < 0:
            raise InputError(f"solver.delay: must be an integer >= 0, got {delay!r}")
        if gamma is not None:
            gamma = float(check_finite("solver.gamma", gamma))
            if not 0.0 < gamma < 2.0:
                raise InputError(f"solver.gamma: must be in (0, 2), got {gamma!r}")
        self.rho = rho
        self._rho_provisional = False  # ρ = 0 from a step that converged at once
        self.delay = int(delay)
        self.gamma_option = gamma
        self.rho_estimations = 0

    @property
    def gamma(self) -> float:
        """γ in use: the option, or 2 / (2 − ρ) (1 while ρ is unknown)."""
        if self.gamma_option is not None:
            return self.gamma_option
        return 2.0 / (2.0 - (self.rho or 0.0))

    @property
    def shifted_rho(self) -> float:
        """ρ' = |γ − 1| ∨ γ ρ + 1 − γ: the half-width of the relaxed spectrum."""
        rho, gamma = self.rho or 0.0, self.gamma
        return max(abs(1.0 - gamma), gamma * rho + 1.0 - gamma)

    def omega(self, k: int, omega_prev: float) -> float:
        """The Chebyshev weight ω_{k+1} (Wang 2015, Eq. 11, with delay S).

        ω = 1 for k < S, ω_S = 2 / (2 − ρ'²), then ω_{k+1} = 4 / (4 − ρ'² ω_k), with
        ρ' = :attr:`shifted_rho`.

        Parameters
        ----------
        k : int
            The iteration (0-based).
        omega_prev : float
            ω_k, the previous weight (ignored for k ≤ S).

        Returns
        -------
        float
            ω_{k+1} (dimensionless, in [1, 2)).
        """
        rho2 = self.shifted_rho ** 2
        if k < self.delay:
            return 1.0
        if k == self.delay:
            return 2.0 / (2.0 - rho2)
        return 4.0 / (4.0 - rho2 * omega_prev)

    def get_state(self) -> dict:
        """The per-run state a resumed run needs to continue bit for bit.

        Returns
        -------
        dict
            ``{"rho": ρ or None}`` (JSON-able).
        """
        return {"rho": None if self._rho_provisional else self.rho}

    def set_state(self, state: dict) -> None:
        """Restore :meth:`get_state`'s output (a missing key leaves ρ unchanged).

        Parameters
        ----------
        state : dict
            ``{"rho": float or None}``.
        """
        if "rho" in state:
            rho = state["rho"]
            self.rho = None if rho is None else float(rho)
            self._rho_provisional = False

    def iterates(self, problem: StepProblem, x0: np.ndarray | None = None) -> Iterator[Iterate]:
        """Yield the initial guess, then each accelerated iterate, without end.

        Each iterate costs one local/global iteration of :class:`~.fused.FusedStep` and one
        linear combination of three rows (its ‖∇g‖ comes for free). ρ is estimated first
        when not known. With G(x_k) the plain local/global iterate from x_k (Wang 2015,
        shifted as in the module docstring),

            x_{k+1} = ω_{k+1} (γ_k (G(x_k) − x_k) + x_k − x_{k−1}) + x_{k−1},

        γ_k = 1 for k < S (plain local/global before acceleration), γ after.

        Parameters
        ----------
        problem : StepProblem
            The step's h [s], y [m], f_ext [N] and pins.
        x0 : ndarray, shape (n, 3), optional
            Initial guess [m]; default y with the pins applied.

        Yields
        ------
        Iterate
            k, x of shape (n, 3) [m] (the solver's array: copy it to keep it) and
            ‖∇g(x)‖ over the free degrees of freedom [N·s²].
        """
        self.system(problem)
        if self.rho is None or self._rho_provisional:
            self.rho = estimate_spectral_radius(self.model, problem, solver=self)
            self.rho_estimations += 1
            self._rho_provisional = self.rho == 0.0  # see the ``rho`` parameter
        gamma = self.gamma
        step = fused_step(self, problem, x0)   # held contacts: on the planes (.held_accel)
        yield Iterate(0, step.x, step.norm0, d=step.current_directions())
        # rows [δ | a] of G(x_k), x_k, x_{k−1} (δ_F = x_F − y_F, a = A_FF δ_F): the update
        # is one linear combination of the three rows, and A_FF δ̂ = rhs(x_k) gives a for
        # free, so ‖∇g(x_{k+1})‖ = ‖a_{k+1} − rhs(x_{k+1})‖ (clothsim.solvers.fused)
        m = step.delta.size
        rows = np.empty((3, 2 * m))
        rows[1, :m], rows[1, m:] = step.delta.reshape(-1), step.a0.reshape(-1)
        rows[2] = rows[1]
        hat, cur, prev = 0, 1, 2
        coef = np.zeros(3)
        shape = step.delta.shape
        delay, rho2 = self.delay, self.shifted_rho ** 2
        omega = 1.0
        k = 0
        while True:
            rows[hat, :m] = step.solve().reshape(-1)
            rows[hat, m:] = step.rhs.reshape(-1)
            # ω and γ as self.omega and the delay say (inlined: this loop is the hot path)
            if k < delay:   # plain local/global: no over-relaxation before acceleration
                omega, g = 1.0, 1.0
            else:
                omega = 2.0 / (2.0 - rho2) if k == delay else 4.0 / (4.0 - rho2 * omega)
                g = gamma
            coef[hat], coef[cur], coef[prev] = omega * g, omega * (1.0 - g), 1.0 - omega
            new = coef @ rows
            rows[prev] = new
            cur, prev = prev, cur
            step.advance(new[:m].reshape(shape))
            k += 1
            yield Iterate(k, step.x, step.gradient_norm(new[m:].reshape(shape)),
                          d=step.current_directions())
