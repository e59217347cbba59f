"""compare: a trajectory shorter or longer than the reference fails, naming both lengths."""

import numpy as np
import pytest

from clothsim.cli import main
from clothsim.ports.compare import compare_trajectories


@pytest.fixture
def ref(tmp_path):
    rng = np.random.default_rng(3)
    traj = rng.normal(size=(31, 4, 3))
    np.save(tmp_path / "ref.npy", traj)
    return traj


@pytest.mark.parametrize("frames", [1, 30, 32])
def test_other_frame_count_fails_naming_both(ref, tmp_path, capsys, frames):
    a = ref[:frames] if frames <= 31 else np.concatenate([ref, ref[-1:]])
    np.save(tmp_path / "a.npy", a)
    assert main(["compare", str(tmp_path / "a.npy"), str(tmp_path / "ref.npy"),
                 "--no-table"]) == 1
    out = capsys.readouterr().out
    line = [x for x in out.splitlines() if x.startswith("FAIL")][0]
    assert f"{frames} frames" in line and "31" in line


def test_single_frame_forms_fail(ref, tmp_path, capsys):
    np.save(tmp_path / "one.npy", ref[0])  # an (n, 3) array
    np.savetxt(tmp_path / "one.txt", ref[:1].reshape(1, -1))  # a one-frame text file
    for name in ("one.npy", "one.txt"):
        assert main(["compare", str(tmp_path / name), str(tmp_path / "ref.npy"),
                     "--no-table"]) == 1
        assert "1 frames" in capsys.readouterr().out


def test_frames_on_request_compares_only_n(ref, tmp_path):
    np.save(tmp_path / "a.npy", ref[:5])
    r = compare_trajectories(tmp_path / "a.npy", tmp_path / "ref.npy", frames=5)
    assert r.passed and r.frames == 5 and r.frame_counts is None
    r = compare_trajectories(tmp_path / "a.npy", tmp_path / "ref.npy")
    assert not r.passed and r.frame_counts == (5, 31)
    assert "5 frames" in r.summary() and "31" in r.summary()


def test_equal_counts_still_pass(ref, tmp_path):
    assert compare_trajectories(tmp_path / "ref.npy", tmp_path / "ref.npy").passed


def test_kappa_from_a_scene_of_another_size_is_refused(tmp_path, capsys):
    from clothsim.cli import main

    assert main(["export", "hanging", "--frames", "2", "--iterate-steps", "0",
                 "--out", str(tmp_path / "e")]) == 0
    capsys.readouterr()
    code = main(["compare", str(tmp_path / "e"), str(tmp_path / "e"), "--precision", "float32",
                 "--scene", "drop-on-square"])
    err = capsys.readouterr().err
    assert code != 0 and "κ comes from a scene of 625 vertices" in err and "441" in err
