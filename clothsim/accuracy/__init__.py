"""What accuracy costs in time: solver error and time-step error, measured separately.

Two kinds of accuracy, both for the implicit Euler problem of Liu et al. (2013), Eq. 4
(x_{n+1} = argmin g(x), g(x) = ½ (x − y)ᵀ M (x − y) + h² E(x)):

1. **Solver error within a step.** Step problems are recorded along one converged run
   (:mod:`.problems`); each gets a certified reference x*
   (:mod:`clothsim.accuracy.reference`); every configuration solves the *same* problems
   (:mod:`.study`), timed in interleaved repeats (:mod:`.timing`). The error is
   ‖x − x*‖ / ‖x* − x_n‖. Steps at rest, trivially solved or with two minima are counted,
   never measured.
2. **Time-step error** (:mod:`.timestep`): converged solves at several h against a
   Richardson-extrapolated small-h reference (:mod:`.trajectory`), with the regime where
   implicit Euler is not yet first order named instead of fitted.

:func:`run_accuracy` is ``clothsim accuracy``; :func:`paper_report` its ``--paper`` preset.
Single-step traces (:func:`trace_solver`), the older trajectory sweep (:func:`run_sweep`)
and implicit Euler's damping (:mod:`.damping`) remain available. docs/accuracy.md shows
the results and explains every CSV column.
"""

from .answer import answer_table
from .command import run_accuracy, scene_factory
from .converged import reference_trajectory
from .damping import (
    damping_curves,
    energy_curves,
    implicit_euler_amplitude,
    single_spring,
    single_spring_heights,
)
from .paper import paper_report
from .plots import (
    plot_convergence,
    plot_damping,
    plot_fixed_budget,
    plot_frontier,
    plot_solver_accuracy,
)
from .problems import RecordedStep, classify, record_problems
from .reference import CertifiedReference, certified_reference
from .report import COLUMNS, fixed_budget_table
from .study import Configuration, default_configurations, measure, prepare_steps
from .sweep import (
    CSV_FIELDS,
    TRAJECTORY_LEVELS,
    cheapest,
    cheapest_in_step,
    pareto_front,
    run_sweep,
    write_csv,
)
from .timestep import TimeStepStudy, time_step_study
from .trace import (
    ACCURACY_LEVELS,
    EXPLICIT_METHODS,
    ITERATIVE_METHODS,
    IterateTrace,
    converged_solution,
    iterates,
    representative_problem,
    solver_accuracy,
    trace_solver,
)
from .trajectory import (
    SweepRow,
    Trajectory,
    convergence_slope,
    mechanical_energy,
    run_trajectory,
    steps_per_frame,
    trajectory_error,
)

__all__ = [
    "ACCURACY_LEVELS", "COLUMNS", "CSV_FIELDS", "EXPLICIT_METHODS", "ITERATIVE_METHODS",
    "TRAJECTORY_LEVELS", "CertifiedReference", "Configuration", "IterateTrace",
    "RecordedStep", "SweepRow", "TimeStepStudy", "Trajectory", "answer_table",
    "certified_reference", "cheapest", "cheapest_in_step", "classify", "convergence_slope",
    "converged_solution", "damping_curves", "default_configurations", "energy_curves",
    "fixed_budget_table", "implicit_euler_amplitude", "iterates", "measure",
    "mechanical_energy", "paper_report", "plot_convergence", "plot_damping",
    "plot_fixed_budget", "plot_frontier", "plot_solver_accuracy", "pareto_front",
    "prepare_steps", "record_problems",
    "reference_trajectory", "representative_problem", "run_accuracy", "run_sweep",
    "run_trajectory", "scene_factory", "single_spring", "single_spring_heights",
    "solver_accuracy", "steps_per_frame", "time_step_study", "trace_solver",
    "trajectory_error", "write_csv",
]
