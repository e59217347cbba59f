"""``accuracy --scheduler`` at something that is not a Dask scheduler (issue 34, item 3).

dask.distributed waits for ever on a listener that never speaks (an HTTP server) and trusts
a garbage frame length (out of memory); :func:`clothsim.accuracy.parallel.check_scheduler`
names both in one line within its timeout. Every server here listens on 127.0.0.1 only,
serves from a daemon thread and is closed by the fixture.
"""

from __future__ import annotations

import http.server
import socket
import threading

import pytest

from clothsim.errors import InputError

pytest.importorskip("dask.distributed", reason="dask.distributed is not installed")


@pytest.fixture
def listener():
    """``start(reply)``: a TCP server on 127.0.0.1 that sends ``reply`` to each client."""
    servers = []

    def start(reply: bytes) -> str:
        srv = socket.socket()
        srv.bind(("127.0.0.1", 0))
        srv.listen()
        srv.settimeout(30)  # the thread ends by itself even if nobody closes it

        def serve():
            try:
                while True:
                    conn, _ = srv.accept()
                    with conn:  # an empty reply: close at once
                        if reply:
                            conn.sendall(reply)
                            conn.recv(1 << 16)
            except OSError:
                return

        threading.Thread(target=serve, daemon=True).start()
        servers.append(srv)
        return f"tcp://127.0.0.1:{srv.getsockname()[1]}"

    yield start
    for srv in servers:
        srv.close()


@pytest.fixture
def http_server():
    srv = http.server.HTTPServer(("127.0.0.1", 0), http.server.BaseHTTPRequestHandler)
    srv.timeout = 1
    thread = threading.Thread(target=srv.serve_forever, kwargs={"poll_interval": 0.1},
                              daemon=True)
    thread.start()
    yield f"tcp://127.0.0.1:{srv.server_address[1]}"
    srv.shutdown()
    srv.server_close()


def _refusal(address: str) -> str:
    from clothsim.accuracy.parallel import check_scheduler

    with pytest.raises(InputError) as info:
        check_scheduler(address)
    text = str(info.value)
    assert "\n" not in text and text.startswith(f"accuracy.scheduler: cannot use '{address}': ")
    return text


def test_an_http_server_is_named_within_the_timeout(http_server, monkeypatch):
    from clothsim.accuracy import parallel

    monkeypatch.setattr(parallel, "CONNECT_TIMEOUT", 1)
    text = _refusal(http_server)
    assert "not a Dask scheduler: it accepted the connection but sent no Dask handshake " \
           "within 1 s" in text


@pytest.mark.parametrize("reply, why", [
    (b"\xff" * 8 + b"garbage", "its first bytes do not frame a Dask message (a length of "
                               "18446744073709551615 bytes)"),
    (b"HTTP/1.1 400 Bad Request\r\n\r\n", "its first bytes do not frame a Dask message"),
    ((24).to_bytes(8, "little") + (1).to_bytes(8, "little") + (8).to_bytes(8, "little")
     + b"\x93\x01\x02\x03" + b"zzzz", "its first message is not a Dask handshake"),
    ((24).to_bytes(8, "little") + (5).to_bytes(8, "little") + b"x" * 16,
     "its first message does not frame a Dask handshake (5 frames)"),
    (b"", "it closed the connection without a Dask handshake"),
], ids=["huge-length", "http-reply", "msgpack-not-handshake", "bad-frame-count", "closed"])
def test_a_peer_answering_garbage_is_one_line_not_out_of_memory(listener, reply, why):
    assert f"not a Dask scheduler: {why}" in _refusal(listener(reply))


def test_nothing_listening_and_a_malformed_address_are_named():
    assert _refusal("tcp://127.0.0.1:1").endswith("Connection refused")
    assert _refusal("garbage").endswith("missing port number in address 'garbage'")


def test_a_real_scheduler_passes_the_probe():
    from dask.distributed import LocalCluster

    from clothsim.accuracy.parallel import check_scheduler, probe_scheduler

    with LocalCluster(processes=False, n_workers=1, threads_per_worker=1, protocol="tcp://",
                      host="127.0.0.1", dashboard_address=None) as cluster:
        assert cluster.scheduler_address.startswith("tcp://127.0.0.1:")
        host, port = cluster.scheduler_address.removeprefix("tcp://").rsplit(":", 1)
        assert "python" in probe_scheduler(host, int(port))
        check_scheduler(cluster.scheduler_address)


def test_the_accuracy_command_refuses_an_http_server_before_writing(http_server, tmp_path,
                                                                    monkeypatch, capsys):
    from clothsim import cli
    from clothsim.accuracy import parallel

    monkeypatch.setattr(parallel, "CONNECT_TIMEOUT", 1)
    code = cli.main(["accuracy", "hanging", "--quick", "--scheduler", http_server,
                     "--out", str(tmp_path / "acc")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "not a Dask scheduler" in err, err
    assert not (tmp_path / "acc").exists()
