"""Run files: the streamed trajectory store, trajectory.npz, run.json and the folder lock
(clothsim.io.runfiles)."""

import json
import os

import numpy as np
import pytest

from clothsim.errors import InputError
from clothsim.io.runfiles import FolderLock, TrajectoryStore, read_json, write_json


def test_store_assembles_the_npz_numpy_would_write(tmp_path):
    rng = np.random.default_rng(7)
    x, v = rng.standard_normal((6, 5, 3)) / 3, rng.standard_normal((6, 5, 3)) * 1e-300
    store = TrajectoryStore(tmp_path, 5)
    for k in range(6):
        store.append(x[k], v[k])
    extra = {"time": np.arange(4) / 30, "triangles": np.arange(6).reshape(2, 3)}
    store.write_npz(tmp_path / "cut.npz", 4, extra)  # fewer frames than stored
    store.write_npz(tmp_path / "all.npz", 6, extra)
    assert np.array_equal(store.view("positions", 6), x)
    store.close()
    assert not list(tmp_path.glob(".*.f64"))
    np.savez(tmp_path / "numpy.npz", positions=x[:4], velocities=v[:4], **extra)
    with np.load(tmp_path / "cut.npz") as a, np.load(tmp_path / "numpy.npz") as b:
        assert a.files == b.files
        for key in a.files:
            assert a[key].dtype == b[key].dtype and np.array_equal(a[key], b[key]), key
    with np.load(tmp_path / "all.npz") as a:
        assert np.array_equal(a["positions"], x) and np.array_equal(a["velocities"], v)
    with pytest.raises(InputError, match=r"^velocities: expected shape \(5, 3\)"):
        TrajectoryStore(tmp_path, 5).append(x[0], v[0, :4])


def test_run_json_is_strict_and_unreadable_json_reads_as_none(tmp_path):
    write_json(tmp_path / "run.json", {"a": float("nan"), "b": np.arange(3), "c": [np.inf]})
    assert json.loads((tmp_path / "run.json").read_text()) == \
        {"a": "nan", "b": [0, 1, 2], "c": ["inf"]}
    (tmp_path / "bad.json").write_text('{"status": "runn')
    (tmp_path / "list.json").write_text("[1, 2]")
    assert read_json(tmp_path / "bad.json") is None and read_json(tmp_path / "list.json") is None
    assert read_json(tmp_path / "absent.json") is None


def test_folder_lock_is_exclusive_and_names_the_holder(tmp_path):
    with FolderLock(tmp_path):
        with pytest.raises(InputError) as info:
            FolderLock(tmp_path).acquire()
        assert str(info.value).startswith(f"{tmp_path}: another clothsim run "
                                          f"(pid {os.getpid()}) is writing")
    with FolderLock(tmp_path):  # released: free again
        pass
