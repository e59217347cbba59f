"""The ``clothsim`` command (also ``python -m clothsim``).

::

    clothsim [--version] [-v | -vv] COMMAND [-v | -vv] ...
    clothsim run [SCENE] [--out DIR] [--frames N] [--resume] [--no-preview] [--force]
    clothsim scenes [--show NAME]
    clothsim validate SCENE
    clothsim accuracy [SCENE] [...]
    clothsim export SCENE [--out DIR] [--frames N] [--iterate-steps K] [--force]
    clothsim compare TRAJECTORY REFERENCE [--key K] [--precision P] [--rtol R] [--atol A] ...
    clothsim check SCENE PORT [--precision float32|float64] [--tolerance T]
    clothsim diff-model A B
    clothsim conformance [--out DIR]
    clothsim data list | fetch [NAME ...] | path NAME[/FILE]

SCENE is a scene file (``.toml``, or an assignment ``.json``) or a built-in scene name;
``run`` without one runs ``drop-on-square`` into ``out/<scene-name>``. A file or folder
argument may be written ``data:<data set>/<path>`` (``data:liu13-port/default-scene``, the
port reference shipped with clothsim; ``clothsim data list`` shows the data sets).

``export``, ``compare``, ``check``, ``diff-model`` and ``conformance`` check another port
(docs/ports.md); ``compare``, ``check`` and ``diff-model`` exit 0 when they pass, 1 when not.

Exit status: 0 success; 1 any other error (one line on stderr); 2 a bad scene or bad
arguments (one line: ``clothsim: error: <file>: <key.path>: <message>``, no traceback);
``run`` interrupted: 130 by Ctrl-C (SIGINT), 143 by SIGTERM, 129 by SIGHUP (frames done so
far stay readable; run.json says ``interrupted``); ``run`` stopped by a blow-up: 1
(``frame k: the state became non-finite (…)``, the last finite frame kept).

Warnings (ill-conditioning, missed tolerances, …) go through :mod:`logging`: each kind is
logged once when it first occurs (with ``-v``) and summarised at the end of the command as
one line with its count. Progress bars are shown only when stderr is a terminal; off a
terminal ``run`` prints a progress line every few seconds instead
(:class:`clothsim.cli.logs.ProgressLines`). Before it writes, ``run`` estimates the disk the
run will use: above 1 GB it says so with a warning, and a run the disk cannot hold is
refused (exit 2) naming ``--frames`` and how many frames fit.
"""


from __future__ import annotations

import argparse
import errno
import os
import signal
import sys
from pathlib import Path

from .. import __version__
from ..errors import InputError
from ..interrupts import SIGNALS, handle_signals
from ..scene.schema import MAX_FRAMES, MAX_VERTICES
from .common import (
    PROG,
    _fail,
    _Parser,
    _UsageError,
    add_set_option,
    count,
    interrupted,
    log,
    os_error_line,
    other_output,
    stopped,
)
from .data import _add_data_command, _cmd_data, expand_data_args
from .logs import (
    ProgressLines,
    _configure_logging,
    _isatty,
    _no_progress_bars_off_terminal,
    _progress_lines_off_terminal,
    _warnings_to_log,
)
from .ports import (
    _add_port_commands,
    _cmd_check,
    _cmd_compare,
    _cmd_conformance,
    _cmd_diff_model,
    _cmd_export,
)

#: exit statuses of a command stopped by SIGHUP, SIGINT or SIGTERM (128 + the signal)
INTERRUPTED = {128 + s for s in SIGNALS}


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
    run.add_argument("--frames", type=count(0, MAX_FRAMES), metavar="N", default=None,
                     help="frames after the initial one (default: the scene's)")
    run.add_argument("--resume", action="store_true",
                     help="continue from the last complete frame in the output directory")
    run.add_argument("--no-preview", action="store_true",
                     help="skip preview.gif and final.png")
    add_set_option(run)
    run.add_argument("--force", action="store_true",
                     help="write into DIR even when it holds files that are not a clothsim "
                     "run's (files named like a run's are replaced)")

    scn = sub.add_parser("scenes", help="list the built-in scenes (or print one: --show NAME)")
    scn.add_argument("--show", metavar="NAME", default=None,
                     help="print the TOML of the built-in scene NAME (a template to start from)")

    val = sub.add_parser("validate", help="check a scene file without running it")
    val.add_argument("scene", metavar="SCENE", help="scene file or built-in name")
    add_set_option(val)

    _add_port_commands(sub)
    _add_data_command(sub)

    acc = sub.add_parser("accuracy", help="what accuracy costs in time: every solver on the "
                                          "same recorded steps of a scene")
    acc.add_argument("scene", nargs="?", default="hanging",
                     help="scene name or TOML path (default: hanging)")
    acc.add_argument("--out", default=None,
                     help="output directory (default: accuracy-out)")
    acc.add_argument("--force", action="store_true",
                     help="write into DIR even when it holds files that are not a clothsim "
                     "accuracy study, or replace the default folder's study of another scene")
    acc.add_argument("--methods", default=None,
                     help="comma-separated solvers (default: local-global,chebyshev,anderson,"
                          "lbfgs,newton)")
    acc.add_argument("--problems", type=count(1, 10_000), default=8,
                     help="step problems recorded along the run (default 8)")
    acc.add_argument("--frames", type=count(0, MAX_FRAMES), default=None,
                     help="frames of the recorded run (default: the scene's)")
    acc.add_argument("--repeats", type=count(1, 10_000), default=5,
                     help="interleaved timing repeats (5) of every setting an answer "
                          "could choose (the others: 2; up to 10 where an answer must tell "
                          "settings apart)")
    acc.add_argument("--target", type=float, default=None,
                     help="report only this solver-error level (e.g. 1e-6); when no "
                          "local/global setting reaches it, its iterations are extrapolated")
    acc.add_argument("--jobs", type=count(1, 1024), default=1,
                     help="parallel workers for the errors and the trajectory runs "
                          "(joblib; same results for any number)")
    acc.add_argument("--scheduler", default=None, metavar="ADDRESS",
                     help="Dask scheduler address (joblib's dask backend)")
    acc.add_argument("--no-time-steps", action="store_true",
                     help="skip the time-step error runs")
    acc.add_argument("--no-plots", action="store_true", help="write no figures")
    acc.add_argument("--quick", action="store_true",
                     help="a first look in seconds, not for a referee: at most 4 problems, "
                          "budgets 1/5/10/20/100, tolerances 1e-3/1e-6 (at most 1000 "
                          "iterations), 1 timing repeat (up to 10 where an answer must "
                          "tell settings apart), one BLAS thread, no trajectory errors, a "
                          "6-frame "
                          "time-step check at h and h/2; stops early when no step can be "
                          "measured")
    acc.add_argument("--steps", default=None, metavar="FILE",
                     help="re-measure exactly the step problems of an earlier study "
                          "(its problems.npz) instead of recording new ones")
    acc.add_argument("--paper", action="store_true",
                     help="the paper's Fig. 1 setup: local/global against Newton (crossover); "
                          "with --out DIR, its table and figure are written there")
    acc.add_argument("--paper-size", type=count(2, int(MAX_VERTICES ** 0.5)), default=41,
                     help="vertices per side (--paper)")
    add_set_option(acc)
    return parser


def _cmd_scenes(args) -> int:
    from ..scene import DEFAULT_SCENE, builtin_scene_text, list_builtin_scenes

    if args.show is not None:
        sys.stdout.write(builtin_scene_text(args.show))
        return 0
    scenes = list_builtin_scenes()
    width = max(map(len, scenes), default=0)
    for name, desc in scenes.items():
        mark = " (default)" if name == DEFAULT_SCENE and "default" not in desc else ""
        print(f"{name:<{width}}  {desc}{mark}")
    return 0


def _build(scene_arg: str, overrides=()):
    """Load, validate and build a scene: (scene, model, simulation)."""
    from ..scene import load_scene

    scene = load_scene(scene_arg, overrides)
    model = scene.build_model()
    return scene, model, scene.build_simulation(model)


def _cmd_validate(args) -> int:
    scene, model, sim = _build(args.scene, args.set)
    print(f"ok: {scene.source}: scene '{scene.name}', {model.vertex_count} vertices, "
          f"{model.spring_count} springs, {scene.frames} frames at h = {scene.h:.6g} s, "
          f"effects: {', '.join(sim.effects_built) or 'none'}")
    return 0


def _cmd_run(args) -> int:
    from ..runner import NonFiniteStateError, run_scene
    from ..scene import DEFAULT_SCENE, load_scene

    if args.frames is not None and args.frames < 0:
        return _fail(f"--frames: must be >= 0, got {args.frames}", 2)
    scene = load_scene(args.scene or DEFAULT_SCENE, args.set)
    if args.out == "":
        return _fail("--out: empty; name a folder", 2)
    if args.out is not None:
        out = Path(args.out)
    else:  # out/<scene name>, and never anywhere else
        base = Path("out")
        out = base / scene.name
        if (out.resolve().parent != base.resolve() or scene.name in ("", ".", "..")
                or Path(scene.name).name != scene.name):
            return _fail(f"scene.name: {scene.name!r} cannot name a folder in out/; "
                         "use --out DIR", 2)
    if args.out is None and not (args.resume or args.force):
        other = other_output(out, scene)
        if other:
            return _fail(other, 2)
    frames = scene.frames if args.frames is None else args.frames
    try:
        from tqdm import tqdm
    except ImportError:  # pragma: no cover - tqdm is a declared dependency
        tqdm = None
    bar = None if tqdm is None else tqdm(total=frames, unit="frame", desc=scene.name,
                                         disable=None, leave=False)
    lines = None if _isatty(sys.stderr) else ProgressLines(scene.name)  # make, nohup, a pipe

    def progress(k, total):
        if bar is not None:
            bar.n = k
            bar.refresh()
        if lines is not None:
            lines(k, total)

    try:
        result = run_scene(scene, out, frames=frames, progress=progress,
                           resume=args.resume, preview=not args.no_preview, force=args.force)
    except KeyboardInterrupt as exc:  # Ctrl-C, SIGTERM, SIGHUP: exit 128 + signal number
        if bar is not None:
            bar.close()  # before the message: the bar's line is cleared when it closes
        return interrupted(exc, f"complete frames and run.json are in {out}")
    except NonFiniteStateError as exc:
        return _fail(f"{exc}; run.json (status failed) is in {out}", 1)
    except OSError as exc:  # full disk, read-only folder, file too large, ...
        log.debug("I/O error", exc_info=True)
        written = ("frames written so far stay (run.json says failed when it could be "
                   "written; --resume continues)" if (out / "run.json").is_file()
                   else "the folder was removed or moved while the run wrote into it (moved: "
                   "--resume continues it where it went)"
                   if exc.errno == errno.ENOENT and not out.is_dir()
                   else "nothing was written")       # e.g. the lock file could not be made
        return _fail(f"{os_error_line(exc, out)}; {written}", 1)
    finally:
        if bar is not None:
            bar.close()
    print(f"{scene.name}: {result.last_frame} frames written to {out}")
    return 0


def _cmd_accuracy(args) -> int:
    from .. import accuracy

    if args.paper:
        print(accuracy.paper_report(n=args.paper_size, repeats=args.repeats, out=args.out,
                                    force=args.force))
        return 0
    from ..scene import load_scene

    scene = load_scene(args.scene, args.set)
    out = args.out if args.out is not None else "accuracy-out"
    if args.out is None and not args.force:
        from ..io.folders import folder_record

        previous = (folder_record(out, "accuracy") or {}).get("scene")
        if previous is not None and previous != scene.name:
            return _fail(f"{out} holds the accuracy study of {previous!r}, not of "
                         f"{scene.name!r}: choose --out DIR to keep both, or --force to "
                         f"replace it", 2)
    kw = {}
    if args.methods:
        kw["methods"] = tuple(m.strip() for m in args.methods.split(",") if m.strip())
    try:
        report = accuracy.run_accuracy(
            scene, out, problems=args.problems, frames=args.frames, quick=args.quick,
            repeats=args.repeats, jobs=args.jobs, scheduler=args.scheduler,
            target=args.target, time_steps=not args.no_time_steps, plots=not args.no_plots,
            steps_file=args.steps, force=args.force, **kw)
    except (KeyboardInterrupt, OSError) as exc:
        return stopped(exc, out)
    print(report)
    return 0


COMMANDS = {"run": _cmd_run, "scenes": _cmd_scenes, "validate": _cmd_validate,
            "accuracy": _cmd_accuracy, "export": _cmd_export, "compare": _cmd_compare,
            "check": _cmd_check, "diff-model": _cmd_diff_model,
            "conformance": _cmd_conformance, "data": _cmd_data}


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
    # SIGINT, SIGTERM and SIGHUP interrupt every command alike, and a second one while it
    # cleans up and says so is ignored (it would end the process with no message)
    try:
        with handle_signals():
            code = _dispatch(args)
    finally:
        undo_logging()
    if argv is None and code in INTERRUPTED:  # the process ends now, interrupted: a further
        for signum in SIGNALS:                # signal must not turn the exit into -2 or -15
            signal.signal(signum, signal.SIG_IGN)
    return code


def _dispatch(args) -> int:
    """Run the command; every error becomes one line and an exit status."""
    try:
        with (_warnings_to_log(), _no_progress_bars_off_terminal(),
              _progress_lines_off_terminal()):
            expand_data_args(args)
            return COMMANDS[args.command](args)
    except InputError as exc:  # SceneError included: bad input, exit status 2
        return _fail(str(exc), 2)
    except KeyboardInterrupt as exc:
        return interrupted(exc)
    except BrokenPipeError:  # the reader went away (`clothsim scenes | head`): stop quietly
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - no flush error at exit
        return 141
    except OSError as exc:  # a path and its cause, not "OSError: [Errno 28] ..."
        log.debug("I/O error", exc_info=True)
        return _fail(os_error_line(exc), 1)
    except MemoryError:
        return _fail("out of memory", 1)
    except Exception as exc:  # one line, no traceback; -vv logs it in full
        log.debug("unhandled error", exc_info=True)
        return _fail(f"{type(exc).__name__}: {exc}", 1)


__all__ = ["main", "build_parser"]
