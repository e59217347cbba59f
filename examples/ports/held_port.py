"""A hold-mode "port" with one fault planted at a time, written as a port writes its output.

It is clothsim's own simulation of a scene with one change in its contact handling, run
from the scene's start: its frames (positions.txt, velocities.txt) and the held planes it
used in each step, in the layout of ``clothsim export`` (contacts.txt). docs/ports.md
("Checking a hold-mode port") checks each with ``clothsim check``;
tests/ports/test_check_held.py asserts what the check names.

    .venv/bin/python examples/ports/held_port.py drop-on-square --fault flipped \
        --frames 15 --out out/held-flipped

- ``"none"``: clothsim's held step itself;
- ``"post-solve"``: the port resolves contact after the solve (the seed's projection)
  instead of holding vertices in it; it holds no planes;
- ``"frictionless"``: the port holds its vertices on their planes without friction (no
  sticking, no kinetic friction on held vertices);
- ``"flipped"``: the port's contact normal has the wrong sign where it reads the contact
  force (n · ∇g): it releases the vertices the obstacle pushes and keeps those the cloth
  pulls away, and its contacts file carries −n (and −offset: the same planes);
- ``"no-stick"``: the port ignores static friction: every held vertex slides under
  kinetic friction μ F_n, none is held in all three directions;
- ``"clinging"``: the port keeps a held vertex after the cloth pulls it away (it never
  releases on a negative normal force).

``--set KEY=VALUE`` (as ``clothsim run --set``) changes the port's scene: a port whose
box, sphere or friction coefficient differs from the scene it is checked against, e.g.
``--set 'effects[1].radius=0.31'`` on drape-sphere.
"""

from __future__ import annotations

import argparse
import sys
import tomllib
from pathlib import Path

import numpy as np

from clothsim.effects.holding import Holding
from clothsim.ports.held_steps import holding_obstacles
from clothsim.scene import Scene, builtin_scene_text, load_scene

FAULTS = ("none", "post-solve", "frictionless", "flipped", "no-stick", "clinging")


def builtin(name: str = "drop-on-square", resolution: int = 25, solver: dict | None = None,
            **contact) -> Scene:
    """A built-in scene at ``resolution``², its [contact] table as given, its [solver]
    table replaced by ``solver`` when given."""
    doc = tomllib.loads(builtin_scene_text(name))
    doc["cloth"]["resolution"] = [resolution, resolution]
    if solver is not None:
        doc["solver"] = dict(solver)
    if contact:
        doc["contact"] = dict(contact)
    return Scene.from_dict(doc, source=f"{name}.toml")


def run_port(scene: Scene, fault: str, frames: int):
    """The port's frames and planes: (positions, velocities (frames + 1, n, 3), rows (c, 6))."""
    assert fault in FAULTS
    sim = scene.build_simulation()
    obstacles = holding_obstacles(sim)
    if fault == "post-solve":
        for e in obstacles:
            e.contact = "post-solve"          # the same obstacles (thickness), projected
    if fault == "flipped":
        sim._contact_forces = _flipped(sim)
    if fault == "clinging":
        sim._contact_forces = _clinging(sim)
    xs, vs, rows = [sim.state.positions.copy()], [sim.state.velocities.copy()], []
    for k in range(frames):
        for e in obstacles:
            h = e._holding
            c = len(h.vertices)
            if fault == "frictionless":
                h = e._holding = Holding(sim.state.positions, h.vertices, h.normals,
                                         np.zeros(c, bool), np.zeros(c), np.zeros((c, 3)))
            if fault == "no-stick":
                h = e._holding = Holding(sim.state.positions, h.vertices, h.normals,
                                         np.zeros(c, bool), h.normal_force, h.pull)
            p = h.planes
            if fault == "post-solve" or not len(p):
                continue
            sign = -1.0 if fault == "flipped" else 1.0
            rows.append(np.column_stack([np.full(len(p), k), p.vertices, sign * p.normals,
                                         sign * p.offsets]))
        sim.step()
        xs.append(sim.state.positions.copy())
        vs.append(sim.state.velocities.copy())
    return np.stack(xs), np.stack(vs), np.concatenate([np.zeros((0, 6))] + rows)


def _flipped(sim):
    """The simulation's contact forces with the normal's sign flipped: F = −n · ∇g / h²."""
    forces = sim._contact_forces

    def flipped(problem, x, t):
        forces(problem, x, t)
        for c in sim._held_sets(t):
            if c.forces is not None:
                c.forces = -c.forces

    return flipped


def _clinging(sim):
    """The simulation's contact forces with no pull: a held vertex's normal force below 0
    is read as 0, so the obstacle never releases it."""
    forces = sim._contact_forces

    def clinging(problem, x, t):
        forces(problem, x, t)
        for e in holding_obstacles(sim):
            h = e._holding
            if h.planes.forces is not None:
                c = len(h.vertices)
                h.planes.forces[:c] = np.maximum(h.planes.forces[:c], 0.0)

    return clinging


def write_port(folder, positions, velocities, rows=None, fmt: str = "%.17g") -> None:
    """The port's output folder: positions.txt, velocities.txt (and contacts.txt)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    np.savetxt(folder / "positions.txt", positions.reshape(len(positions), -1), fmt=fmt)
    np.savetxt(folder / "velocities.txt", velocities.reshape(len(velocities), -1), fmt=fmt)
    if rows is not None:
        np.savetxt(folder / "contacts.txt", rows,
                   fmt=["%d", "%d", fmt, fmt, fmt, fmt], header="step vertex nx ny nz offset")


def main(argv=None) -> int:
    """Run the port on a scene and write its output folder."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", help="scene file or built-in name (obstacles in hold mode)")
    parser.add_argument("--fault", choices=FAULTS, default="none")
    parser.add_argument("--frames", type=int, default=15)
    parser.add_argument("--out", required=True, help="output folder")
    parser.add_argument("--format", default="%.17g", help="printf format of the numbers")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="change the port's scene (a port of another obstacle or friction)")
    parser.add_argument("--no-contacts", action="store_true",
                        help="write no contacts.txt (a port that does not write its planes)")
    args = parser.parse_args(argv)
    x, v, rows = run_port(load_scene(args.scene, args.set), args.fault, args.frames)
    write_port(Path(args.out), x, v, None if args.no_contacts else rows, fmt=args.format)
    print(f"{args.fault}: {args.frames} steps written to {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
