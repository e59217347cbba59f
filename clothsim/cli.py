"""The ``clothsim`` command (also ``python -m clothsim``).

::

    clothsim [--version] [-v | -vv] COMMAND [-v | -vv] ...
    clothsim run [SCENE] [--out DIR] [--frames N] [--resume] [--no-preview]
    clothsim scenes [--show NAME]
    clothsim validate SCENE
    clothsim accuracy [SCENE] [...]
    clothsim export SCENE [--out DIR] [--frames N] [--iterate-steps K]
    clothsim compare TRAJECTORY REFERENCE [--key K] [--precision P] [--rtol R] [--atol A] ...
    clothsim check SCENE PORT [--precision float32|float64] [--tolerance T]
    clothsim diff-model A B
    clothsim conformance [--out DIR]

SCENE is a scene file (``.toml``, or an assignment ``.json``) or a built-in scene name;
``run`` without one runs ``drop-on-square`` into ``out/<scene-name>``.

``export``, ``compare``, ``check``, ``diff-model`` and ``conformance`` check another port
(docs/ports.md); ``compare``, ``check`` and ``diff-model`` exit 0 when they pass, 1 when not.

Exit status: 0 success; 1 any other error (one line on stderr); 2 a bad scene or bad
arguments (one line: ``clothsim: error: <file>: <key.path>: <message>``, no traceback);
``run`` interrupted: 130 by Ctrl-C (SIGINT), 143 by SIGTERM, 129 by SIGHUP (frames done so
far stay readable; run.json says ``interrupted``); ``run`` stopped by a blow-up: 1
(``frame k: the state became non-finite (…)``, the last finite frame kept).

Warnings (ill-conditioning, missed tolerances, …) go through :mod:`logging`: each kind is
logged once when it first occurs (with ``-v``) and summarised at the end of the command as
one line with its count. Progress bars are shown only when stderr is a terminal.
"""

from __future__ import annotations

import argparse
import logging
import os
import re
import signal
import sys
import warnings
from contextlib import contextmanager
from pathlib import Path

from . import __version__
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
    """The argument parser of the ``clothsim`` command.

    Returns
    -------
    argparse.ArgumentParser
        Every subcommand wired; ``-v`` is accepted before and after the subcommand.
    """
    parser = _Parser(prog=PROG, description="Cloth simulation with mass-spring systems by the "
                     "local/global method of Liu et al. (2013).")
    parser.add_argument("-v", "--verbose", action="count", default=0,
                        help="log more (-v info, -vv debug)")
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    # -v is accepted after the command too (counts add up: clothsim -v run -v = -vv)
    verbose = _Parser(add_help=False)
    verbose.add_argument("-v", "--verbose", action="count", default=0, dest="verbose_after",
                         help="log more (-v info, -vv debug)")
    add_parser = sub.add_parser

    def add_with_verbose(*a, **kw):
        return add_parser(*a, parents=[verbose], **kw)

    sub.add_parser = add_with_verbose

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

    scn = sub.add_parser("scenes", help="list the built-in scenes (or print one: --show NAME)")
    scn.add_argument("--show", metavar="NAME", default=None,
                     help="print the TOML of the built-in scene NAME (a template to start from)")

    val = sub.add_parser("validate", help="check a scene file without running it")
    val.add_argument("scene", metavar="SCENE", help="scene file or built-in name")

    _add_port_commands(sub)

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


_NUMBER = re.compile(r"[-+]?\d[\d.]*(?:e[-+]?\d+)?")


@contextmanager
def _warnings_to_log():
    """Route Python warnings to the ``clothsim`` logger and count them by kind.

    A kind is the warning category plus its message with numbers blanked out. The first
    warning of each kind is logged at INFO (visible with -v); at exit one WARNING line per
    kind gives its count and the first message.
    """
    counts: dict[tuple[str, str], list] = {}

    def show(message, category, filename, lineno, file=None, line=None):
        text = _one_line(message)
        key = (category.__name__, _NUMBER.sub("#", text))
        if key not in counts:
            counts[key] = [0, text]
            log.info("%s: %s", category.__name__, text)
        counts[key][0] += 1

    with warnings.catch_warnings():
        warnings.simplefilter("always")
        warnings.showwarning = show
        try:
            yield counts
        finally:
            for (kind, _), (count, first) in counts.items():
                times = "once" if count == 1 else f"{count} times"
                log.warning("%s (%s): %s", kind, times, first)


@contextmanager
def _no_progress_bars_off_terminal():
    """Disable tqdm progress bars (TQDM_DISABLE) when stderr is not a terminal."""
    set_here = not _isatty(sys.stderr) and "TQDM_DISABLE" not in os.environ
    if set_here:
        os.environ["TQDM_DISABLE"] = "1"
    try:
        yield
    finally:
        if set_here:
            os.environ.pop("TQDM_DISABLE", None)


def _isatty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


def _cmd_scenes(args) -> int:
    from .scene import DEFAULT_SCENE, builtin_scene_text, list_builtin_scenes

    if args.show is not None:
        sys.stdout.write(builtin_scene_text(args.show))
        return 0
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
    from .runner import NonFiniteStateError, handle_signals, run_scene
    from .scene import DEFAULT_SCENE, load_scene

    if args.frames is not None and args.frames < 0:
        return _fail(f"--frames: must be >= 0, got {args.frames}", 2)
    scene = load_scene(args.scene or DEFAULT_SCENE)
    if args.out:
        out = Path(args.out)
    else:  # out/<scene name>, and never anywhere else
        base = Path("out")
        out = base / scene.name
        if (out.resolve().parent != base.resolve() or scene.name in ("", ".", "..")
                or Path(scene.name).name != scene.name):
            return _fail(f"scene.name: {scene.name!r} cannot name a folder in out/; "
                         "use --out DIR", 2)
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
        with handle_signals():
            result = run_scene(scene, out, frames=frames, progress=progress,
                               resume=args.resume, preview=not args.no_preview)
    except KeyboardInterrupt as exc:  # Ctrl-C, SIGTERM, SIGHUP: exit 128 + signal number
        signum = getattr(exc, "signum", signal.SIGINT)
        name = signal.Signals(signum).name
        return _fail(f"interrupted ({name}); complete frames and run.json are in {out}",
                     128 + signum)
    except NonFiniteStateError as exc:
        return _fail(f"{exc}; run.json (status failed) is in {out}", 1)
    finally:
        if bar is not None:
            bar.close()
    print(f"{scene.name}: {result.last_frame} frames written to {out}")
    return 0


def _add_port_commands(sub) -> None:
    """export, compare, check, diff-model, conformance: checking another port (docs/ports.md)."""
    exp = sub.add_parser("export", help="write everything a port needs: M, L, J, M + h²L "
                         "(penalty pins in), model files, settings, reference trajectory, "
                         "local/global iterates")
    exp.add_argument("scene", metavar="SCENE", help="scene file or built-in name")
    exp.add_argument("--out", metavar="DIR", default=None,
                     help="output directory (default: out/<scene-name>/export)")
    exp.add_argument("--frames", type=int, metavar="N", default=None,
                     help="steps of the reference trajectory (default: the scene's)")
    exp.add_argument("--iterate-steps", type=int, metavar="K", default=3,
                     help="steps whose local/global iterates are written (3)")

    cmp_ = sub.add_parser("compare", help="compare a trajectory with a reference: per-vertex "
                          "distance per frame, relative to the cloth size")
    cmp_.add_argument("trajectory", help="npz, npy, text/CSV, raw, .pvd, a folder, or a .mtx "
                      "matrix (then REFERENCE is one too)")
    cmp_.add_argument("reference", help="the reference, in any of the same forms")
    cmp_.add_argument("--key", default=None, help="array name in .npz files (positions)")
    cmp_.add_argument("--field", default=None, choices=("positions", "velocities"),
                      help="positions or velocities (same as --key)")
    cmp_.add_argument("--format", dest="fmt", default=None,
                      choices=("npz", "npy", "text", "frames", "raw", "pvd"),
                      help="format of TRAJECTORY when its name does not say")
    cmp_.add_argument("--dtype", default=None, choices=("float32", "float64"),
                      help="raw files: element type")
    cmp_.add_argument("--vertices", type=int, default=None, metavar="N",
                      help="raw files: vertex count n")
    cmp_.add_argument("--precision", default="float64", choices=("float64", "float32"),
                      help="float32: tolerance from κ(M + h²L) ε32 |x| (needs --scene, "
                      "--kappa or an export folder as REFERENCE)")
    cmp_.add_argument("--scene", default=None, help="scene to estimate κ from")
    cmp_.add_argument("--kappa", type=float, default=None, help="κ(M + h²L) if known")
    cmp_.add_argument("--rtol", type=float, default=None,
                      help="tolerance relative to the cloth size (1e-9)")
    cmp_.add_argument("--atol", type=float, default=None, help="absolute tolerance [m]")
    cmp_.add_argument("--frames", type=int, default=None, metavar="N",
                      help="compare only the first N frames")
    cmp_.add_argument("--match-vertices", action="store_true",
                      help="pair vertices by their initial positions (other vertex order)")
    cmp_.add_argument("--no-table", action="store_true",
                      help="print only the verdict line, not the per-frame table")
    cmp_.add_argument("--plot", metavar="PNG", default=None,
                      help="write the deviation-over-time plot")
    cmp_.add_argument("--drop-attachments", action="store_true",
                      help="two .mtx files: leave out TRAJECTORY's leading single-vertex "
                      "columns (a J storing attachments as extra constraint columns)")

    chk = sub.add_parser("check", help="check a port step by step: clothsim's step from the "
                         "port's (x_k, v_k) against the port's x_{k+1}")
    chk.add_argument("scene", metavar="SCENE", help="scene file or built-in name")
    chk.add_argument("port", metavar="PORT", help="folder with positions.txt and "
                     "velocities.txt, or a trajectory file in any format compare reads")
    chk.add_argument("--precision", default="float64", choices=("float64", "float32"))
    chk.add_argument("--tolerance", type=float, default=None,
                     help="allowed per-vertex distance [m] (default from --precision)")
    chk.add_argument("--steps", type=int, default=None, help="check only the first N steps")
    chk.add_argument("--optimality", type=float, default=1e-6,
                     help="largest relative gradient |grad g(x)| / |grad g(x0)| of a port's "
                     "answer counted as a minimizer (1e-6)")
    chk.add_argument("--verbose-steps", action="store_true", help="print every step")

    dif = sub.add_parser("diff-model", help="compare two models: springs, stiffness, rest "
                         "lengths, masses, pins")
    dif.add_argument("a", metavar="A", help="scene or folder of model files")
    dif.add_argument("b", metavar="B", help="scene or folder of model files")

    con = sub.add_parser("conformance", help="write the conformance set: tiny scenes, one "
                         "effect each, with reference data and iterates")
    con.add_argument("--out", metavar="DIR", default="conformance",
                     help="output directory (conformance)")


def _positive(args, names) -> str | None:
    for name in names:
        value = getattr(args, name)
        if value is not None and not value >= 0:
            return f"--{name.replace('_', '-')}: must be a non-negative number, got {value}"
    return None


def _cmd_export(args) -> int:
    from .ports.export import export_port
    from .scene import load_scene

    bad = _positive(args, ("frames", "iterate_steps"))
    if bad:
        return _fail(bad, 2)
    scene = load_scene(args.scene)
    out = Path(args.out) if args.out else Path("out") / scene.name / "export"
    frames = scene.frames if args.frames is None else args.frames
    manifest = export_port(scene, out, frames=frames, iterate_steps=args.iterate_steps)
    print(f"{scene.name}: {len(manifest['files'])} files for n = {manifest['vertex_count']}, "
          f"s = {manifest['spring_count']}, h = {manifest['h']:.6g} s, {frames} frames, "
          f"κ(M + h²L) = {manifest['condition_number']:.4g} written to {out}")
    return 0


def _cmd_compare(args) -> int:
    from .ports.compare import compare_trajectories, plot_deviation

    bad = _positive(args, ("rtol", "atol", "kappa"))
    if bad:
        return _fail(bad, 2)
    if Path(args.trajectory).suffix == ".mtx":
        from .ports.compare import compare_matrices

        mres = compare_matrices(args.trajectory, args.reference,
                                rtol=1e-12 if args.rtol is None else args.rtol,
                                atol=args.atol or 0.0,
                                drop_columns="attachments" if args.drop_attachments else None)
        print(mres.summary())
        return 0 if mres.passed else 1
    kappa = args.kappa
    if kappa is None and args.scene is not None:
        from .ports.check import _simulation
        from .ports.compare import condition_number
        from .scene import load_scene

        sim = _simulation(load_scene(args.scene))
        p = sim.problem(sim.state)
        kappa = condition_number(sim.model, sim.h, anchor_vertices=p.anchor_vertices,
                                 anchor_stiffness=p.anchor_stiffness)
    result = compare_trajectories(
        args.trajectory, args.reference, key=args.key or args.field or "positions",
        frames=args.frames, match=args.match_vertices, kappa=kappa, fmt=args.fmt,
        dtype=args.dtype, vertex_count=args.vertices, rtol=args.rtol, atol=args.atol,
        precision=args.precision)
    for note in result.notes:
        print(f"note: {note}")
    print(result.summary())
    if not args.no_table:
        print(result.table())
    if args.plot:
        plot_deviation(result, args.plot)
    return 0 if result.passed else 1


def _cmd_check(args) -> int:
    from .ports.check import check_steps
    from .ports.formats import read_trajectory, read_velocities
    from .scene import load_scene

    bad = _positive(args, ("tolerance", "steps", "optimality"))
    if bad:
        return _fail(bad, 2)
    scene = load_scene(args.scene)
    x = read_trajectory(args.port)
    v = read_velocities(args.port)
    report = check_steps(scene, x, v, precision=args.precision, tolerance=args.tolerance,
                         steps=args.steps, optimality=args.optimality)
    if args.verbose_steps:
        for step in report.steps:
            print(step.line())
    for note in report.notes:
        print(f"note: {note}")
    print(report.summary())
    return 0 if report.passed else 1


def _cmd_diff_model(args) -> int:
    from .ports.diff import diff_models

    result = diff_models(args.a, args.b)
    print(result.report())
    return 0 if result.identical else 1


def _cmd_conformance(args) -> int:
    from .ports.conformance import write_conformance

    names = write_conformance(args.out)
    print(f"{len(names)} conformance cases written to {args.out} (read {args.out}/README.md)")
    return 0


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
            "accuracy": _cmd_accuracy, "export": _cmd_export, "compare": _cmd_compare,
            "check": _cmd_check, "diff-model": _cmd_diff_model,
            "conformance": _cmd_conformance}


def main(argv: list[str] | None = None) -> int:
    """Run the command line.

    Parameters
    ----------
    argv : list of str, optional
        Arguments without the program name (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        The exit status (the entry point exits with it): 0 success, 1 error, 2 bad input,
        130 interrupted.
    """
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except _UsageError as exc:
        return _fail(str(exc), 2)
    except SystemExit as exc:  # --help
        return int(exc.code or 0)
    undo_logging = _configure_logging(args.verbose + getattr(args, "verbose_after", 0))
    try:
        with _warnings_to_log(), _no_progress_bars_off_terminal():
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
