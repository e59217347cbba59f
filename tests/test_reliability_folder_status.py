"""One status per output folder (writing, complete, interrupted, failed), written by one
object (clothsim.io.outfolder.OutputFolder) and honoured by every reader: compare, check,
diff-model and matrix comparison refuse a folder that is not complete, naming it."""

import json

import numpy as np
import pytest

from clothsim.cli import main
from clothsim.errors import InputError
from clothsim.io.folders import folder_state, require_complete
from clothsim.io.outfolder import OutputFolder
from clothsim.ports import export as export_module
from clothsim.ports.export import export_port
from clothsim.scene import load_scene
from tests.test_reliability_folders import TINY

OTHER = TINY.replace('"tiny"', '"other"').replace("200.0", "50.0")


@pytest.fixture
def scenes(tmp_path):
    a, b = tmp_path / "a.toml", tmp_path / "b.toml"
    a.write_text(TINY)
    b.write_text(OTHER)
    return str(a), str(b)


def _killed_rewrite(tmp_path, scenes, monkeypatch, exc):
    """Export scene a, then an export of scene b into the same folder stops (``exc``) after
    writing its model files and before its trajectory: the folder mixes the two."""
    a, b = scenes
    out = tmp_path / "F"
    assert main(["export", a, "--out", str(out), "--frames", "2"]) == 0

    def stop(*args, **kwargs):
        raise exc

    monkeypatch.setattr(export_module, "record_iterates", stop)
    with pytest.raises(type(exc)):
        export_port(load_scene(b), out, frames=2)
    monkeypatch.undo()
    return out


@pytest.mark.parametrize("exc, status", [(KeyboardInterrupt(), "interrupted"),
                                         (RuntimeError("killed"), "failed")])
def test_readers_refuse_an_export_killed_while_rewriting_another(tmp_path, scenes, capsys,
                                                                 monkeypatch, exc, status):
    out = _killed_rewrite(tmp_path, scenes, monkeypatch, exc)
    state = folder_state(out)
    assert (state.kind, state.status) == ("export", status)
    a, _ = scenes
    port = tmp_path / "port"
    assert main(["export", a, "--out", str(port), "--frames", "2"]) == 0
    for argv in (["compare", str(port), str(out)], ["compare", str(out / "trajectory.npz"),
                                                     str(port)],
                 ["check", a, str(out)], ["diff-model", str(port), str(out)],
                 ["compare", str(out / "M.mtx"), str(port / "M.mtx")]):
        assert main(argv) == 2, argv
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and str(out) in err and repr(status) in err, err
        assert "clothsim export" in err  # how to complete it
    assert main(["compare", str(port), str(port), "--no-table"]) == 0  # complete: read


def test_a_sigkilled_export_says_writing_and_is_refused(tmp_path, scenes):
    """SIGKILL leaves the manifest that says writing (nothing can mark it)."""
    a, _ = scenes
    out = tmp_path / "F"
    export_port(load_scene(a), out, frames=2)
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["status"] == "complete"
    (out / "manifest.json").write_text(json.dumps({"layout": manifest["layout"],
                                                  "status": "writing"}))
    with pytest.raises(InputError, match="'writing', not complete"):
        require_complete(out / "positions.txt")


def test_an_export_of_another_scene_leaves_no_file_of_the_earlier_one(tmp_path, scenes):
    a, b = scenes
    out = tmp_path / "F"
    export_port(load_scene(a), out, frames=3, iterate_steps=3)
    export_port(load_scene(b), out, frames=3, iterate_steps=1)
    assert sorted(p.name for p in (out / "iterates").iterdir()) == ["step_0000.npz"]


@pytest.mark.parametrize("status", ["running", "interrupted", "failed"])
def test_readers_refuse_a_run_that_is_not_complete(tmp_path, scenes, capsys, status):
    a, _ = scenes
    out = tmp_path / "run"
    assert main(["run", a, "--out", str(out), "--no-preview"]) == 0
    assert main(["compare", str(out), str(out), "--no-table"]) == 0
    run = json.loads((out / "run.json").read_text())
    (out / "run.json").write_text(json.dumps(run | {"status": status}))
    assert main(["compare", str(out / "trajectory.npz"), str(out)]) == 2
    err = capsys.readouterr().err
    assert str(out) in err and f"run.json says {status!r}" in err and "--resume" in err


def test_a_folder_clothsim_did_not_write_is_read(tmp_path):
    np.save(tmp_path / "x.npy", np.zeros((2, 3, 3)))
    require_complete(tmp_path / "x.npy")
    require_complete(tmp_path)


def test_one_mark_for_every_kind(tmp_path):
    for kind, record in (("export", {"layout": "x in R^{3n} ..."}),
                         ("accuracy", {"clothsim": "1", "scene": "s"}), ("run", None),
                         ("conformance", None), ("coursework", None)):
        folder = tmp_path / kind
        with pytest.raises(RuntimeError), OutputFolder(folder, kind) as out:
            out.mark("writing", {"clothsim_run": 1} if kind == "run" else record)
            assert folder_state(folder).status == "writing"
            raise RuntimeError("disk gone")
        state = folder_state(folder)
        assert (state.kind, state.status) == (kind, "failed"), kind
        assert "disk gone" in state.error
        with OutputFolder(folder, kind) as out:
            out.mark("complete", "# clothsim " + ("conformance set" if kind == "conformance"
                                                  else "coursework profile") + "\n"
                     if kind in ("conformance", "coursework") else None)
        assert folder_state(folder).status == "complete", kind
