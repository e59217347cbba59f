"""Output folders: run and export write only into an empty folder or their own kind of
folder; anything else is refused naming the folder and the first foreign file, --force
writes anyway; export takes the same lock as run."""

import re

import numpy as np
import pytest

from clothsim.cli import main
from clothsim.errors import InputError
from clothsim.io.folders import FolderLock, claim_folder, folder_kind
from clothsim.ports.export import export_port
from clothsim.runner import run_scene

TINY = """
[scene]
name = "tiny"
frames = 2
fps = 30
[cloth]
resolution = [3, 3]
plane = "xy"
[springs]
structural = 200.0
[[effects]]
kind = "gravity"
"""


@pytest.fixture
def tiny(tmp_path):
    p = tmp_path / "tiny.toml"
    p.write_text(TINY)
    return str(p)


def _snapshot(folder):
    return {p.name: p.read_bytes() for p in folder.iterdir() if p.is_file()}


@pytest.mark.parametrize("name", ["trajectory.npz", "final.png", "notes.txt", "run.json"])
def test_run_refuses_a_users_folder_and_changes_nothing(tiny, tmp_path, capsys, name):
    out = tmp_path / "mine"
    out.mkdir()
    (out / name).write_bytes(b"the user's own data")
    before = _snapshot(out)
    for extra in ([], ["--resume"]):
        assert main(["run", tiny, "--out", str(out), "--no-preview", *extra]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and str(out) in err and name in err
        assert "--force" in err
    assert _snapshot(out) == before and sorted(p.name for p in out.iterdir()) == [name]


def test_force_writes_into_a_foreign_folder(tiny, tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("keep me")
    assert main(["run", tiny, "--out", str(out), "--no-preview", "--force"]) == 0
    assert (out / "notes.txt").read_text() == "keep me"  # a name clothsim does not write
    assert folder_kind(out) == "run"
    assert main(["run", tiny, "--out", str(out), "--no-preview"]) == 0  # now its own


def test_run_writes_again_into_its_own_folder_beside_an_export(tiny, tmp_path):
    out = tmp_path / "run"
    assert main(["export", tiny, "--out", str(out / "export"), "--frames", "1",
                 "--iterate-steps", "0"]) == 0
    assert main(["run", tiny, "--out", str(out), "--no-preview"]) == 0
    assert main(["run", tiny, "--out", str(out), "--no-preview"]) == 0
    assert folder_kind(out / "export") == "export"


def test_export_refuses_a_run_folder_and_a_foreign_folder(tiny, tmp_path, capsys):
    run = tmp_path / "run"
    assert main(["run", tiny, "--out", str(run), "--no-preview"]) == 0
    traj = (run / "trajectory.npz").read_bytes()
    assert main(["export", tiny, "--out", str(run)]) == 2
    err = capsys.readouterr().err
    assert "holds a clothsim run, not a clothsim export" in err
    assert (run / "trajectory.npz").read_bytes() == traj
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "positions.txt").write_text("1 2 3\n")
    assert main(["export", tiny, "--out", str(mine)]) == 2
    assert "positions.txt" in capsys.readouterr().err
    assert (mine / "positions.txt").read_text() == "1 2 3\n"
    # an export folder is exported into again
    assert main(["export", tiny, "--out", str(tmp_path / "e"), "--frames", "1"]) == 0
    assert main(["export", tiny, "--out", str(tmp_path / "e"), "--frames", "1"]) == 0
    # and a run is refused in it
    assert main(["run", tiny, "--out", str(tmp_path / "e"), "--no-preview"]) == 2


def test_export_into_a_running_runs_folder_is_refused_even_with_force(tiny, tmp_path):
    run = tmp_path / "run"
    run_scene(tiny, run, preview=False)
    traj = (run / "trajectory.npz").read_bytes()
    with FolderLock(run):  # a run in progress holds this lock
        with pytest.raises(InputError, match="another clothsim run"):
            export_port(tiny_scene(tiny), run, frames=1, force=True)
        with pytest.raises(InputError, match="another clothsim run"):
            run_scene(tiny, run, preview=False)
    assert (run / "trajectory.npz").read_bytes() == traj


@pytest.mark.parametrize("kind, said", [("export", "another clothsim export (pid "),
                                        ("accuracy", "another clothsim accuracy study (pid ")])
def test_a_refused_lock_names_what_holds_it(tiny, tmp_path, kind, said):
    import os

    folder = tmp_path / "f"
    folder.mkdir()
    with FolderLock(folder, kind):
        with pytest.raises(InputError, match=re.escape(f"{folder}: {said}{os.getpid()})")):
            run_scene(tiny, folder, preview=False, force=True)
    with pytest.raises(ValueError, match="kind"):
        FolderLock(folder, "study")


def tiny_scene(path):
    from clothsim.scene import load_scene

    return load_scene(path)


def test_out_empty_or_a_file_is_refused(tiny, tmp_path, capsys):
    assert main(["run", tiny, "--out", "", "--no-preview"]) == 2
    assert "--out: empty" in capsys.readouterr().err
    f = tmp_path / "file.txt"
    f.write_text("x")
    for cmd in (["run", tiny, "--no-preview"], ["export", tiny]):
        assert main([*cmd, "--out", str(f)]) == 2
        err = capsys.readouterr().err
        assert "is not a folder" in err and str(f) in err and "Error" not in err
    assert f.read_text() == "x"


def test_claim_folder_kinds(tmp_path):
    assert claim_folder(tmp_path / "new", "run") == tmp_path / "new"
    (tmp_path / "e").mkdir()
    (tmp_path / "e" / ".clothsim.lock").write_text("")
    claim_folder(tmp_path / "e", "export")  # only a lock file: empty
    (tmp_path / "e" / "run.json").write_text('{"not": "clothsim"}')
    with pytest.raises(InputError, match="'run.json'"):
        claim_folder(tmp_path / "e", "run")
    np.save(tmp_path / "e" / "x.npy", np.zeros(3))
    with pytest.raises(InputError, match="and 1 more"):
        claim_folder(tmp_path / "e", "export")
