"""Files read through a cache are read again after an edit (issue 34, item 6).

``load_scene(json).build_model()`` returned the old mesh after the OBJ an assignment JSON
names was edited in the same process: the cache was keyed on the JSON's path and mtime
only. Both caches (assignment, spring table) are now keyed on every file read and on
:func:`clothsim.io.common.file_stamp` (mtime_ns, size, ctime_ns, inode).
"""

from __future__ import annotations

import os

import numpy as np

from clothsim.io.common import file_stamp
from clothsim.scene import load_scene

OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"


def _assignment(tmp_path, obj=OBJ):
    (tmp_path / "m.obj").write_text(obj)
    (tmp_path / "a.json").write_text('{"obj": "m.obj", "b": [1], "k": 100, "m": 1}')
    return tmp_path / "a.json"


def test_editing_the_obj_of_an_assignment_is_seen_in_the_same_process(tmp_path):
    p = _assignment(tmp_path)
    first = load_scene(p).build_model().mesh.vertices.copy()
    (tmp_path / "m.obj").write_text(OBJ.replace("v 1 0 0", "v 2 0 0"))
    second = load_scene(p).build_model().mesh.vertices
    assert first[1, 0] == 1.0 and second[1, 0] == 2.0


def test_an_edit_that_keeps_size_and_mtime_is_seen_too(tmp_path):
    """Same size, modification time put back (a copy with -p, a coarse clock)."""
    p = _assignment(tmp_path)
    obj = tmp_path / "m.obj"
    before = os.stat(obj)
    assert load_scene(p).build_model().mesh.vertices[1, 0] == 1.0
    obj.write_text(OBJ.replace("v 1 0 0", "v 3 0 0"))
    os.utime(obj, ns=(before.st_atime_ns, before.st_mtime_ns))
    assert os.stat(obj).st_size == before.st_size
    assert os.stat(obj).st_mtime_ns == before.st_mtime_ns
    assert load_scene(p).build_model().mesh.vertices[1, 0] == 3.0


def test_replacing_the_obj_the_json_names_is_seen(tmp_path):
    p = _assignment(tmp_path)
    assert load_scene(p).build_model().vertex_count == 3
    (tmp_path / "m2.obj").write_text(OBJ + "v 1 1 0\nf 2 4 3\n")
    p.write_text('{"obj": "m2.obj", "b": [1], "k": 100, "m": 1}')
    assert load_scene(p).build_model().vertex_count == 4


def test_editing_a_spring_table_is_seen_in_the_same_process(tmp_path):
    (tmp_path / "t.txt").write_text("0 8 50 0.5\n")
    (tmp_path / "s.toml").write_text('[cloth]\nresolution = [3, 3]\n[springs]\n'
                                     'structural = 10\ntable = "t.txt"\n')
    k = load_scene(tmp_path / "s.toml").build_model().springs.spring_stiffness
    assert k[-1] == 50.0
    before = os.stat(tmp_path / "t.txt")
    (tmp_path / "t.txt").write_text("0 8 70 0.5\n")
    os.utime(tmp_path / "t.txt", ns=(before.st_atime_ns, before.st_mtime_ns))
    k = load_scene(tmp_path / "s.toml").build_model().springs.spring_stiffness
    assert k[-1] == 70.0


def test_file_stamp_of_a_missing_file_is_none_and_of_a_file_a_tuple(tmp_path):
    assert file_stamp(tmp_path / "nope") is None
    (tmp_path / "f").write_text("x")
    assert isinstance(file_stamp(tmp_path / "f"), tuple)
    assert np.ndim(file_stamp(tmp_path / "f")) == 1
