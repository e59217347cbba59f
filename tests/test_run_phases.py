"""benchmarks.run_phases: the phases of a real (small) `clothsim run`, each counted."""

from __future__ import annotations

import clothsim as cs
from benchmarks import run_phases


def test_the_phases_of_a_small_run_are_all_there_and_counted():
    frames = 2
    r = run_phases.phases(9, frames, ["--no-preview"], frame_process=False)
    assert r["rc"] == 0
    rows = {name: (calls, wall, cpu) for name, calls, wall, cpu in run_phases.summary(r)}
    substeps = cs.load_scene("hanging").substeps
    assert rows["step"][0] == frames * substeps
    assert rows["frame write (all)"][0] == frames + 1
    assert rows["  frame .vtu + .pvd"][0] == frames + 1
    assert rows["factorization (CHOLMOD)"][0] == 1
    assert "    .vtu file (frame process, waited for)" not in rows   # 81 vertices: here
    assert rows["trajectory store (run's thread)"][0] == frames + 1
    assert "  trajectory.npz" not in rows            # written once, beside the last frame
    for name in ("imports", "model build", "final files (npz, run.json)", "  step 1",
                 "last frame: npz built, then waited for",
                 "  trajectory.npz beside the last frame"):
        calls, wall, cpu = rows[name]
        assert calls == 1 and wall >= 0 and cpu >= 0, name
    table = run_phases.table(r)
    assert table[0].startswith("| phase |") and table[-1].startswith("| whole process |")
    assert len(table) == len(rows) + 3
