"""The commands that check another port: export, compare, check, diff-model, conformance
(docs/ports.md)."""

from __future__ import annotations

import math
from pathlib import Path

from ..scene.schema import MAX_FRAMES, MAX_VERTICES
from .common import _fail, add_set_option, count, other_output, stopped


def _add_port_commands(sub) -> None:
    """export, compare, check, diff-model, conformance: checking another port (docs/ports.md)."""
    exp = sub.add_parser("export", help="write everything a port needs: M, L, J, M + h²L "
                         "(penalty pins in), model files, settings, reference trajectory, "
                         "local/global iterates")
    exp.add_argument("scene", metavar="SCENE", help="scene file or built-in name")
    exp.add_argument("--out", metavar="DIR", default=None,
                     help="output directory (default: out/<scene-name>/export)")
    exp.add_argument("--frames", type=count(0, MAX_FRAMES), metavar="N", default=None,
                     help="steps of the reference trajectory (default: the scene's)")
    add_set_option(exp)
    exp.add_argument("--iterate-steps", type=count(0, MAX_FRAMES), metavar="K", default=3,
                     help="steps whose local/global iterates are written (3)")
    exp.add_argument("--force", action="store_true",
                     help="write into DIR even when it is not an export folder of clothsim")

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
    cmp_.add_argument("--vertices", type=count(1, MAX_VERTICES), default=None, metavar="N",
                      help="raw files: vertex count n")
    cmp_.add_argument("--precision", default="float64", choices=("float64", "float32"),
                      help="float32: tolerance from κ(M + h²L) ε32 |x| (needs --scene, "
                      "--kappa or an export folder as REFERENCE)")
    cmp_.add_argument("--scene", default=None, help="scene to estimate κ from")
    cmp_.add_argument("--kappa", type=float, default=None, help="κ(M + h²L) if known")
    cmp_.add_argument("--rtol", type=float, default=None,
                      help="tolerance relative to the cloth size (1e-9)")
    cmp_.add_argument("--atol", type=float, default=None, help="absolute tolerance [m]")
    cmp_.add_argument("--frames", type=count(1, MAX_FRAMES), default=None, metavar="N",
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
                         "port's (x_k, v_k) against the port's x_{k+1} (held contacts: with "
                         "the planes clothsim decides from the port's state, and the port's "
                         "own planes compared with them)")
    chk.add_argument("scene", metavar="SCENE", help="scene file or built-in name")
    chk.add_argument("port", metavar="PORT", help="folder with positions.txt and "
                     "velocities.txt, or a trajectory file in any format compare reads")
    chk.add_argument("--precision", default="float64", choices=("float64", "float32"),
                     help="the port's arithmetic: float32 uses the step's measured float32 "
                     "tolerance, float64 1e-9 of the cloth size (default float64)")
    add_set_option(chk)
    chk.add_argument("--tolerance", type=float, default=None,
                     help="allowed per-vertex distance [m] (default from --precision)")
    chk.add_argument("--steps", type=count(0, MAX_FRAMES), default=None,
                     help="check only the first N steps (default: all the scene's frames; "
                     "an output with fewer fails)")
    chk.add_argument("--optimality", type=float, default=1e-6,
                     help="largest relative gradient |grad g(x)| / |grad g(x0)| of a port's "
                     "answer counted as a minimizer (1e-6)")
    chk.add_argument("--contacts", metavar="FILE", default=None,
                     help="the port's held contact planes per step (contacts.txt or "
                     "contacts.npz, as export writes them: step vertex nx ny nz offset), for "
                     "a scene whose obstacles hold contacts ([contact] mode = \"hold\", the "
                     "default): a step whose planes differ fails 'contacts differ', naming "
                     "the vertex (default: PORT/contacts.npz or PORT/contacts.txt when PORT "
                     "is a folder holding one; 'none' ignores it)")
    chk.add_argument("--verbose-steps", action="store_true", help="print every step")

    dif = sub.add_parser("diff-model", help="compare two models: springs, stiffness, rest "
                         "lengths, damping, masses, pins, forces, step settings")
    dif.add_argument("a", metavar="A", help="scene or folder of model files")
    dif.add_argument("b", metavar="B", help="scene or folder of model files")

    con = sub.add_parser("conformance", help="write the conformance set: tiny scenes, one "
                         "effect each, with reference data and iterates")
    con.add_argument("--out", metavar="DIR", default=None,
                     help="output directory (default: conformance, or coursework with "
                     "--profile coursework)")
    con.add_argument("--force", action="store_true",
                     help="write into DIR even when it holds files that are not a clothsim "
                     "conformance set")
    con.add_argument("--profile", choices=("general", "coursework"), default="general",
                     help="general: one effect per case (default); coursework: cases the "
                     "mass-spring assignment's program runs unchanged (one k, penalty pins "
                     "w = 1e10, -9.8 N per vertex, x_n, 50 iterations), in its JSON format too")


def _positive(args, names) -> str | None:
    for name in names:
        value = getattr(args, name)
        if value is not None and not (value >= 0 and math.isfinite(value)):
            return (f"--{name.replace('_', '-')}: must be a finite non-negative number, "
                    f"got {value}")
    return None


def _refuse_special(*paths) -> None:
    """A FIFO, device or socket among the inputs (or directly in an input folder) is
    refused at once: reading it would block."""
    from ..io.common import refuse_special

    for p in paths:
        if p is not None:
            refuse_special(p, inside=True)


def _bad_plot_path(path: Path) -> str | None:
    """Why ``compare --plot PATH`` cannot write an image there, or None."""
    from matplotlib.backend_bases import FigureCanvasBase

    kinds = FigureCanvasBase.get_supported_filetypes()
    if path.is_dir():
        return f"{path} is a folder; give an image file name, e.g. {path / 'deviation.png'}"
    if path.suffix.lower().lstrip(".") not in kinds:
        return (f"{path}: cannot tell the image format from {path.suffix or 'no suffix'!r}; "
                f"end the name with one of {', '.join('.' + k for k in sorted(kinds))}")
    return None


def _cmd_export(args) -> int:
    from ..ports.export import export_port
    from ..scene import load_scene

    bad = _positive(args, ("frames", "iterate_steps"))
    if bad:
        return _fail(bad, 2)
    if args.out == "":
        return _fail("--out: empty; name a folder", 2)
    scene = load_scene(args.scene, args.set)
    out = Path(args.out) if args.out is not None else Path("out") / scene.name / "export"
    if args.out is None and not args.force:
        other = other_output(out, scene, "manifest.json")
        if other:
            return _fail(other, 2)
    frames = scene.frames if args.frames is None else args.frames
    try:
        manifest = export_port(scene, out, frames=frames, iterate_steps=args.iterate_steps,
                               force=args.force)
    except (KeyboardInterrupt, OSError) as exc:
        return stopped(exc, out)
    print(f"{scene.name}: {len(manifest['files'])} files for n = {manifest['vertex_count']}, "
          f"s = {manifest['spring_count']}, h = {manifest['h']:.6g} s, {frames} frames, "
          f"κ(M + h²L) = {manifest['condition_number']:.4g} written to {out}")
    return 0


def _cmd_compare(args) -> int:
    from ..ports.compare import compare_trajectories, plot_deviation

    bad = _positive(args, ("rtol", "atol", "kappa"))
    if bad:
        return _fail(bad, 2)
    _refuse_special(args.trajectory, args.reference, args.scene)
    if args.plot and (bad := _bad_plot_path(Path(args.plot))):
        return _fail(f"--plot: {bad}", 2)  # before the comparison, not after its report
    if Path(args.trajectory).suffix == ".mtx":
        from ..ports.matrices import compare_matrices

        mres = compare_matrices(args.trajectory, args.reference,
                                rtol=1e-12 if args.rtol is None else args.rtol,
                                atol=args.atol or 0.0,
                                drop_columns="attachments" if args.drop_attachments else None)
        print(mres.summary())
        return 0 if mres.passed else 1
    kappa, kappa_vertices = args.kappa, None
    if kappa is None and args.scene is not None:
        from ..ports.check import as_simulation, system_condition_number
        from ..scene import load_scene

        sim = as_simulation(load_scene(args.scene))
        kappa, kappa_vertices = system_condition_number(sim), sim.model.vertex_count
    result = compare_trajectories(
        args.trajectory, args.reference, key=args.key or args.field or "positions",
        frames=args.frames, match=args.match_vertices, kappa=kappa, fmt=args.fmt,
        dtype=args.dtype, vertex_count=args.vertices, rtol=args.rtol, atol=args.atol,
        precision=args.precision, kappa_vertices=kappa_vertices)
    for note in result.notes:
        print(f"note: {note}")
    print(result.summary())
    if not args.no_table:
        print(result.table())
    if args.plot:
        plot_deviation(result, args.plot)
    return 0 if result.passed else 1


def _cmd_check(args) -> int:
    from ..ports.check import check_steps
    from ..ports.contact_planes import port_contacts
    from ..ports.formats import read_trajectory, read_velocities
    from ..scene import load_scene

    bad = _positive(args, ("tolerance", "steps", "optimality"))
    if bad:
        return _fail(bad, 2)
    _refuse_special(args.scene, args.port)
    scene = load_scene(args.scene, args.set)
    x = read_trajectory(args.port)
    v = read_velocities(args.port)
    contacts = port_contacts(args.port, args.contacts)
    _refuse_special(contacts)
    report = check_steps(scene, x, v, precision=args.precision, tolerance=args.tolerance,
                         steps=args.steps, optimality=args.optimality,
                         expected_steps=None if args.steps is not None else scene.frames,
                         contacts=contacts)
    if args.verbose_steps:
        for step in report.steps:
            print(step.line())
    for note in report.notes:
        print(f"note: {note}")
    print(report.summary())
    return 0 if report.passed else 1


def _cmd_diff_model(args) -> int:
    from ..errors import InputError
    from ..ports.diff import diff_models

    _refuse_special(args.a, args.b)   # model files are read, each bad line named, by
    try:                              # clothsim.ports.model_folder
        result = diff_models(args.a, args.b)
    except InputError:
        raise
    except (ValueError, IndexError, KeyError, TypeError, MemoryError) as exc:
        kind = "too large" if isinstance(exc, MemoryError) else "shapes or values do not fit"
        return _fail(f"{args.a} / {args.b}: cannot read the model files ({kind})", 2)
    print(result.report())
    return 0 if result.identical else 1


def _cmd_conformance(args) -> int:
    if args.profile == "coursework":
        from ..ports.coursework import write_coursework as write
    else:
        from ..ports.conformance import write_conformance as write

    out = args.out if args.out is not None else (
        "coursework" if args.profile == "coursework" else "conformance")
    try:
        names = write(out, force=args.force)
    except (KeyboardInterrupt, OSError) as exc:
        return stopped(exc, out)
    print(f"{len(names)} {args.profile} conformance cases written to {out} "
          f"(read {out}/README.md)")
    return 0
