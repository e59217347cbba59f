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
