"""export, accuracy and conformance stopped by a signal: one line, exit 128 + the signal,
the folder marked interrupted (never left saying "writing"); a double Ctrl-C to run always
ends with its message."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from clothsim.io.folders import folder_state
from tests.test_interrupts import REPO, _default_signals, start_run, wait_for_frame, write_scene

pytestmark = pytest.mark.skipif(not hasattr(signal, "SIGHUP"), reason="needs POSIX signals")

BIG = """
[scene]
name = "big"
frames = 10
fps = 30
[cloth]
resolution = [{size}, {size}]
plane = "xy"
[springs]
structural = 200.0
[solver]
iterations = {iterations}
[[effects]]
kind = "gravity"
"""


def _start(*argv):
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    return subprocess.Popen([sys.executable, "-m", "clothsim", *map(str, argv)], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=_default_signals)


def _wait_for(proc, test, what, timeout=120):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        assert proc.poll() is None, (what, proc.communicate())
        if test():
            return
        time.sleep(0.01)
    raise AssertionError(f"never: {what}")


def _says(path, key, value):
    def test():
        try:
            return json.loads(path.read_text()).get(key) == value
        except (OSError, ValueError):
            return False
    return test


def _scene(tmp_path, size=20, iterations=10):
    p = tmp_path / f"big{size}.toml"
    p.write_text(BIG.format(size=size, iterations=iterations))
    return p


@pytest.mark.parametrize("signame", [   # SIGINT takes SIGTERM's path: a variant (-m slow)
    "SIGTERM", pytest.param("SIGINT", marks=pytest.mark.slow)])
def test_a_signal_to_export_marks_it_interrupted(tmp_path, signame):
    out = tmp_path / "export"
    proc = _start("export", _scene(tmp_path), "--out", out, "--frames", "20000",
                  "--iterate-steps", "0")
    _wait_for(proc, _says(out / "manifest.json", "status", "writing"), "export writing")
    proc.send_signal(getattr(signal, signame))
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 128 + getattr(signal, signame), err
    assert err.count("\n") == 1 and f"interrupted ({signame})" in err and str(out) in err
    assert "marked interrupted" in err and "clothsim export" in err
    state = folder_state(out)
    assert (state.status, state.error) == ("interrupted", f"SignalInterrupt: {signame}")
    assert not (out / ".clothsim.lock").exists()


def test_a_signal_to_accuracy_marks_it_interrupted(tmp_path):
    out = tmp_path / "study"
    proc = _start("accuracy", _scene(tmp_path, 12), "--out", out, "--problems", "8",
                  "--no-plots", "--frames", "10")
    _wait_for(proc, _says(out / "accuracy.json", "status", "running"), "study running")
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 143, err
    assert err.count("\n") == 1 and "interrupted (SIGTERM)" in err and str(out) in err
    record = json.loads((out / "accuracy.json").read_text())
    assert record["status"] == "interrupted" and record["error"] == "SignalInterrupt: SIGTERM"


def test_a_signal_to_conformance_says_so_in_its_readme(tmp_path):
    out = tmp_path / "set"
    proc = _start("conformance", "--out", out)
    _wait_for(proc, lambda: (out / "springs-stretch" / "manifest.json").exists(), "a case")
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 143 and "interrupted (SIGTERM)" in err, err
    readme = (out / "README.md").read_text().splitlines()
    assert readme[0] == "# clothsim conformance set"
    assert readme[2] == "status: interrupted (SignalInterrupt: SIGTERM)"
    assert folder_state(out).status == "interrupted"


@pytest.mark.parametrize("gap", [0.0, 0.002, 0.02])
def test_a_double_ctrl_c_to_run_always_ends_with_its_message(tmp_path, gap):
    out = tmp_path / "run"
    proc = start_run(write_scene(tmp_path, "local-global"), out)
    wait_for_frame(out, 2, proc)
    proc.send_signal(signal.SIGINT)
    time.sleep(gap)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert err.count("\n") == 1 and "interrupted (SIGINT)" in err
    assert json.loads((out / "run.json").read_text())["status"] == "interrupted"
