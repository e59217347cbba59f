"""The same step problems for every configuration: recorded along one converged run.

:func:`record_problems` runs a simulation (solved to convergence, at the scene's own h,
frames and substeps) and keeps the step problems of several steps spread over the whole
run — contact and buckling included, whatever the run goes through. Every configuration of
the study then solves exactly these problems (never its own drifting state), so rows are
comparable. The run uses one BLAS/OpenMP thread (a recording does not depend on the
machine's thread count), and a recorded step whose solve missed its tolerance is marked
(:attr:`RecordedStep.converged`). :func:`save_problems` writes the recorded problems to a
``.npz`` file with a digest of the model they belong to (:func:`step_digest`), and
:func:`load_problems` reads them back exactly, so a study can be re-run on the same steps
(a file recorded on another cloth or at another h is refused). :func:`classify` names the
steps that teach nothing:

``"at-rest"``
    ‖∇g(y)‖ within 1e3 of its rounding floor
    (:func:`clothsim.solvers.base.gradient_noise_floor`): the cloth does not move; any
    "error" is rounding noise.
``"trivial"``
    one local/global iteration already reaches relative error 1e-12 (free fall: the
    springs are at rest length and the global step is exact).
``"measured"``
    everything else.
"""

from __future__ import annotations

import copy
import hashlib
import logging
import warnings
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..factorization import single_threaded
from ..io.common import atomic_path, special_file
from ..model import Model
from ..simulation import Simulation
from ..solvers import LocalGlobalSolver, StepProblem, objective_gradient
from ..solvers.base import gradient_noise_floor
from .phases import advance

log = logging.getLogger(__name__)

AT_REST_FACTOR = 1e3
TRIVIAL_ERROR = 1e-12


@dataclass(eq=False)
class RecordedStep:
    """One recorded step problem.

    Attributes
    ----------
    index : int
        Step number in the run (0 is the first step).
    time : float
        Simulated time at the start of the step [s].
    problem : StepProblem
        A copy of the step's problem (h, y, f_ext, pins).
    converged : bool or None
        Whether the recording solver met its tolerance on this step (None: not checked).
    """

    index: int
    time: float
    problem: StepProblem
    converged: bool | None = None


_ARRAYS = ("x", "v", "y", "f_ext", "fixed_vertices", "fixed_positions", "anchor_vertices",
           "anchor_positions", "anchor_stiffness", "contact_vertices", "contact_normals",
           "contact_offsets")


def step_digest(model: Model) -> str:
    """SHA-256 (hex, 16 digits) of what a step problem is solved with besides its own
    arrays: the masses and the springs (ends, stiffness, rest lengths, damping).

    Parameters
    ----------
    model : Model
        The cloth.

    Returns
    -------
    str
        16 hexadecimal digits; equal for two models whose step problems are the same.
    """
    digest = hashlib.sha256()
    s = model.springs
    for a in (model.vertex_mass, s.spring_vertices, s.spring_stiffness, s.spring_rest_length,
              s.spring_damping):
        digest.update(np.ascontiguousarray(a, dtype=np.float64).tobytes())
    return digest.hexdigest()[:16]


def save_problems(recorded, path, model: Model | None = None) -> Path:
    """Write recorded step problems to an ``.npz`` file (exactly; :func:`load_problems`).

    Parameters
    ----------
    recorded : sequence of RecordedStep
        The steps.
    path : str or Path
        The file (overwritten, written atomically).
    model : Model, optional
        The cloth they belong to: its :func:`step_digest` is saved, for
        :func:`load_problems` to check.

    Returns
    -------
    Path
        ``path``.
    """
    path = Path(path)
    data = {"index": np.array([r.index for r in recorded], dtype=np.int64),
            "time": np.array([r.time for r in recorded], dtype=np.float64),
            "h": np.array([r.problem.h for r in recorded], dtype=np.float64),
            "start": np.array([r.problem.start for r in recorded]),
            "converged": np.array([-1 if r.converged is None else int(r.converged)
                                   for r in recorded], dtype=np.int64)}
    if model is not None:
        data["model_digest"] = np.array(step_digest(model))
    for i, r in enumerate(recorded):
        for name in _ARRAYS:
            value = getattr(r.problem, name)
            if value is not None:
                data[f"{i}/{name}"] = np.asarray(value)
    with atomic_path(path) as tmp, tmp.open("wb") as fh:
        np.savez_compressed(fh, **data)
    return path


def load_problems(path, model: Model | None = None,
                  h: float | None = None) -> list[RecordedStep]:
    """Read the step problems :func:`save_problems` wrote.

    Parameters
    ----------
    path : str or Path
        The ``.npz`` file.
    model : Model, optional
        The cloth the problems will be solved with: refused when their vertex count
        differs, or when the file's :func:`step_digest` (files of earlier versions have
        none) is another model's.
    h : float, optional
        The time step they must have been recorded at [s].

    Returns
    -------
    list of RecordedStep
        The same problems, bit for bit.

    Raises
    ------
    InputError
        When the file is missing, is not a saved problem set, or does not belong to
        ``model`` and ``h``.
    """
    path = Path(path)
    check_steps_file(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
        out = []
        for i in range(len(data["index"])):
            fields = {name: data[f"{i}/{name}"] for name in _ARRAYS if f"{i}/{name}" in data}
            problem = StepProblem(h=float(data["h"][i]), start=str(data["start"][i]), **fields)
            c = int(data["converged"][i])
            out.append(RecordedStep(int(data["index"][i]), float(data["time"][i]), problem,
                                    None if c < 0 else bool(c)))
    except (KeyError, ValueError, OSError, EOFError, zipfile.BadZipFile) as exc:
        why = " ".join(str(exc).split())[:200] or ("the file is empty" if isinstance(
            exc, EOFError) else type(exc).__name__)
        raise InputError(f"accuracy.steps: {str(path)!r} is not a saved problem set "
                         f"({why})") from None
    where = f"accuracy.steps: {str(path)!r}"
    if model is not None:
        n = model.vertex_count
        sizes = sorted({len(r.problem.y) for r in out} - {n})
        if sizes:
            raise InputError(f"{where} holds step problems of {sizes[0]} vertices; this "
                             f"scene's cloth has {n} (record them anew: drop --steps)")
        saved, mine = (str(data["model_digest"]) if "model_digest" in data else None,
                       step_digest(model))
        if saved is not None and saved != mine:
            raise InputError(f"{where} was recorded on another cloth (masses or springs "
                             f"differ: model digest {saved}, this scene's {mine}); record "
                             f"them anew: drop --steps")
    if h is not None:
        other = sorted({r.problem.h for r in out if r.problem.h != h})
        if other:
            raise InputError(f"{where} was recorded at h = {other[0]:.6g} s; this scene "
                             f"steps at h = {h:.6g} s")
    return out


def check_steps_file(path) -> None:
    """Refuse, in one line, a ``--steps`` path that is no regular file (before anything runs).

    Parameters
    ----------
    path : str or Path

    Raises
    ------
    InputError
        ``accuracy.steps: …``: missing, a folder, a FIFO or device (a FIFO would block the
        reader, ``/dev/zero`` never ends), or empty.
    """

    path = Path(path)
    what = special_file(path) or ("a folder" if path.is_dir() else None)
    if what:
        raise InputError(f"accuracy.steps: {str(path)!r} is {what}, not a regular file")
    if not path.is_file():
        raise InputError(f"accuracy.steps: no such file {str(path)!r}")
    if path.stat().st_size == 0:
        raise InputError(f"accuracy.steps: {str(path)!r} is empty, not a saved problem set")


def record_problems(sim: Simulation, *, steps: int, count: int = 8) -> list[RecordedStep]:
    """Run ``sim`` for ``steps`` steps and record ``count`` step problems spread over it.

    Parameters
    ----------
    sim : Simulation
        The run (give it a converged solver, e.g. Newton to 1e-10, so the recorded states
        are implicit Euler's); advanced by ``steps`` steps.
    steps : int
        Steps of the run (frames × substeps of the scene).
    count : int
        Problems to keep, at evenly spread steps (first and last included).

    Returns
    -------
    list of RecordedStep
        With ``converged`` from the recording solver's own stop rule.
    """
    picks = set(np.unique(np.linspace(0, max(steps - 1, 0), max(1, count)).round().astype(int)))
    out = []
    with warnings.catch_warnings(), single_threaded():
        warnings.simplefilter("ignore")
        for i in range(steps):
            rec = None
            if i in picks:
                rec = RecordedStep(i, i * sim.h, copy.deepcopy(sim.problem()))
                out.append(rec)
            record = sim.step()
            if rec is not None:
                rec.converged = record.converged
            advance()
    return out


def at_rest_ratio(model: Model, problem: StepProblem) -> float:
    """‖∇g(y)‖ / its rounding floor (∞ when the floor is 0): "how far from rest".

    Parameters
    ----------
    model : Model
        The cloth.
    problem : StepProblem
        The step.

    Returns
    -------
    float
        The ratio (dimensionless).
    """
    x0 = problem.initial_guess()
    norm = float(np.linalg.norm(objective_gradient(model, problem, x0)))
    floor = gradient_noise_floor(model, problem, x0)
    return norm / floor if floor > 0 else (np.inf if norm > 0 else 0.0)


def one_iteration_error(model: Model, problem: StepProblem, x_star: np.ndarray) -> float:
    """Relative error ‖x_1 − x*‖ / ‖x* − x_n‖ after one local/global iteration.

    Parameters
    ----------
    model : Model
        The cloth.
    problem : StepProblem
        The step.
    x_star : ndarray, shape (n, 3)
        The converged step [m].

    Returns
    -------
    float
        The relative error (dimensionless).
    """
    gen = LocalGlobalSolver(model, check_conditioning=False).iterates(problem)
    next(gen)
    x1 = next(gen).x
    gen.close()
    scale = float(np.linalg.norm(x_star - problem.x)) or 1.0
    return float(np.linalg.norm(x1 - x_star)) / scale


def classify(model: Model, problem: StepProblem, x_star: np.ndarray) -> tuple[str, float, float]:
    """Classify a step as in the module docstring.

    Parameters
    ----------
    model : Model
        The cloth.
    problem : StepProblem
        The step.
    x_star : ndarray, shape (n, 3)
        The converged step [m].

    Returns
    -------
    kind : str
        "measured", "at-rest" or "trivial".
    ratio : float
        ‖∇g(y)‖ / rounding floor (:func:`at_rest_ratio`).
    error : float
        One-iteration relative error (0 when at rest: not computed).
    """
    ratio = at_rest_ratio(model, problem)
    if ratio <= AT_REST_FACTOR:
        return "at-rest", ratio, 0.0
    err1 = one_iteration_error(model, problem, x_star)
    return ("trivial" if err1 <= TRIVIAL_ERROR else "measured"), ratio, err1
