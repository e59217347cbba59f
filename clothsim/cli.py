"""The ``clothsim`` command (also ``python -m clothsim``).

::

    clothsim run [SCENE] [--out DIR] [--frames N] [--resume] [--no-preview]
    clothsim scenes
    clothsim validate SCENE
    clothsim accuracy [SCENE] [...]
    clothsim export SCENE [--out DIR]
    clothsim compare TRAJECTORY REFERENCE [--rtol R] [--atol A] [--frames N] [--field F]

SCENE is a scene file (``.toml``, or an assignment ``.json``) or a built-in scene name;
``run`` without one runs ``drop-on-square`` into ``out/<scene-name>``.

``export`` writes the paper's matrices and the model's arrays for regression-checking another
port; ``compare`` checks a trajectory against a reference with tolerances (exit 0 when it
passes, 1 when it does not).

Exit status: 0 success; 1 any other error (one line on stderr); 2 a bad scene or bad
arguments (one line: ``clothsim: error: <file>: <key.path>: <message>``, no traceback);
130 interrupted with Ctrl-C (frames done so far stay readable).
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

from .errors import InputError

PROG = "clothsim"
log = logging.getLogger(__name__)


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line and exit status 2 (no usage dump)."""

    def error(self, message):
        raise _UsageError(message)


class _UsageError(Exception):
    pass


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def _fail(message: str, code: int) -> int:
    print(f"{PROG}: error: {_one_line(message)}", file=sys.stderr)
    return code


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``clothsim`` command."""
    parser = _Parser(prog=PROG, description="Cloth simulation with mass-spring systems by the "
                     "local/global method of Liu et al. (2013).")
    parser.add_argument("-v", "--verbose", action="count", default=0,
                        help="log more (-v info, -vv debug)")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True

    run = sub.add_parser("run", help="run a scene and write frames, trajectory, previews")
    run.add_argument("scene", nargs="?", default=None, metavar="SCENE",
                     help="scene file or built-in name (default: drop-on-square)")
    run.add_argument("--out", metavar="DIR", default=None,
                     help="output directory (default: out/<scene-name>)")
    run.add_argument("--frames", type=int, metavar="N", default=None,
                     help="frames after the initial one (default: the scene's)")
    run.add_argument("--resume", action="store_true",
                     help="continue from the last complete frame in the output directory")
    run.add_argument("--no-preview", action="store_true",
                     help="skip preview.gif and final.png")

    sub.add_parser("scenes", help="list the built-in scenes")

    val = sub.add_parser("validate", help="check a scene file without running it")
    val.add_argument("scene", metavar="SCENE", help="scene file or built-in name")

    exp = sub.add_parser("export", help="write M, L, J, M + h²L and the model's arrays "
                         "(Matrix Market, text) for checking another port")
    exp.add_argument("scene", metavar="SCENE", help="scene file or built-in name")
    exp.add_argument("--out", metavar="DIR", default=None,
                     help="output directory (default: out/<scene-name>/matrices)")

    cmp_ = sub.add_parser("compare", help="compare a trajectory with a reference, with "
                          "tolerances |a - b| <= atol + rtol |b|")
    cmp_.add_argument("trajectory", help="trajectory.npz, a run directory, or a .pvd")
    cmp_.add_argument("reference", help="the reference, in any of the same forms")
    cmp_.add_argument("--rtol", type=float, default=1e-6, help="relative tolerance (1e-6)")
    cmp_.add_argument("--atol", type=float, default=1e-9, help="absolute tolerance [m] (1e-9)")
    cmp_.add_argument("--frames", type=int, default=None, metavar="N",
                      help="compare only the first N frames")
    cmp_.add_argument("--field", default="positions", choices=("positions", "velocities"))

    acc = sub.add_parser("accuracy", help="what accuracy costs in time: every solver on the "
                                          "same recorded steps of a scene")
    acc.add_argument("scene", nargs="?", default="hanging",
                     help="scene name or TOML path (default: hanging)")
    acc.add_argument("--out", default="accuracy-out", help="output directory")
    acc.add_argument("--methods", default=None,
                     help="comma-separated solvers (default: local-global,chebyshev,anderson,"
                          "lbfgs,newton)")
    acc.add_argument("--problems", type=int, default=8,
                     help="step problems recorded along the run (default 8)")
    acc.add_argument("--frames", type=int, default=None,
                     help="frames of the recorded run (default: the scene's)")
    acc.add_argument("--repeats", type=int, default=5, help="interleaved timing repeats (5)")
    acc.add_argument("--target", type=float, default=None,
                     help="report only this solver-error level (e.g. 1e-6)")
    acc.add_argument("--jobs", type=int, default=1, help="parallel workers (joblib)")
    acc.add_argument("--scheduler", default=None, metavar="ADDRESS",
                     help="Dask scheduler address (joblib's dask backend)")
    acc.add_argument("--no-time-steps", action="store_true",
                     help="skip the time-step error runs")
    acc.add_argument("--no-plots", action="store_true", help="write no figures")
    acc.add_argument("--quick", action="store_true",
                     help="few problems, budgets and repeats (a first look, not for a referee)")
    acc.add_argument("--paper", action="store_true",
                     help="the paper's Fig. 1 setup: local/global against Newton (crossover)")
    acc.add_argument("--paper-size", type=int, default=41, help="vertices per side (--paper)")
    return parser


def _configure_logging(verbose: int):
    """Send clothsim's log records to stderr (warnings only, unless -v); returns an undo."""
    level = logging.WARNING if verbose <= 0 else logging.INFO if verbose == 1 else logging.DEBUG
    root = logging.getLogger("clothsim")
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter(f"{PROG}: %(levelname)s: %(message)s"))
    old_level = root.level
    root.addHandler(handler)
    root.setLevel(level)

    def undo():
        root.removeHandler(handler)
        root.setLevel(old_level)

    return undo


def _cmd_scenes(args) -> int:
    from .scene import DEFAULT_SCENE, list_builtin_scenes

    scenes = list_builtin_scenes()
    width = max(map(len, scenes), default=0)
    for name, desc in scenes.items():
        mark = " (default)" if name == DEFAULT_SCENE and "default" not in desc else ""
        print(f"{name:<{width}}  {desc}{mark}")
    return 0


def _build(scene_arg: str):
    """Load, validate and build a scene: (scene, model, simulation)."""
    from .scene import load_scene

    scene = load_scene(scene_arg)
    model = scene.build_model()
    return scene, model, scene.build_simulation(model)


def _cmd_validate(args) -> int:
    scene, model, sim = _build(args.scene)
    print(f"ok: {scene.source}: scene '{scene.name}', {model.vertex_count} vertices, "
          f"{model.spring_count} springs, {scene.frames} frames at h = {scene.h:.6g} s, "
          f"effects: {', '.join(sim.effects_built) or 'none'}")
    return 0


def _cmd_run(args) -> int:
    from .runner import run_scene
    from .scene import DEFAULT_SCENE, load_scene

    if args.frames is not None and args.frames < 0:
        return _fail(f"--frames: must be >= 0, got {args.frames}", 2)
    scene = load_scene(args.scene or DEFAULT_SCENE)
    out = Path(args.out) if args.out else Path("out") / scene.name
    frames = scene.frames if args.frames is None else args.frames
    try:
        from tqdm import tqdm
    except ImportError:  # pragma: no cover - tqdm is a declared dependency
        tqdm = None
    bar = None if tqdm is None else tqdm(total=frames, unit="frame", desc=scene.name,
                                         disable=None, leave=False)

    def progress(k, total):
        if bar is not None:
            bar.n = k
            bar.refresh()

    try:
        result = run_scene(scene, out, frames=frames, progress=progress, resume=args.resume,
                           preview=not args.no_preview)
    except KeyboardInterrupt:
        return _fail(f"interrupted; complete frames and run.json are in {out}", 130)
    finally:
        if bar is not None:
            bar.close()
    print(f"{scene.name}: {result.last_frame} frames written to {out}")
    return 0


def _cmd_export(args) -> int:
    from .export import export_matrices

    scene, model, sim = _build(args.scene)
    out = Path(args.out) if args.out else Path("out") / scene.name / "matrices"
    pinned = sim.pinned_vertices(sim.h)
    manifest = export_matrices(model, scene.h, out, pinned=pinned)
    print(f"{scene.name}: {len(manifest['files'])} files for n = {model.vertex_count}, "
          f"s = {model.spring_count}, h = {scene.h:.6g} s written to {out}")
    return 0


def _cmd_compare(args) -> int:
    from .compare import compare_trajectories

    for name in ("rtol", "atol"):
        value = getattr(args, name)
        if not value >= 0:
            return _fail(f"--{name}: must be a non-negative number, got {value}", 2)
    result = compare_trajectories(args.trajectory, args.reference, rtol=args.rtol,
                                  atol=args.atol, field=args.field, frames=args.frames)
    print(result.summary())
    return 0 if result.passed else 1


def _cmd_accuracy(args) -> int:
    from . import accuracy

    if args.paper:
        print(accuracy.paper_report(n=args.paper_size, repeats=args.repeats))
        return 0
    from .scene import load_scene

    scene = load_scene(args.scene)
    kw = {}
    if args.methods:
        kw["methods"] = tuple(m.strip() for m in args.methods.split(",") if m.strip())
    if args.quick:
        kw.update(budgets=(1, 5, 10, 20, 100), tolerances=(1e-3, 1e-6),
                  problems=min(args.problems, 4))
    print(accuracy.run_accuracy(
        scene, args.out, problems=kw.pop("problems", args.problems), frames=args.frames,
        repeats=args.repeats, jobs=args.jobs, scheduler=args.scheduler, target=args.target,
        time_steps=not args.no_time_steps, plots=not args.no_plots, **kw))
    return 0


COMMANDS = {"run": _cmd_run, "scenes": _cmd_scenes, "validate": _cmd_validate,
            "accuracy": _cmd_accuracy, "export": _cmd_export, "compare": _cmd_compare}


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status (the entry point exits with it)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except _UsageError as exc:
        return _fail(str(exc), 2)
    except SystemExit as exc:  # --help
        return int(exc.code or 0)
    undo_logging = _configure_logging(args.verbose)
    try:
        return COMMANDS[args.command](args)
    except InputError as exc:  # SceneError included: bad input, exit status 2
        return _fail(str(exc), 2)
    except KeyboardInterrupt:
        return _fail("interrupted", 130)
    except Exception as exc:  # one line, no traceback; -vv logs it in full
        log.debug("unhandled error", exc_info=True)
        return _fail(f"{type(exc).__name__}: {exc}", 1)
    finally:
        undo_logging()


__all__ = ["main", "build_parser"]
