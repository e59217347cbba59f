"""How near a vertex's first contact lands to the edge of its friction decision.

A vertex caught by an obstacle in hold mode gets its friction state geometrically
(:func:`clothsim.effects.holding.hold_step`: it sticks when the seed's response leaves its
tangential step at most 1e-3 of the step, i.e. when μ × depth reaches |Δ_t| less that),
so a right port printed with 6 digits could take the other state only when its margin
s = |Δ_t| − μ depth − 1e-3 |step| lies within the rounding's reach
(:mod:`clothsim.ports.held_first`). This prints, for drop-on-square (20 steps) and
drape-sphere (30 steps) at 25², the first contacts nearest the edge (a box's placement
keeps the tangential step, so its s is exact; a sphere's radial placement adds to it),
and vertex 186 of drop-on-square with the box's friction 0.3343, the case
tests/ports/test_held_causes.py constructs. Run from the repository root:
``.venv/bin/python -m benchmarks first_contact_margins`` (about 20 s of CPU).
"""

from __future__ import annotations

import numpy as np

from clothsim.scene import load_scene


def first_contacts(scene: str, frames: int, overrides=()) -> list[tuple]:
    """(step, obstacle, vertex, s [m]) of every first contact of the run."""
    sim = load_scene(scene, list(overrides)).build_simulation()
    found = []
    for e in sim.effects:
        if getattr(e, "contact", None) != "hold":
            continue
        correct = type(e).correct_positions

        def record(t, state, x, e=e, correct=correct):
            held = set(e._holding.vertices.tolist())
            x0 = state.positions
            index, p, n = e.contacts(x0, x)
            for j, i in enumerate(index):
                if int(i) in held:
                    continue
                depth = max(float((p[j] - x[i]) @ n[j]), 0.0)
                d = x[i] + depth * n[j] - x0[i]
                dt = float(np.linalg.norm(d - (d @ n[j]) * n[j]))
                s = dt - e.friction * depth - 1e-3 * float(np.linalg.norm(x[i] - x0[i]))
                found.append((state.step, e.kind, int(i), s))
            return correct(e, t, state, x)

        e.correct_positions = record
    for _ in range(frames):
        sim.step()
    return found


def main() -> list[str]:
    lines = []
    for scene, frames in (("drop-on-square", 20), ("drape-sphere", 30)):
        near = sorted(first_contacts(scene, frames), key=lambda f: abs(f[3]))[:3]
        lines.append(f"{scene} ({frames} steps), first contacts nearest the edge: " + "; ".join(
            f"vertex {v} on the {kind} in step {k} -> {k + 1}: s = {s:+.2e} m"
            for k, kind, v, s in near))
    edge = [f for f in first_contacts("drop-on-square", 11, ["effects[1].friction=0.3343"])
            if f[2] == 186]
    lines.append("drop-on-square, box friction 0.3343: " + "; ".join(
        f"vertex 186 in step {k} -> {k + 1}: s = {s:+.2e} m" for k, _, _, s in edge))
    for line in lines:
        print(line)
    return lines


if __name__ == "__main__":
    main()
