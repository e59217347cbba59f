""".clothsim.lock is never followed nor written through (a link, a hard link, a folder, a
FIFO: refused by name, the user's file unchanged), and no finished folder keeps it."""

import os

import pytest

from clothsim.cli import main
from clothsim.errors import InputError
from clothsim.io.lock import LOCK_NAME, FolderLock
from tests import test_reliability_folders as folders
from tests.test_reliability_folders import TINY

tiny = folders.tiny  # the fixture: a 3 x 3 scene file


def _plant(folder, how, target):
    lock = folder / LOCK_NAME
    if how == "symlink":
        lock.symlink_to(os.path.relpath(target, folder))
    elif how == "hardlink":
        os.link(target, lock)
    elif how == "folder":
        lock.mkdir()
    else:
        os.mkfifo(lock)


@pytest.mark.parametrize("how", ["symlink", "hardlink", "folder", "fifo"])
@pytest.mark.parametrize("command", ["run", "export"])
def test_a_planted_lock_file_is_refused_and_the_users_file_unchanged(tiny, tmp_path, capsys,
                                                                    how, command):
    user = tmp_path / "user.txt"
    user.write_text("thesis\n")
    out = tmp_path / "F"
    out.mkdir()
    _plant(out, how, user)
    extra = ["--no-preview"] if command == "run" else ["--frames", "1"]
    assert main([command, tiny, "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and str(out / LOCK_NAME) in err and "Error" not in err
    assert user.read_text() == "thesis\n"
    assert sorted(p.name for p in out.iterdir()) == [LOCK_NAME]  # nothing else written


def test_a_dangling_symlink_lock_creates_nothing_at_its_target(tmp_path):
    (tmp_path / "F").mkdir()
    (tmp_path / "F" / LOCK_NAME).symlink_to(tmp_path / "created-by-clothsim")
    with pytest.raises(InputError, match="symbolic link"):
        FolderLock(tmp_path / "F").acquire()
    assert not (tmp_path / "created-by-clothsim").exists()


@pytest.mark.parametrize("command", [["run", "--no-preview"], ["export", "--frames", "1"]])
def test_no_lock_file_stays_in_a_finished_folder(tiny, tmp_path, command):
    out = tmp_path / "F"
    assert main([command[0], tiny, "--out", str(out), *command[1:]]) == 0
    assert not (out / LOCK_NAME).exists()


def test_the_lock_file_goes_after_an_error_too(tiny, tmp_path):
    out = tmp_path / "F"
    assert main(["run", tiny, "--out", str(out), "--no-preview"]) == 0
    (tmp_path / "other.toml").write_text(TINY.replace('"tiny"', '"other"'))
    assert main(["run", str(tmp_path / "other.toml"), "--out", str(out), "--no-preview",
                 "--resume"]) == 2  # another scene's run: refused
    assert not (out / LOCK_NAME).exists()


def test_a_stale_lock_file_is_taken_over(tmp_path):
    """After SIGKILL the lock file stays; nobody holds its lock, so the next writer takes it
    and removes it at the end."""
    (tmp_path / LOCK_NAME).write_text("99999999 run\n")
    with FolderLock(tmp_path, "export") as lock:
        assert (tmp_path / LOCK_NAME).read_text() == f"{os.getpid()} export\n"
        assert lock.path.exists()
    assert not (tmp_path / LOCK_NAME).exists()


def test_a_lock_file_removed_by_its_holder_is_not_taken_twice(tmp_path):
    """The classic race of removing lock files: B opened the file A holds; A removes it and
    releases; C creates a new one. B's flock then succeeds on the removed file, so B must
    notice the name now points elsewhere and lock that (and be refused while C holds it)."""
    import fcntl

    a = FolderLock(tmp_path).acquire()
    fd_b = os.open(tmp_path / LOCK_NAME, os.O_RDWR)  # B opens before A removes
    a.release()
    with FolderLock(tmp_path, "export"):  # C
        fcntl.flock(fd_b, fcntl.LOCK_EX | fcntl.LOCK_NB)  # B's flock on the old file
        assert not FolderLock(tmp_path)._still_named(fd_b)
        with pytest.raises(InputError, match="another clothsim export"):
            FolderLock(tmp_path).acquire()  # B trying again: refused while C holds it
    os.close(fd_b)
