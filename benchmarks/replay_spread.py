"""How far a printed start moves an accelerated step: the replayed printed-precision bound.

Runs the right port of examples/ports/held_port.py (clothsim's own step, printed with
``%g``) on the contact scenes with their declared solver (Anderson: 30 iterations on the
box, 50 on the sphere) and on ``hanging`` with Anderson, L-BFGS and Chebyshev at 30
iterations, 20 steps each, and checks
it. For every step that fails the contraction bound and is replayed
(:func:`clothsim.ports.printed_replay.replayed_tolerance`, along the port's branch of the
solver's discrete choices, :mod:`clothsim.ports.solver_branches`), it prints the port's
error, the contraction bound, the spread of the 4 sign patterns the check replays, of 32
sign patterns, and of 32 uniform draws (as rounding is), and the tolerance the step gets;
and per case, how many steps were replayed and the summary. Writes
docs/data/replay-spread.md (included by docs/ports.md). Run from the repository root:
``.venv/bin/python -m benchmarks replay_spread`` (about a minute of CPU).
"""

from __future__ import annotations

import importlib.util
import tempfile
import tomllib
from unittest import mock

import numpy as np

from clothsim.ports import precision
from clothsim.ports.check import check_steps
from clothsim.ports.formats import read_trajectory, read_velocities
from clothsim.ports.precision import printed_tolerances
from clothsim.ports.printed_replay import SPREAD_MARGIN, moved_starts, spread_tolerance
from clothsim.scene import Scene, builtin_scene_text

from .port_causes import ROOT

OUT = ROOT / "docs" / "data" / "replay-spread.md"
FRAMES = 20
#: (scene, [solver] table or None for the scene's own)
CASES = [("drape-sphere", None), ("drop-on-square", None)] + [
    ("hanging", {"method": m, "iterations": 30}) for m in ("anderson", "lbfgs", "chebyshev")]


def _held_port():
    spec = importlib.util.spec_from_file_location(
        "held_port", ROOT / "examples" / "ports" / "held_port.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _scene(name, solver):
    doc = tomllib.loads(builtin_scene_text(name))
    if solver is not None:
        doc["solver"] = dict(solver)
    return Scene.from_dict(doc, source=f"{name}.toml")


def main() -> list[str]:
    held_port = _held_port()
    rows = ["| scene, solver | step | port error [m] | contraction bound [m] | spread, 4 sign "
            "patterns [m] | 32 sign patterns [m] | 32 uniform draws [m] | tolerance [m] |",
            "|---|---|---|---|---|---|---|---|"]
    cases = []
    for name, solver in CASES:
        scene = _scene(name, solver)
        sim = scene.build_simulation()
        label = f"{name}, {sim.solver.name} {sim.solver.iterations}"
        X, V, contacts = held_port.run_port(scene, "none", FRAMES)
        with tempfile.TemporaryDirectory() as folder:
            held_port.write_port(folder, X, V, contacts, fmt="%g")
            X, V = read_trajectory(folder), read_velocities(folder)
        cheap = printed_tolerances(X, V, sim.h, 6)
        found = []

        captured = {}

        def starts_spy(*args, captured=captured, **kwargs):
            captured["args"], captured["kwargs"] = args, kwargs
            return moved_starts(*args, **kwargs)

        def spy(replay, starts, xa, xp, ux, found=found, X=X, captured=captured):
            # the check's replays (along the port's branch of the solver's choices), and
            # 32 sign patterns and 32 uniform draws from the same start
            own = np.sqrt(3.0) * ux * float(np.abs(xp).max())
            tol = spread_tolerance(replay, starts, xa, xp, ux)
            args, kwargs = captured["args"], captured["kwargs"]
            k = next(i for i in range(len(X)) if np.array_equal(X[i], args[0]))
            more = [moved_starts(*args, **{**kwargs, **kw})
                    for kw in ({"patterns": 32}, {"patterns": 32, "signs": False})]
            found.append((k, [(tol - own) / SPREAD_MARGIN] + [
                (spread_tolerance(replay, st, xa, xp, ux) - own) / SPREAD_MARGIN
                for st in more]))
            return tol

        with mock.patch.object(precision, "moved_starts", starts_spy), \
                mock.patch.object(precision, "spread_tolerance", spy):
            report = check_steps(scene, X, V)
        for k, spreads in found:
            rows.append(f"| {label} | {k} → {k + 1} | {report.steps[k].error:.2e} | "
                        f"{cheap[k]:.2e} | " + " | ".join(f"{s:.2e}" for s in spreads)
                        + f" | {report.steps[k].tolerance:.2e} |")
        cases.append(f"- {label}: {len(found)} of {FRAMES} steps replayed; "
                     f"`{report.summary().split(';')[0]}`")
    text = "\n".join([f"Printed by `.venv/bin/python -m benchmarks replay_spread` (right "
                      f"ports printed with `%g`, {FRAMES} steps, checked with their stored "
                      f"velocities):", "", *rows, "", *cases, ""])
    OUT.write_text(text)
    print(text)
    return rows


if __name__ == "__main__":
    main()
