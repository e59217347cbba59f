"""The pictures of a large run, this commit against another source tree, interleaved.

``python -m benchmarks.pictures_vs OLD_TREE [--size 513] [--repeats 3]`` makes one
``clothsim run`` of the ``hanging`` cloth at SIZE² for 5 frames without pictures, then draws
its ``preview.gif`` and ``final.png`` as the runner does (:func:`clothsim.plotting.write_preview`,
:func:`~clothsim.plotting.write_final_image`, from the memory-mapped trajectory), alternately
with the clothsim source tree at OLD_TREE (e.g. ``/work/main``, or ``git archive main | tar -x
-C /tmp/old``) and this one, each in a fresh process. It reports the thread CPU seconds of
the matplotlib import and of the two pictures (medians; CPU, not wall: the machine may be
shared), and whether the two trees' pictures are the same pixel for pixel. Prints a
Markdown table and writes it to ``docs/data/pictures-vs.md`` (``--out`` elsewhere).
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from .large_vs import env_for
from .scale_ladder import commit

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "data" / "pictures-vs.md"
FRAMES = 5

CHILD = r"""
import json, sys, time
from pathlib import Path
import numpy as np
import clothsim as cs
from clothsim.plotting import write_final_image, write_preview
run, out, n = Path(sys.argv[1]), Path(sys.argv[2]), int(sys.argv[3])
sim = cs.load_scene("hanging", [f"cloth.resolution=[{n}, {n}]"]).build_simulation()
c0 = time.thread_time()
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: F401
from matplotlib.figure import Figure  # noqa: F401
c1 = time.thread_time()
z = np.load(run / "trajectory.npz", mmap_mode="r")
positions, times = z["positions"], z["time"]
write_preview(out / "preview.gif", positions, sim.model.mesh, times=times, effects=sim.effects)
c2 = time.thread_time()
write_final_image(out / "final.png", np.array(positions[-1]), sim.model.mesh,
                  title=f"hanging, t = {times[-1]:.2f} s", effects=sim.effects,
                  t=float(times[-1]))
c3 = time.thread_time()
print(json.dumps({"import": c1 - c0, "preview": c2 - c1, "final": c3 - c2}))
"""


def make_run(folder: Path, n: int) -> None:
    """The run whose pictures are drawn (this tree, no pictures)."""
    subprocess.run([sys.executable, "-m", "clothsim", "run", "hanging", "--set",
                    f"cloth.resolution=[{n}, {n}]", "--frames", str(FRAMES), "--out",
                    str(folder), "--no-preview"], check=True, cwd=ROOT, capture_output=True)


def pictures(tree: Path, run: Path, out: Path, n: int) -> dict:
    """Thread CPU seconds of one tree's pictures of ``run``, written to ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    res = subprocess.run([sys.executable, "-c", CHILD, str(run), str(out), str(n)], check=True,
                         cwd=tree, capture_output=True, text=True, env=env_for(tree))
    return json.loads(res.stdout.strip().splitlines()[-1])


def same_pixels(a: Path, b: Path) -> bool:
    """Do two folders hold the same preview.gif frames and final.png, pixel for pixel?"""
    import numpy as np
    from PIL import Image, ImageSequence

    for name in ("preview.gif", "final.png"):
        with Image.open(a / name) as ia, Image.open(b / name) as ib:
            fa = [np.asarray(f.convert("RGB")) for f in ImageSequence.Iterator(ia)]
            fb = [np.asarray(f.convert("RGB")) for f in ImageSequence.Iterator(ib)]
        if len(fa) != len(fb) or any(not np.array_equal(x, y) for x, y in zip(fa, fb)):
            return False
    return True


def table(res: dict, same: bool) -> list[str]:
    """The Markdown lines: each tree's median thread CPU per part, and new / old."""
    lines = ["| thread CPU | old | new | new / old |", "|---|---|---|---|"]
    for label, key in (("matplotlib import", "import"), ("preview.gif", "preview"),
                       ("final.png", "final"), ("pictures in all", "all")):
        old, new = (statistics.median(r[key] for r in res[k]) for k in ("old", "new"))
        lines.append(f"| {label} | {old:.3f} s | {new:.3f} s | {new / old:.2f} |")
    lines += ["", f"Pictures pixel for pixel the same in both trees: {'yes' if same else 'NO'}."]
    return lines


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.pictures_vs")
    parser.add_argument("old", type=Path)
    parser.add_argument("--size", type=int, default=513)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    trees = {"old": args.old.resolve(), "new": ROOT}
    res = {k: [] for k in trees}
    load = Path("/proc/loadavg").read_text().split()[0]
    with tempfile.TemporaryDirectory() as tmp:
        run = Path(tmp) / "run"
        make_run(run, args.size)
        for r in range(args.repeats):
            for name in (("old", "new") if r % 2 == 0 else ("new", "old")):
                t = pictures(trees[name], run, Path(tmp) / name, args.size)
                t["all"] = t["import"] + t["preview"] + t["final"]
                res[name].append(t)
                print(name, json.dumps({k: round(v, 3) for k, v in t.items()}), flush=True)
        same = same_pixels(Path(tmp) / "old", Path(tmp) / "new")
    lines = [f"Measured by `python -m benchmarks.pictures_vs OLD_TREE --size {args.size} "
             f"--repeats {args.repeats}` at commit {commit()} against {args.old.name}/ "
             f"({args.size}² `hanging`, {FRAMES} frames; median thread CPU of fresh processes, "
             f"interleaved; load average {load} at the start).", ""] + table(res, same)
    print("\n" + "\n".join(lines))
    args.out.write_text("\n".join(lines) + "\n")
    print(f"written to {args.out}")



if __name__ == "__main__":
    main()
