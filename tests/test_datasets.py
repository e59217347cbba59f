"""The data sets: the shipped one unpacks whole, verified, once; the third-party one is
downloaded (from a local server here: the real address cannot be reached from the tests),
checked against its pinned SHA-256, cached, and never half-written; ``clothsim data``
lists, fetches and locates; offline, one line says how to get what is missing."""

from __future__ import annotations

import dataclasses
import hashlib
import http.server
import os
import tarfile
import threading
from pathlib import Path

import pytest

from clothsim import cli, datasets
from clothsim.datasets import DataUnavailableError, registry, store
from clothsim.scene import SceneError, load_scene

from .data_sets import SKIP_ASSIGNMENT

REPO = Path(__file__).resolve().parents[1]
FILES = {"a.json": b'{"obj": "a.obj", "b": [1], "k": 10, "m": 1}\n',
         "a.obj": b"v 0 0 0\nv 1 0 0\nf 1 2\n", "sub/b.txt": b"0 0 0\n"}


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """An empty cache folder, no CLOTHSIM_DATA."""
    monkeypatch.setenv("CLOTHSIM_CACHE", str(tmp_path / "cache"))
    monkeypatch.delenv("CLOTHSIM_DATA", raising=False)
    return tmp_path / "cache"


class Server:
    """A local HTTP server of a folder, counting the requests it answers."""

    def __init__(self, root: Path):
        self.root, self.requests = root, []
        server = self

        class Handler(http.server.SimpleHTTPRequestHandler):
            def __init__(self, *a, **kw):
                super().__init__(*a, directory=str(root), **kw)

            def log_message(self, *args):  # quiet
                server.requests.append(self.path)

        self.httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.url = f"http://127.0.0.1:{self.httpd.server_address[1]}/files/"
        self.thread = threading.Thread(target=self.httpd.serve_forever, daemon=True)
        self.thread.start()

    def stop(self):
        self.httpd.shutdown()
        self.httpd.server_close()


@pytest.fixture
def server(tmp_path):
    root = tmp_path / "www"
    for name, data in FILES.items():
        (root / "files" / name).parent.mkdir(parents=True, exist_ok=True)
        (root / "files" / name).write_bytes(data)
    s = Server(root)
    yield s
    s.stop()


@pytest.fixture
def remote(server, monkeypatch):
    """A third-party data set ``test-set`` served by ``server``, hashes pinned."""
    ds = registry.Dataset(name="test-set", title="test files", source="a local server",
                          url=server.url, loose_folder=True,
                          files={n: hashlib.sha256(d).hexdigest() for n, d in FILES.items()})
    monkeypatch.setitem(registry.DATASETS, "test-set", ds)
    return ds


# ---------------------------------------------------------------- the shipped data set
def test_shipped_data_unpacks_once_whole_and_verified(cache):
    st = datasets.status("liu13-port")
    assert st.present and st.origin == "package" and st.missing == 9
    folder = datasets.locate("liu13-port")
    assert folder == cache / "liu13-port" and datasets.status("liu13-port").origin == "cache"
    assert datasets.changed_files("liu13-port", folder) == []
    assert "chunleili/fast_mass_spring" in (folder / "README.md").read_text()
    assert [p.name for p in cache.iterdir()] == ["liu13-port"]  # no temporary left
    stamp = (folder / datasets.STAMP).stat().st_mtime_ns
    assert datasets.locate("liu13-port") == folder
    assert (folder / datasets.STAMP).stat().st_mtime_ns == stamp  # not unpacked again
    # the archive holds exactly the text files the README describes: 61 frames of 3n numbers
    lines = (folder / "default-scene" / "positions.txt").read_text().splitlines()
    assert len(lines) == 61 and len(lines[0].split()) == 3 * 441


def test_a_damaged_or_stale_unpacking_is_replaced(cache):
    folder = datasets.locate("liu13-port")
    x0 = folder / "default-scene" / "x0.txt"
    x0.write_text("0 0 0\n")
    assert datasets.changed_files("liu13-port", folder) == ["default-scene/x0.txt"]
    assert datasets.fetch("liu13-port") == folder  # fetch verifies every file
    assert datasets.changed_files("liu13-port", folder) == []
    (folder / datasets.STAMP).write_text("an older archive\n")
    assert datasets.status("liu13-port").origin == "package"
    datasets.locate("liu13-port")
    assert store.stamp(folder) == store.archive_digest(registry.LIU13)


def test_a_failed_unpacking_leaves_nothing(cache, monkeypatch):
    def broken(self, *a, **kw):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(tarfile.TarFile, "extractall", broken)
    with pytest.raises(DataUnavailableError) as info:
        datasets.locate("liu13-port")
    assert str(info.value) == (f"data set liu13-port: cannot unpack it into "
                               f"{cache / 'liu13-port'} (No space left on device); set "
                               f"CLOTHSIM_CACHE to a writable folder")
    assert list(cache.iterdir()) == []


def test_two_processes_unpacking_at_once_both_get_the_whole_folder(cache):
    import subprocess
    import sys

    code = ("from clothsim import datasets; from clothsim.datasets import store; "
            "f = datasets.locate('liu13-port'); "
            "print(f, store.changed(datasets.dataset('liu13-port'), f))")
    env = {**os.environ, "CLOTHSIM_CACHE": str(cache)}
    procs = [subprocess.Popen([sys.executable, "-c", code], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for _ in range(3)]
    outs = [p.communicate(timeout=300) for p in procs]
    assert all(p.returncode == 0 for p in procs), [e for _, e in outs]
    assert {o.strip() for o, _ in outs} == {f"{cache / 'liu13-port'} []"}
    assert [p.name for p in cache.iterdir()] == ["liu13-port"]


def test_unpacking_into_a_named_folder(tmp_path, cache, monkeypatch):
    out = datasets.fetch("liu13-port", into=tmp_path / "mine")
    assert out == tmp_path / "mine" / "liu13-port" and not (cache / "liu13-port").exists()
    monkeypatch.setenv("CLOTHSIM_DATA", str(tmp_path / "mine"))
    st = datasets.status("liu13-port")
    assert st.origin == "CLOTHSIM_DATA" and st.folder == out


# ---------------------------------------------------------------- the third-party data set
def test_download_checks_every_file_and_caches_it(cache, remote, server, monkeypatch):
    monkeypatch.delenv("CLOTHSIM_OFFLINE")
    assert not datasets.status("test-set").present
    folder = datasets.locate("test-set")
    assert folder == cache / "test-set"
    assert {str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file()} == set(FILES)
    assert (folder / "sub" / "b.txt").read_bytes() == FILES["sub/b.txt"]
    assert len(server.requests) == 3 and datasets.status("test-set").present
    datasets.locate("test-set")
    datasets.fetch("test-set")  # files already there and right: no download
    assert len(server.requests) == 3
    (folder / "a.obj").write_bytes(b"changed\n")  # a damaged file is fetched again
    datasets.fetch("test-set")
    assert (folder / "a.obj").read_bytes() == FILES["a.obj"] and len(server.requests) == 4


def test_a_file_that_fails_its_sha256_is_refused_and_not_kept(cache, remote, server,
                                                              monkeypatch):
    (server.root / "files" / "a.obj").write_bytes(b"v 0 0 0\nv 2 0 0\nf 1 2\n")
    with pytest.raises(DataUnavailableError) as info:
        datasets.fetch("test-set")
    msg = str(info.value)
    assert "\n" not in msg and "could not download a.obj" in msg
    assert "does not match its pinned SHA-256" in msg
    assert "`clothsim data fetch test-set`" in msg and "CLOTHSIM_DATA" in msg
    assert not (cache / "test-set" / "a.obj").exists()
    assert not [p for p in (cache / "test-set").rglob("*") if "a.obj" in p.name]


def test_no_server_and_a_missing_file_are_one_line_each(cache, remote, server):
    (server.root / "files" / "sub" / "b.txt").unlink()
    with pytest.raises(DataUnavailableError, match=r"could not download sub/b.txt .*HTTP 404"):
        datasets.fetch("test-set")
    server.stop()
    with pytest.raises(DataUnavailableError, match=r"\(no connection\); run `clothsim data"):
        datasets.fetch("test-set", into=cache.parent / "other")
    assert not (cache.parent / "other" / "test-set").exists()  # nothing half made


def test_offline_nothing_is_downloaded_on_first_use(cache, remote, server):
    assert os.environ["CLOTHSIM_OFFLINE"] == "1"  # the suite's setting (conftest.py)
    with pytest.raises(DataUnavailableError) as info:
        datasets.locate("test-set")
    assert str(info.value) == ("data set test-set is not downloaded (CLOTHSIM_OFFLINE is "
                               "set); run `clothsim data fetch test-set` with a network "
                               "connection, or set CLOTHSIM_DATA to a folder holding a copy "
                               "(a checkout's data/ folder)")
    assert server.requests == []
    datasets.fetch("test-set")  # asking for it on purpose downloads
    assert datasets.locate("test-set") == cache / "test-set"


def test_a_mirror_url_and_a_named_folder_from_the_command_line(tmp_path, cache, remote,
                                                                server, capsys, monkeypatch):
    ds = dataclasses.replace(remote, url="http://127.0.0.1:9/")
    monkeypatch.setitem(registry.DATASETS, "test-set", ds)  # its own URL is dead
    assert cli.main(["data", "fetch", "test-set", "--into", str(tmp_path / "d"),
                     "--url", server.url.rstrip("/")]) == 0
    assert capsys.readouterr().out == f"test-set: 3 files in {tmp_path / 'd' / 'test-set'}\n"
    monkeypatch.setenv("CLOTHSIM_DATA", str(tmp_path / "d"))
    assert cli.main(["data", "path", "test-set/sub/b.txt"]) == 0
    assert capsys.readouterr().out == f"{tmp_path / 'd' / 'test-set' / 'sub' / 'b.txt'}\n"


def test_a_user_folder_is_used_as_it_is(tmp_path, cache, remote, monkeypatch):
    own = tmp_path / "checkout" / "data"  # the assignment's own data/ folder, edited
    own.mkdir(parents=True)
    (own / "a.json").write_bytes(FILES["a.json"].replace(b"10", b"20"))
    monkeypatch.setenv("CLOTHSIM_DATA", str(own))
    st = datasets.status("test-set")
    assert (st.folder, st.origin, st.present) == (own, "CLOTHSIM_DATA", True)
    assert datasets.locate("test-set") == own
    assert datasets.changed_files("test-set", own) == ["a.json", "a.obj", "sub/b.txt"]


# ---------------------------------------------------------------- the command line
def test_data_list_says_what_where_and_whether(cache, capsys):
    assert cli.main(["data", "list"]) == 0
    out = capsys.readouterr().out
    assert "liu13-port   in the package (unpacked on first use)" in out
    assert f"folder: {cache / 'liu13-port'}" in out
    assert "jacobson-a8  missing 10 of its files: clothsim data fetch jacobson-a8" in out
    assert registry.JACOBSON_COMMIT[:7] in out
    assert cli.main(["data", "fetch", "liu13-port"]) == 0
    capsys.readouterr()
    assert cli.main(["data", "list", "--verify"]) == 0
    assert "liu13-port   ready; all 9 files match their SHA-256" in capsys.readouterr().out


def test_data_path_and_its_errors(cache, capsys):
    assert cli.main(["data", "path", "liu13-port/default-scene"]) == 0
    assert capsys.readouterr().out == f"{cache / 'liu13-port' / 'default-scene'}\n"
    for bad, code, msg in (("liu13-port/nope", 2, "no such file or folder in data set"),
                           ("liu13-port/../../x", 2, "no such file or folder in data set"),
                           ("liu13", 2, "data set 'liu13' is unknown; known: liu13-port, "
                                        "jacobson-a8")):
        assert cli.main(["data", "path", bad]) == code
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and msg in err, err
    assert cli.main(["data"]) == 2
    assert cli.main(["data", "fetch", "liu13-port", "nope", "--into",
                     str(cache.parent / "x")]) == 2
    assert not (cache.parent / "x").exists()  # every name is checked before any fetch


def test_data_arguments_of_other_commands(cache, capsys):
    scene = str(REPO / "examples" / "ports" / "liu13-default.toml")
    assert cli.main(["check", scene, "data:liu13-port/default-scene", "--steps", "2"]) == 0
    assert capsys.readouterr().out.startswith("PASS: 2 steps agree")
    assert cli.main(["check", scene, "data:liu13-port/nothing"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("clothsim: error: PORT: data:liu13-port/nothing: no such file")
    assert err.count("\n") == 1


# ---------------------------------------------------------------- scenes that need data
def test_a_scene_needing_absent_data_is_one_line_on_how_to_get_it(cache, capsys):
    assert cli.main(["validate", "jacobson-net"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert err.startswith("clothsim: error: ") and "jacobson-net.toml: cloth.file: " in err
    assert "`clothsim data fetch jacobson-a8`" in err and "CLOTHSIM_DATA" in err


def test_a_first_use_download_that_fails_is_one_line(cache, monkeypatch):
    monkeypatch.delenv("CLOTHSIM_OFFLINE")
    dead = dataclasses.replace(registry.JACOBSON, url="http://127.0.0.1:9/")
    monkeypatch.setitem(registry.DATASETS, "jacobson-a8", dead)
    with pytest.raises(SceneError) as info:
        load_scene("jacobson-chain")
    msg = str(info.value)
    assert "\n" not in msg and "cloth.file: data set jacobson-a8: could not download" in msg
    assert "(no connection)" in msg and "`clothsim data fetch jacobson-a8`" in msg


def test_a_data_path_cannot_leave_its_data_set(cache, tmp_path):
    p = tmp_path / "s.toml"
    p.write_text('[cloth]\nshape = "files"\nvertices = "data:liu13-port/../../secret.txt"\n')
    (cache / "secret.txt").parent.mkdir(parents=True, exist_ok=True)
    (cache / "secret.txt").write_text("0 0 0\n1 0 0\n0 0 1\n")
    with pytest.raises(SceneError, match="must stay inside the data set's folder"):
        load_scene(p)
    p.write_text('[cloth]\nshape = "files"\nvertices = "data:nothing/x.txt"\n')
    with pytest.raises(SceneError, match=r"names no data set \(known: liu13-port, "
                                         r"jacobson-a8\); set CLOTHSIM_DATA"):
        load_scene(p)


# ---------------------------------------------------------------- the pinned hashes
def test_the_pinned_hashes_are_those_of_the_assignments_files():
    """Served from a local copy when there is one (CLOTHSIM_DATA or the cache)."""
    st = datasets.status("jacobson-a8")
    if not st.present:
        pytest.skip(SKIP_ASSIGNMENT)
    assert datasets.changed_files("jacobson-a8", st.folder) == []
    assert registry.JACOBSON.url.endswith(f"/{registry.JACOBSON_COMMIT}/data/")
    assert len(registry.JACOBSON_COMMIT) == 40


def test_the_real_registry_downloads_from_a_copy(tmp_path, monkeypatch):
    """The jacobson-a8 registry fetched from a local server holding a copy of the files
    (the real address cannot be reached from the tests)."""
    src = datasets.status("jacobson-a8")
    if not src.present:
        pytest.skip(SKIP_ASSIGNMENT)
    (tmp_path / "www").mkdir()
    (tmp_path / "www" / "data").symlink_to(src.folder)
    monkeypatch.setenv("CLOTHSIM_CACHE", str(tmp_path / "cache"))
    monkeypatch.delenv("CLOTHSIM_DATA", raising=False)
    s = Server(tmp_path / "www")
    try:
        folder = datasets.fetch("jacobson-a8", base_url=s.url.replace("/files/", "/data/"))
    finally:
        s.stop()
    assert folder == tmp_path / "cache" / "jacobson-a8"
    assert datasets.changed_files("jacobson-a8", folder) == []
    assert load_scene("jacobson-net").build_model().vertex_count == 61
