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
    assert rows["first factorization (before frame 0)"][0] == 1   # Simulation.prepare
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


def test_the_parts_of_one_step_add_up_to_it():
    r = run_phases.step_parts(9, repeats=1)
    assert r["iterations"] == cs.load_scene("hanging").data["solver"]["iterations"]
    for key, _label, _calls in run_phases.PARTS:
        assert r[key] >= 0, key
    rows = run_phases.parts_table(r)
    assert len(rows) == 2 + len(run_phases.PARTS) + 2
    assert rows[-2].startswith("| other:") and rows[-1].startswith("| whole step")
    # each part's per-step figure is its per-call figure times its calls
    solve = next(row for row in rows if row.startswith("| global step"))
    assert f"| {r['iterations']} |" in solve


def test_runs_with_and_without_what_goes_beside_the_steps(tmp_path):
    """--beside's bare run: every step counted with its page faults, empty frame files."""
    substeps = cs.load_scene("hanging").substeps
    r = run_phases.phases(9, 2, ["--no-preview"], bare=True)
    assert r["rc"] == 0 and r["children_cpu"] == 0
    assert len(r["steps_ru"]) == 2 * substeps
    assert all(t >= 0 and f >= 0 for t, f in r["steps_ru"])
    row = run_phases.beside_rows(1, "0.5", "neither", r)
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[:3] == ["1", "0.5", "neither"] and len(cells[3].split()) == 2 * substeps
    assert cells[6] == "0.00 s"
