"""When the contact scenes come to rest: the solver and damping settings they were chosen from.

Run from the repository root (about half an hour on a busy 2-core machine; Newton only
at 25²)::

    .venv/bin/python -m benchmarks.contact --rest                # 25² and 49²
    .venv/bin/python -m benchmarks.contact --rest --sizes 25     # one size

"At rest" (:data:`benchmarks.contact.REST_SPEED`) is every vertex slower than 0.02 m/s over
the last second of the scene. Each run here is a scene in ``"hold"`` mode at n × n
vertices for :data:`SECONDS` seconds, with the row's ``[solver]`` and damping in place of
the scene's; it reports the largest speed of any vertex in the third and in the fourth
second and the CPU seconds per frame (``time.process_time``: the machine may be shared).
The Newton rows (``tolerance`` 1e-6: each step's exact solution) tell physics from
solver: a converged run that still moves is moving because of the scene's physics (its
damping, its friction, folds settling), not because the iterations were cut short.

The second table, at 25² only, compares damping models with the scenes' declared solver
over 5 s, and counts the frames of each second whose contact set changed.
"""

from __future__ import annotations

import time
import tomllib

from clothsim.scene import builtin_scene_text

from . import ROOT
from .contact import REST_SPEED, SCENES, trace_contact
from .iteration_cost import commit

PAGE = ROOT / "docs" / "data" / "contact-rest.md"
#: Seconds of each run of the settings table.
SECONDS = 4
SIZES = (25, 49)
RIGID = {0.1: {"model": "rigid", "coefficient": 0.1},
         0.2: {"model": "rigid", "coefficient": 0.2},
         0.3: {"model": "rigid", "coefficient": 0.3}}
NEWTON = {"method": "newton", "iterations": 50, "tolerance": 1e-6}
#: The settings table's rows: (label, ``[solver]``, damping ``[[effects]]`` table, sizes
#: or None for every size).
SETTINGS = (
    ("local/global 10, rigid 0.1 (until now)", {"method": "local-global", "iterations": 10},
     RIGID[0.1], None),
    ("local/global 20, rigid 0.1", {"method": "local-global", "iterations": 20},
     RIGID[0.1], None),
    ("local/global 100, rigid 0.1", {"method": "local-global", "iterations": 100},
     RIGID[0.1], None),
    ("local/global 10, rigid 0.3", {"method": "local-global", "iterations": 10},
     RIGID[0.3], None),
    ("chebyshev 20, rigid 0.1", {"method": "chebyshev", "iterations": 20}, RIGID[0.1], None),
    ("anderson 10, rigid 0.1", {"method": "anderson", "iterations": 10}, RIGID[0.1], None),
    ("anderson 20, rigid 0.1", {"method": "anderson", "iterations": 20}, RIGID[0.1], None),
    ("anderson 30, rigid 0.1", {"method": "anderson", "iterations": 30}, RIGID[0.1], None),
    ("anderson 30, rigid 0.3", {"method": "anderson", "iterations": 30}, RIGID[0.3], None),
    ("anderson 50, rigid 0.2", {"method": "anderson", "iterations": 50}, RIGID[0.2], None),
    ("newton to 1e-6, rigid 0.1", NEWTON, RIGID[0.1], (25,)),
    ("newton to 1e-6, rigid 0.3", NEWTON, RIGID[0.3], (25,)),
)
#: The damping table's rows: (label, damping as :func:`~benchmarks.contact.trace_contact`
#: takes it: False for none).
DAMPING = (("none", False), ("rigid 0.1", RIGID[0.1]), ("rigid 0.2", {"model": "rigid",
                                                                     "coefficient": 0.2}),
           ("rigid 0.3", RIGID[0.3]), ("rigid 0.4", {"model": "rigid", "coefficient": 0.4}),
           ("velocity 0.05", {"model": "velocity", "coefficient": 0.05}),
           ("inertial 0.9", {"model": "inertial", "coefficient": 0.9}))


def declared(scene: str) -> tuple[dict, dict]:
    """The scene's own ``[solver]`` table and damping ``[[effects]]`` table (without its
    ``kind``)."""
    doc = tomllib.loads(builtin_scene_text(scene))
    damping = [e for e in doc["effects"] if e["kind"] == "damping"]
    return doc["solver"], ({k: v for k, v in damping[0].items() if k != "kind"}
                           if damping else {})


def by_second(scene: str, resolution: int, seconds: int, damping=None,
              solver: dict | None = None) -> tuple[list[float], list[int], float]:
    """The largest speed [m/s] of any vertex in each second of a run ("hold" mode), the
    frames of each second whose contact set changed, and the CPU seconds per frame."""
    speed, changes = [0.0] * seconds, [0] * seconds
    t0 = time.process_time()
    for r in trace_contact(scene, resolution, "hold", frames=30 * seconds, damping=damping,
                           solver=solver):
        k = r["frame"] // 30
        speed[k] = max(speed[k], r["speed"])
        changes[k] += int(r["set_changed"])
    return speed, changes, (time.process_time() - t0) / (30 * seconds)


def _mark(label: str, solver: dict, damping: dict) -> str:
    """The row's label, bold and naming the scenes that declare its settings, if any."""
    row = ({"method": "local-global", **solver} if "method" not in solver else solver, damping)
    scenes = [s for s in SCENES if declared(s) == row]
    if len(scenes) == len(SCENES):
        return f"**{label} (declared)**"
    return f"**{label} (declared by {', '.join(scenes)})**" if scenes else label


def settings_table(resolution: int) -> list[str]:
    """The settings table at ``resolution``² (Markdown lines)."""
    cells = " | ".join(f"{s} {k}. s" for s in SCENES for k in (3, 4))
    out = [f"| {resolution}² | {cells} | CPU s per frame |", "|---" * 6 + "|"]
    for label, solver, damping, sizes in SETTINGS:
        if sizes is not None and resolution not in sizes:
            continue
        row, cpu = [], []
        for scene in SCENES:
            speed, _, c = by_second(scene, resolution, SECONDS, damping, solver)
            row += [_speed(v) for v in speed[2:4]]
            cpu.append(c)
        out.append(f"| {_mark(label, solver, damping)} | " + " | ".join(row)
                   + f" | {cpu[0]:.3f}, {cpu[1]:.3f} |")
        print(out[-1], flush=True)
    return out


def damping_table(resolution: int = 25, seconds: int = 5) -> list[str]:
    """The damping models with the scenes' declared solver (Markdown lines)."""
    out = []
    for scene in SCENES:
        solver, own = declared(scene)
        out += [f"| {scene} | " + " | ".join(f"{k + 1}. s" for k in range(seconds)) + " |",
                "|---" * (seconds + 1) + "|"]
        for label, damping in DAMPING:
            speed, changes, _ = by_second(scene, resolution, seconds, damping)
            mark = f"**{label} (declared)**" if damping == own else label
            out.append(f"| {mark} | " + " | ".join(
                f"{_speed(v)} ({c})" for v, c in zip(speed, changes)) + " |")
            print(out[-1], flush=True)
        out.append("")
    return out


def _speed(v: float) -> str:
    return f"{v:.3f}" if v < REST_SPEED else f"*{v:.3f}*"


def rest_page(sizes=SIZES) -> str:
    """The page: the settings tables at ``sizes``, then the damping table at 25²."""
    solvers = ", ".join(f"{s} {declared(s)[0]['method']} {declared(s)[0]['iterations']}"
                        for s in SCENES)
    out = [f"Printed by `.venv/bin/python -m benchmarks.contact --rest`, commit {commit()}.",
           "",
           f"The largest speed of any vertex [m/s] in the third and the fourth second of a "
           f"{SECONDS} s run of each scene in \"hold\" mode with the row's solver and damping "
           f"(in italics: not at rest, {REST_SPEED} m/s or faster), and the CPU seconds per "
           f"frame (drop-on-square, drape-sphere). The scenes declare the bold rows and end "
           f"after {_frames()} frames.", ""]
    for n in sizes:
        out += settings_table(n) + [""]
    out += [f"The damping models at 25² with each scene's declared solver ({solvers} "
            f"iterations): the largest speed in each second of a 5 s run, and in brackets the "
            f"frames of that second whose contact set changed.", ""]
    out += damping_table()
    return "\n".join(out)


def _frames() -> str:
    """Each scene's declared number of frames ("120 and 150")."""
    return " and ".join(str(tomllib.loads(builtin_scene_text(s))["scene"]["frames"])
                        for s in SCENES)


def write_rest_page(sizes=None) -> None:
    """Print the comparison and write it to docs/data/contact-rest.md (atomically)."""
    from clothsim.io.common import atomic_path

    text = rest_page(SIZES if sizes is None else tuple(sizes))
    with atomic_path(PAGE) as tmp:
        tmp.write_text(text, encoding="utf-8")
