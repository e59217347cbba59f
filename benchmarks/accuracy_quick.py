"""``clothsim accuracy --quick`` on the seed's demo at 21 × 21 (the issue's 30 s target).

Runs the drop-on-square scene (a cloth dropped onto a box: free fall, then contact and
crumpling) with its resolution set to 21 × 21, in this process, exactly as
``clothsim accuracy SCENE --quick --no-plots`` does, and prints the wall and CPU seconds,
the commit, the report's first line (how many recorded steps were measured, per class) and
the CPU seconds of each phase of the study (``phase_seconds`` of its ``accuracy.json``).
The machine is shared: the wall time includes waiting for a core, the CPU time does not.
Run: ``python -m benchmarks accuracy_quick``; it also writes
``docs/data/accuracy-quick.md``, which docs/accuracy.md includes.
"""

from __future__ import annotations

import json
import os
import subprocess
import tempfile
import time
import warnings
from pathlib import Path

N = 21
TARGET_SECONDS = 30.0
OUT = Path(__file__).resolve().parents[1] / "docs" / "data" / "accuracy-quick.md"


def scene(n: int = N):
    """The built-in drop-on-square scene at n × n vertices.

    Parameters
    ----------
    n : int
        Vertices per side.

    Returns
    -------
    clothsim.scene.Scene
    """
    from clothsim.scene import Scene, load_scene

    data = load_scene("drop-on-square").to_dict()
    data["cloth"]["resolution"] = [n, n]
    data["scene"]["name"] = f"drop-on-square-{n}"
    return Scene.from_dict(data)


def commit() -> str:
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def main() -> None:
    from clothsim.accuracy import run_accuracy

    with tempfile.TemporaryDirectory() as out, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0, c0 = time.perf_counter(), time.process_time()
        text = run_accuracy(scene(), Path(out), quick=True, plots=False)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        phases = json.loads((Path(out) / "accuracy.json").read_text())["phase_seconds"]
    lines = [f"commit {commit()}: clothsim accuracy drop-on-square ({N}x{N}) --quick",
             text.splitlines()[0].lstrip("# "),
             f"wall {wall:.1f} s, CPU {cpu:.1f} s (target: {TARGET_SECONDS:.0f} s; "
             f"{'met' if wall <= TARGET_SECONDS else 'missed'} in wall time, "
             f"{'met' if cpu <= TARGET_SECONDS else 'missed'} in CPU time; load average "
             f"{os.getloadavg()[0]:.2f} at the end)",
             "CPU seconds per phase: " + ", ".join(f"{name} {spent['cpu']:.1f}"
                                                   for name, spent in phases.items())]
    print("\n".join(f"   {line}" for line in lines))
    OUT.write_text("Printed by `.venv/bin/python -m benchmarks accuracy_quick`:\n\n```text\n"
                   + "\n".join(lines) + "\n```\n", encoding="utf-8")


if __name__ == "__main__":
    main()
