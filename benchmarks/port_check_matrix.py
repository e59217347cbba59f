"""The port checker on contact scenes with accelerated solvers: a matrix of right ports.

For drop-on-square and drape-sphere at 25², in both contact modes (``hold``, and the
seed's ``post-solve`` projection), with Anderson, L-BFGS and Chebyshev at 10 and 30
iterations, clothsim's own trajectory (:data:`FRAMES` steps, through the landing) is the
port: printed with ``%g`` and read back (checked as float64), and rounded to float32
(checked with ``precision="float32"``). Each row gives the verdict, the step of the largest
error / tolerance with both numbers, the loosest step (the largest tolerance), whether a
1 mm fault planted in that step (on the vertex of its largest error, in x_{k+1}; the step
checked alone, from the port's x_k and v_k) still fails, and how many steps needed a
replay (the printed start's effect measured by replaying it,
:mod:`clothsim.ports.printed_replay`). Writes
docs/data/port-check-matrix.md (included by docs/ports.md). Run from the repository root:
``.venv/bin/python -m benchmarks port_check_matrix`` (minutes of CPU; :data:`WORKERS`
rows at once).
"""

from __future__ import annotations

import time
import tomllib
from concurrent.futures import ProcessPoolExecutor
from unittest import mock

import numpy as np

from clothsim.ports import precision
from clothsim.ports.check import check_steps
from clothsim.scene import Scene, builtin_scene_text

from .port_causes import ROOT
from .replay_spread import _held_port

OUT = ROOT / "docs" / "data" / "port-check-matrix.md"
FRAMES = 16
#: Rows checked at once (each row is independent).
WORKERS = 2
SCENES = ("drop-on-square", "drape-sphere")
MODES = ("hold", "post-solve")
SOLVERS = tuple((m, k) for m in ("anderson", "lbfgs", "chebyshev") for k in (10, 30))
PORTS = ("%g", "float32")
FAULT = 1e-3
#: Why a right port of a row still fails, as far as it was established (docs/ports.md):
#: (scene, mode, solver, port) -> the reason; none is known now.
KNOWN: dict = {}
_g = np.vectorize(lambda c: float(f"{c:g}"))   # printed with %g and read back


def scene_for(name: str, mode: str, method: str, iterations: int) -> Scene:
    """The built-in scene at 25² with ``[contact] mode`` and the solver given."""
    doc = tomllib.loads(builtin_scene_text(name))
    doc["cloth"]["resolution"] = [25, 25]
    doc["solver"] = {"method": method, "iterations": iterations}
    doc["contact"] = {"mode": mode}
    return Scene.from_dict(doc, source=f"{name}.toml")


def trajectory(scene: Scene, frames: int = FRAMES):
    """clothsim's own positions and velocities, (frames + 1, n, 3) each: the right port
    (examples/ports/held_port.py without a fault)."""
    return _held_port().run_port(scene, "none", frames)[:2]


def printed(X, V, port: str):
    """The port's frames as a check reads them, and the precision to check them at."""
    if port == "float32":
        return X.astype(np.float32), V.astype(np.float32), "float32"
    return _g(X), _g(V), "float64"


def row(name: str, mode: str, method: str, iterations: int, port: str) -> dict:
    """One cell of the matrix: the right port's verdict and its planted fault's."""
    scene = scene_for(name, mode, method, iterations)
    X, V = trajectory(scene)
    Xp, Vp, prec = printed(X, V, port)
    replays = []
    real = precision.spread_tolerance

    def counted(*args, **kwargs):
        replays.append(1)
        return real(*args, **kwargs)

    t0 = time.process_time()
    with mock.patch.object(precision, "spread_tolerance", counted):
        report = check_steps(scene, Xp, Vp, precision=prec)
    cpu = time.process_time() - t0
    worst = max(report.steps, key=lambda s: s.error / s.tolerance)
    loose = max(report.steps, key=lambda s: (s.tolerance, s.error / s.tolerance))
    k, v = loose.k, loose.vertex
    Xf = np.array(X[k:k + 2])   # that step alone, from the port's x_k and v_k
    Xf[1, v] += [0.0, 0.0, FAULT]
    Xf, Vf, _ = printed(Xf, V[k:k + 2], port)
    caught = not check_steps(scene, Xf, Vf, precision=prec).passed
    return {"scene": name, "mode": mode, "solver": f"{method} {iterations}", "port": port,
            "passed": report.passed, "verdict": report.summary().split(";")[0],
            "k": worst.k, "error": worst.error, "tolerance": worst.tolerance,
            "loose": k, "loose_tolerance": loose.tolerance,
            "replays": len(replays), "fault": caught, "cpu": cpu,
            "failing": [s.line() for s in report.steps if not s.passed][:1]}


def _row(args):
    return row(*args)


def main() -> list[dict]:
    cells = [(name, mode, method, iterations, port) for name in SCENES for mode in MODES
             for method, iterations in SOLVERS for port in PORTS]
    rows = []
    with ProcessPoolExecutor(WORKERS) as pool:
        for (name, mode, method, iterations, port), r in zip(cells, pool.map(_row, cells)):
            print(f"{name} {mode} {method} {iterations} {port}: {r['verdict']} "
                  f"(step {r['k']}: {r['error']:.2e} / {r['tolerance']:.2e}; loosest "
                  f"{r['loose']}: {r['loose_tolerance']:.2e}; "
                  f"{r['replays']} replayed; fault caught {r['fault']}; "
                  f"{r['cpu']:.1f} s)", flush=True)
            for line in r["failing"]:
                print("   ", line[:600], flush=True)
            rows.append(r)
    _write(rows)
    return rows


def _write(rows) -> None:
    lines = [f"Printed by `.venv/bin/python -m benchmarks port_check_matrix` (right ports: "
             f"clothsim's own {FRAMES} steps at 25², printed with `%g` and checked as float64, "
             f"or rounded to float32 and checked with `--precision float32`; the fault: "
             f"{FAULT * 1e3:g} mm on the vertex of the largest error in the step of the "
             f"largest tolerance (the loosest), that step checked alone):", "",
             "| scene | contact | solver | port | verdict | largest error / tolerance "
             "(step: error, tolerance [m]) | loosest step: tolerance [m] | 1 mm fault there "
             "| steps replayed |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['scene']} | {r['mode']} | {r['solver']} | {r['port']} | "
                     f"{'PASS' if r['passed'] else 'FAIL'} | "
                     f"{r['error'] / r['tolerance']:.2f} ({r['k']} → {r['k'] + 1}: "
                     f"{r['error']:.2e}, {r['tolerance']:.2e}) | "
                     f"{r['loose']} → {r['loose'] + 1}: {r['loose_tolerance']:.2e} | "
                     f"{'fails' if r['fault'] else 'MISSED'} | {r['replays']} |")
    failing = [r for r in rows if not r["passed"]]
    lines += ["", f"{len(rows) - len(failing)} of {len(rows)} right ports pass; "
              f"{sum(r['fault'] for r in rows)} of {len(rows)} planted faults fail at their "
              f"step."]
    for r in failing:
        why = KNOWN.get((r["scene"], r["mode"], r["solver"], r["port"]),
                        "reason not established")
        lines.append(f"- still failed: {r['scene']}, {r['mode']}, {r['solver']}, {r['port']}: "
                     f"`{r['verdict'][:160]}…`; why: {why}")
    OUT.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
