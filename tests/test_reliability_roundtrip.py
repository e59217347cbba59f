"""Every file clothsim writes, clothsim reads back: a springs-only files cloth and a
one-vertex cloth run, resume and compare against themselves."""

import pytest

from clothsim.cli import main

CASES = {
    "strand": ("0 0 0\n1 0 0\n2 0 0\n", '[springs]\ntable = "s.txt"\n', "0 1 10 1\n1 2 10 1\n",
               '[[effects]]\nkind = "pin"\nvertices = [0]\n'),
    "one-vertex": ("0 0 0\n", "", None, ""),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_run_resume_compare(case, tmp_path):
    x, springs, table, pins = CASES[case]
    (tmp_path / "x.txt").write_text(x)
    if table:
        (tmp_path / "s.txt").write_text(table)
    p = tmp_path / "c.toml"
    p.write_text('[scene]\nframes = 3\n[cloth]\nshape = "files"\nvertices = "x.txt"\n'
                 f'{springs}[[effects]]\nkind = "gravity"\n{pins}')
    out = tmp_path / "out"
    assert main(["run", str(p), "--out", str(out), "--frames", "2", "--no-preview"]) == 0
    assert main(["run", str(p), "--out", str(out), "--resume", "--no-preview"]) == 0
    assert main(["compare", str(out / "trajectory.pvd"), str(out / "trajectory.npz"),
                 "--no-table"]) == 0
    assert main(["compare", str(out), str(out), "--field", "velocities", "--no-table"]) == 0
