"""Tools for checking another implementation (a C++/GPU port) against clothsim.

:mod:`~clothsim.ports.formats` reads and writes trajectories in every format,
:mod:`~clothsim.ports.export` writes everything a port needs, :mod:`~clothsim.ports.compare`
compares trajectories and :mod:`~clothsim.ports.matrices` matrices,
:mod:`~clothsim.ports.check` checks a port one step at a time (and
:mod:`~clothsim.ports.causes` names the model a failing port solves),
:mod:`~clothsim.ports.diff` compares two models and :mod:`~clothsim.ports.conformance`
writes the conformance set. See docs/ports.md.
"""

from .check import CheckReport, StepCheck, check_steps
from .compare import (
    Comparison,
    compare_arrays,
    compare_trajectories,
    condition_number,
    match_vertices,
)
from .conformance import write_conformance
from .diff import ModelDiff, diff_models
from .export import export_matrices, export_port
from .formats import read_trajectory, read_velocities, write_trajectory
from .matrices import MatrixComparison, attachment_columns, compare_matrices

__all__ = [
    "CheckReport", "StepCheck", "check_steps", "Comparison", "MatrixComparison",
    "attachment_columns", "compare_arrays", "compare_matrices", "compare_trajectories",
    "condition_number",
    "match_vertices", "write_conformance", "ModelDiff", "diff_models", "export_matrices",
    "export_port", "read_trajectory", "read_velocities", "write_trajectory",
]
