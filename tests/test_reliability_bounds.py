"""Count flags get the scene schema's limits: --frames beyond 1e7 (the scene key's limit)
is refused at once with one line naming the flag, for every command that takes one."""

import pytest

from clothsim.cli import main
from clothsim.errors import InputError
from clothsim.runner import run_scene
from clothsim.scene.schema import MAX_FRAMES

HUGE = "100000000000"


@pytest.mark.parametrize("argv", [
    ["run", "hanging", "--frames", HUGE],
    ["run", "hanging", "--frames", str(MAX_FRAMES + 1)],
    ["run", "hanging", "--frames", "-1"],
    ["run", "hanging", "--frames", "1e3"],
    ["export", "hanging", "--frames", HUGE],
    ["export", "hanging", "--iterate-steps", HUGE],
    ["compare", "a.npy", "b.npy", "--frames", HUGE],
    ["compare", "a.npy", "b.npy", "--frames", "0"],
    ["compare", "a.raw", "b.npy", "--vertices", HUGE],
    ["check", "hanging", "port", "--steps", HUGE],
    ["accuracy", "hanging", "--frames", HUGE],
    ["accuracy", "hanging", "--jobs", "0"],
])
def test_count_flags_are_bounded(argv, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    flag = [a for a in argv if a.startswith("--")][0]
    assert len(err.splitlines()) == 1 and flag in err and "must be an integer" in err
    assert not (tmp_path / "out").exists()


def test_the_limit_itself_is_accepted_by_the_parser():
    from clothsim.cli import build_parser

    args = build_parser().parse_args(["run", "--frames", str(MAX_FRAMES)])
    assert args.frames == MAX_FRAMES


@pytest.mark.parametrize("frames", [MAX_FRAMES + 1, -1, 2.5, True, "3"])
def test_run_scene_bounds_frames(frames, tmp_path):
    with pytest.raises(InputError, match="frames: must be an integer"):
        run_scene("hanging", tmp_path / "out", frames=frames, preview=False)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("value", ["inf", "nan", "-1"])
def test_float_flags_must_be_finite(value, tmp_path, capsys):
    assert main(["compare", "a.npy", "b.npy", "--rtol", value]) == 2
    assert "--rtol: must be a finite non-negative number" in capsys.readouterr().err
