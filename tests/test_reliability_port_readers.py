"""Malformed inputs to the port commands give one line naming the file (and the line of a
text file): exit 1 or 2, never a traceback or Python exception text; the Matrix Market
reader is clothsim's own strict one."""

import io as _io
import pickle
import zipfile

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from clothsim.cli import main
from clothsim.errors import InputError
from clothsim.io import read_matrix

PYTHON_TEXT = ("Traceback", "Error:", "EOFError", "allow_pickle", "IndexError",
               "UnicodeDecodeError", "MemoryError", "pickled data", "Errno")


def _npy_bytes(a, **kw):
    b = _io.BytesIO()
    np.save(b, a, **kw)
    return b.getvalue()


def _npz_bytes(**arrays):
    b = _io.BytesIO()
    np.savez(b, **arrays)
    return b.getvalue()


GOOD = np.zeros((2, 3, 3))
MALFORMED = {
    "truncated.npy": _npy_bytes(GOOD)[:-20],
    "header-only.npy": _npy_bytes(GOOD)[:10],
    "empty.npy": b"",
    "pickled.npy": _npy_bytes(np.array([{"a": 1}], dtype=object), allow_pickle=True),
    "complex.npy": _npy_bytes(np.ones((2, 3, 3), complex)),
    "strings.npy": _npy_bytes(np.array([["a", "b", "c"]])),
    "zero.npy": _npy_bytes(np.zeros((0, 3, 3))),
    "npz-as.npy": _npz_bytes(positions=GOOD),
    "garbage.npz": b"PK\x03\x04 this is not a zip",
    "truncated.npz": _npz_bytes(positions=GOOD)[:200],
    "pickle.npz": _npz_bytes(positions=np.array([None, 1], dtype=object)),
    "binary.txt": bytes(range(256)),
    "word.txt": b"1 2 3\n4 five 6\n",
    "ragged.txt": b"1 2 3 4 5 6\n1 2 3\n",
    "four.txt": b"1 2 3 4\n",
    "only-comments.txt": b"# nothing\n",
    "garbage.pvd": b"<VTKFile><Collection><DataSet file='nope.vtu' timestep='x'/>",
    "raw.f64": b"\x00" * 7,
    "pickle-bytes.npy": pickle.dumps([1, 2, 3]),
}


@pytest.mark.parametrize("name", sorted(MALFORMED))
def test_compare_malformed_trajectory_is_one_line(name, tmp_path, capsys):
    (tmp_path / name).write_bytes(MALFORMED[name])
    np.save(tmp_path / "ref.npy", GOOD)
    extra = ["--vertices", "3"] if name.endswith(".f64") else []
    for argv in (["compare", str(tmp_path / name), str(tmp_path / "ref.npy"), *extra],
                 ["compare", str(tmp_path / "ref.npy"), str(tmp_path / name), *extra],
                 ["check", "hanging", str(tmp_path / name)]):
        assert main(argv) in (1, 2)
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and name in err, err
        assert not any(t in err for t in PYTHON_TEXT), err


def test_text_errors_name_the_line(tmp_path):
    from clothsim.ports.formats import read_trajectory

    (tmp_path / "a.txt").write_text("# header\n1 2 3\n4 five 6\n")
    with pytest.raises(InputError, match=r"a\.txt: line 3: not a number: 'five'"):
        read_trajectory(tmp_path / "a.txt")


MTX = {
    "header.mtx": "%%MatrixMarket matrix coordinate complex general\n1 1 1\n1 1 1\n",
    "noheader.mtx": "1 1 1\n1 1 1\n",
    "size.mtx": "%%MatrixMarket matrix coordinate real general\n2 x 1\n1 1 1\n",
    "count.mtx": "%%MatrixMarket matrix coordinate real general\n2 2 3\n1 1 1\n",
    "index.mtx": "%%MatrixMarket matrix coordinate real general\n2 2 1\n3 1 1\n",
    "zero-index.mtx": "%%MatrixMarket matrix coordinate real general\n2 2 1\n0 1 1\n",
    "value.mtx": "%%MatrixMarket matrix coordinate real general\n2 2 1\n1 1 abc\n",
    "huge.mtx": "%%MatrixMarket matrix coordinate real general\n"
                "99999999999 99999999999 1\n1 1 1\n",
    "array.mtx": "%%MatrixMarket matrix array real general\n2 2\n1\n2\n3\n",
    "binary.mtx": "%%MatrixMarket matrix coordinate real general\n\xff\xfe\n",
    "empty.mtx": "",
}


@pytest.mark.parametrize("name", sorted(MTX))
def test_malformed_matrix_market_is_one_line(name, tmp_path, capsys):
    (tmp_path / name).write_bytes(MTX[name].encode("latin-1"))
    (tmp_path / "ok.mtx").write_text("%%MatrixMarket matrix coordinate real general\n"
                                     "2 2 1\n1 1 1\n")
    with pytest.raises(InputError, match=name):
        read_matrix(tmp_path / name)
    assert main(["compare", str(tmp_path / name), str(tmp_path / "ok.mtx")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and not any(t in err for t in PYTHON_TEXT), err


def test_matrix_market_symmetric_and_array_read_back(tmp_path):
    (tmp_path / "s.mtx").write_text("%%MatrixMarket matrix coordinate real symmetric\n%\n"
                                    "2 2 2\n1 1 2\n2 1 -1\n")
    assert read_matrix(tmp_path / "s.mtx").toarray().tolist() == [[2, -1], [-1, 0]]
    (tmp_path / "a.mtx").write_text("%%MatrixMarket matrix array real general\n2 2\n1\n2\n3\n4\n")
    assert read_matrix(tmp_path / "a.mtx").tolist() == [[1, 3], [2, 4]]


def test_diff_model_malformed_folder_names_file_and_line(tmp_path, capsys):
    d = tmp_path / "model"
    d.mkdir()
    (d / "x0.txt").write_text("0 0 0 1 0 0\n")
    (d / "springs.txt").write_text("0 1 10 1\n0 1 ten 1\n")
    assert main(["diff-model", str(d), str(d)]) == 2
    err = capsys.readouterr().err.strip()
    assert "springs.txt: line 2: not a number: 'ten'" in err and len(err.splitlines()) == 1
    (d / "springs.txt").write_text("0 1 10\n")  # three columns: shapes do not fit
    assert main(["diff-model", str(d), str(d)]) in (1, 2)
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.binary(max_size=300), suffix=st.sampled_from([".npy", ".npz", ".txt", ".csv",
                                                             ".mtx", ".pvd", ".f64"]),
       base=st.sampled_from(["", "npy", "npz", "mtx"]))
def test_fuzz_port_readers_one_line(tmp_path, capsys, data, suffix, base):
    """Random bytes, optionally after a valid file's start: one line, exit 1 or 2."""
    head = {"": b"", "npy": _npy_bytes(GOOD)[:128], "npz": _npz_bytes(positions=GOOD)[:60],
            "mtx": b"%%MatrixMarket matrix coordinate real general\n2 2 1\n"}[base]
    p = tmp_path / f"fuzz{suffix}"
    p.write_bytes(head + data)
    ref = tmp_path / ("ref.mtx" if suffix == ".mtx" else "ref.npy")
    if suffix == ".mtx":
        ref.write_text("%%MatrixMarket matrix coordinate real general\n2 2 1\n1 1 1\n")
    else:
        np.save(ref, GOOD)
    code = main(["compare", str(p), str(ref), "--vertices", "3", "--no-table"])
    err = capsys.readouterr().err.strip()
    assert code in (0, 1, 2)
    if code == 2 or err:
        assert len(err.splitlines()) == 1 and not any(t in err for t in PYTHON_TEXT), err


def test_zip_member_that_is_not_an_array(tmp_path, capsys):
    with zipfile.ZipFile(tmp_path / "z.npz", "w") as z:
        z.writestr("positions.npy", b"\x93NUMPY garbage")
    np.save(tmp_path / "ref.npy", GOOD)
    assert main(["compare", str(tmp_path / "z.npz"), str(tmp_path / "ref.npy")]) == 2
    err = capsys.readouterr().err.strip()
    assert "z.npz" in err and not any(t in err for t in PYTHON_TEXT), err
