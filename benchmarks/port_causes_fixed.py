"""What ``check`` says about ports that run a fixed number of iterations with a planted
fault, and what naming the cause costs (replays of clothsim's step).

The port is clothsim itself with one scene key changed (as ``--set`` changes it): a
16 × 10 and a 30 × 20 curtain (area-lumped masses, three pins) at the scene's 10
local/global iterations from y, drop-on-square 25² with contact projected after the solve
(10 iterations, 16 frames), and drape-sphere at 30 × 20 in post-solve mode (8 frames).
Two faults at once are joined by " + ". For each run: the check's summary line, the
replays of clothsim's step it took (each costs one step of the scene), and its CPU time
beside the check of the right port's run.
Writes docs/data/port-causes-fixed.md (included by docs/ports.md). Run from the
repository root: ``.venv/bin/python -m benchmarks port_causes_fixed`` (about a minute).
"""

from __future__ import annotations

import re
import tempfile
import time
from importlib import resources
from pathlib import Path

import clothsim as cs
from clothsim.ports import check as check_module
from clothsim.ports import effect_causes
from clothsim.ports.check import check_steps

from .contact import SEED

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "data" / "port-causes-fixed.md"

#: A non-square curtain (area-lumped masses, three pins); tests/ports/test_planted_faults.py
#: uses it too, converged (500 iterations, a tolerance) and at 10 iterations.
CURTAIN = """
[scene]
name = "curtain"
frames = 3
fps = 30

[cloth]
shape = "grid"
size = [1.5, 1.0]
resolution = [{nx}, {ny}]
center = [0.0, 1.0, 0.0]
plane = "xy"
mass = 0.8
mass_lumping = "area"

[springs]
structural = 600.0
shear = 400.0
bending = 40.0

[solver]
method = "local-global"
iterations = {iterations}
{tolerance}

[[effects]]
kind = "gravity"
acceleration = [0.0, -9.81, 0.0]

[[effects]]
kind = "pin"
grid = [[-1, 0], [-1, {mid}], [-1, -1]]
"""

CURTAIN_FAULTS = ['cloth.mass_lumping="uniform"', "scene.fps=15", "springs.bending=0",
                  "effects[0].acceleration=[0.0, 9.81, 0.0]", "springs.structural=300.0",
                  'scene.fps=15 + cloth.mass_lumping="uniform"']


def seed_scene_text(name, frames, resolution=None) -> str:
    """The built-in scene ``name`` with the seed's solver (:data:`benchmarks.contact.SEED`:
    10 local/global iterations, whatever solver the scene declares now), post-solve
    contact and ``frames`` frames; its declared damping stays."""
    solver = SEED["solver"]
    text = resources.files("clothsim.scenes").joinpath(f"{name}.toml").read_text()
    text = re.sub(r"(?m)^frames = \d+$", f"frames = {frames}", text)
    text = re.sub(r'(?m)^method = "[\w-]+"$', f'method = "{solver["method"]}"', text)
    text = re.sub(r"(?m)^iterations = \d+$", f'iterations = {solver["iterations"]}', text)
    if resolution:
        text = text.replace("resolution = [25, 25]", resolution)
    return text + '\n[contact]\nmode = "post-solve"\n'


def _cases():
    for nx, ny in ((16, 10), (30, 20)):
        yield (f"curtain {nx}x{ny}", CURTAIN.format(nx=nx, ny=ny, mid=nx // 2 - 1, iterations=10,
                                                    tolerance=""), CURTAIN_FAULTS)
    yield ("drop-on-square 25², post-solve", seed_scene_text("drop-on-square", 16),
           ['cloth.mass_lumping="area"', "scene.fps=15", "springs.bending=0",
            "effects[3].coefficient=0", "effects[1].max=[0.25, 0.45, 0.25]"])
    yield ("drape-sphere 30x20, post-solve",
           seed_scene_text("drape-sphere", 8, "resolution = [30, 20]"),
           ["effects[3].coefficient=0", "effects[3].coefficient=0.05", "effects[1].radius=0.25",
            "scene.fps=15", "effects[1].radius=0.25 + scene.fps=15"])


class _Counter:
    """Counts the replays of clothsim's step a check takes."""

    def __init__(self):
        self.count = 0
        self._replayer, self._replay_step = check_module._replayer, effect_causes._replay_step

    def __enter__(self):
        def replayer(sim, state, *shared):
            solve = self._replayer(sim, state, *shared)

            def counted(model, problem):
                self.count += 1
                return solve(model, problem)
            return counted

        def replay_step(sim, state):
            self.count += 1
            return self._replay_step(sim, state)
        check_module._replayer, effect_causes._replay_step = replayer, replay_step
        return self

    def __exit__(self, *exc):
        check_module._replayer, effect_causes._replay_step = self._replayer, self._replay_step


def _port(path, overrides):
    scene = cs.load_scene(path, overrides)
    sim = scene.build_simulation(scene.build_model())
    xs, vs = [sim.state.positions.copy()], [sim.state.velocities.copy()]
    for _ in range(scene.frames):
        sim.step()
        xs.append(sim.state.positions.copy())
        vs.append(sim.state.velocities.copy())
    return xs, vs


def _check(path, overrides):
    xs, vs = _port(path, overrides)
    with _Counter() as counter:
        t0 = time.process_time()
        summary = check_steps(cs.load_scene(path), xs, vs).summary()
        cpu = time.process_time() - t0
    return summary, counter.count, cpu


def main() -> None:
    lines = ["Printed by `.venv/bin/python -m benchmarks port_causes_fixed`: each port is "
             "clothsim's run of the scene with the keys shown changed (`--set`); replays: "
             "steps of clothsim the check took to name the cause; CPU: seconds of the "
             "check, beside the right port's check (a shared machine: ±30 %).", ""]
    with tempfile.TemporaryDirectory() as tmp:
        for title, text, faults in _cases():
            path = Path(tmp) / "scene.toml"
            path.write_text(text, encoding="utf-8")
            right, _, cpu0 = _check(path, [])
            lines += [f"**{title}** (the right port: {right[:4]}, {cpu0:.2f} s CPU)", "",
                      "```text"]
            for fault in faults:
                summary, replays, cpu = _check(path, fault.split(" + "))
                lines += [f"--set {fault}", f"  {summary}",
                          f"  [{replays} replays, {cpu:.2f} s CPU]"]
                print(f"{title} {fault}: {replays} replays, {cpu:.2f} s: {summary[:120]}",
                      flush=True)
            lines += ["```", ""]
    OUT.write_text("\n".join(lines), encoding="utf-8")
    print(f"   written to {OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
