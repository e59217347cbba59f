"""An inherited SIG_IGN is kept (``nohup``): the run survives SIGHUP; the other signals
still interrupt it."""

import json
import os
import signal
import subprocess
import sys

import pytest

from clothsim.interrupts import SignalInterrupt, handle_signals, signals_deferred
from tests.test_interrupts import REPO, wait_for_frame, write_scene

pytestmark = pytest.mark.skipif(not hasattr(signal, "SIGHUP"), reason="needs SIGHUP (POSIX)")


@pytest.fixture
def sighup_ignored():
    old = signal.signal(signal.SIGHUP, signal.SIG_IGN)
    yield
    signal.signal(signal.SIGHUP, old)


def test_ignored_sighup_stays_ignored_in_both_contexts(sighup_ignored):
    with handle_signals():
        assert signal.getsignal(signal.SIGHUP) == signal.SIG_IGN
        assert signal.getsignal(signal.SIGTERM) != signal.SIG_IGN
        with signals_deferred():
            assert signal.getsignal(signal.SIGHUP) == signal.SIG_IGN
            os.kill(os.getpid(), signal.SIGHUP)  # ignored: nothing held, nothing raised
        os.kill(os.getpid(), signal.SIGHUP)
    assert signal.getsignal(signal.SIGHUP) == signal.SIG_IGN


def test_not_ignored_signals_still_interrupt(sighup_ignored):
    with pytest.raises(SignalInterrupt), handle_signals():
        os.kill(os.getpid(), signal.SIGTERM)
        for _ in range(10 ** 6):  # the handler runs between bytecodes
            pass


def _nohup():
    signal.signal(signal.SIGHUP, signal.SIG_IGN)


def test_a_nohup_run_survives_sighup(tmp_path):
    out = tmp_path / "run"
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    proc = subprocess.Popen([sys.executable, "-m", "clothsim", "run",
                             str(write_scene(tmp_path, "local-global")), "--out", str(out),
                             "--no-preview"], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, preexec_fn=_nohup)
    try:
        wait_for_frame(out, 2, proc)
        proc.send_signal(signal.SIGHUP)
        last = json.loads((out / "run.json").read_text())["last_frame"]
        wait_for_frame(out, last + 3, proc)  # still stepping after the SIGHUP
        assert proc.poll() is None
    finally:
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143 and "interrupted (SIGTERM)" in err


def test_resume_after_sigkill_is_bit_for_bit_with_one_record_per_frame(tmp_path):
    import numpy as np

    from clothsim.runner import run_scene

    scene = write_scene(tmp_path, "local-global")
    out = tmp_path / "killed"
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    proc = subprocess.Popen([sys.executable, "-m", "clothsim", "run", str(scene), "--out",
                             str(out), "--no-preview", "--frames", "400"], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        wait_for_frame(out, 3, proc)
    finally:
        proc.kill()  # SIGKILL: nothing can be cleaned up
        proc.communicate(timeout=60)
    frames = 12
    run_scene(str(scene), out, frames=frames, resume=True, preview=False)
    full = tmp_path / "full"
    run_scene(str(scene), full, frames=frames, preview=False)
    a, b = np.load(out / "trajectory.npz"), np.load(full / "trajectory.npz")
    for key in ("positions", "velocities"):
        assert np.array_equal(a[key], b[key]), key
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "completed"
    assert [r["frame"] for r in run["frames"]] == list(range(1, frames + 1))
