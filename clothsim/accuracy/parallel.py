"""One way to spread the study's independent computations over workers (joblib).

:func:`map_jobs` runs ``func(*item)`` for every item, serially, in ``jobs`` joblib (loky)
worker processes, or on a Dask cluster through joblib's dask backend, and returns the
results in the items' order. Every function it runs in the study is deterministic (one
solve, one reference, one trajectory), so the results do not depend on ``jobs``.
:func:`check_scheduler` tries a Dask scheduler's address before a study starts, so that a
wrong one is a one-line error at once instead of a failure after the recording.
"""

from __future__ import annotations

import socket
import struct
import time
from collections.abc import Callable, Iterable, Sequence

from ..errors import InputError

#: seconds a study waits for its Dask scheduler to answer before it gives up
CONNECT_TIMEOUT = 10
#: largest first message accepted from a scheduler [bytes] (its handshake is ~100 bytes)
MAX_HANDSHAKE = 1 << 20


class _NotDask(Exception):
    """The peer at a ``tcp://`` address is not a Dask scheduler (the reason)."""


def _read_exactly(sock: socket.socket, count: int, deadline: float) -> bytes:
    buf = bytearray()
    while len(buf) < count:
        sock.settimeout(max(deadline - time.monotonic(), 0.001))
        try:
            chunk = sock.recv(count - len(buf))
        except TimeoutError:
            raise _NotDask(f"it accepted the connection but sent no Dask handshake within "
                           f"{CONNECT_TIMEOUT} s (is it a Dask scheduler? an HTTP server or "
                           f"the dashboard's port waits for a request)") from None
        if not chunk:
            raise _NotDask("it closed the connection without a Dask handshake")
        buf += chunk
    return bytes(buf)


def probe_scheduler(host: str, port: int, timeout: float = CONNECT_TIMEOUT) -> dict:
    """Read the handshake a Dask scheduler sends first on a new TCP connection.

    A scheduler writes its handshake (a msgpack map with ``python``, ``compression``,
    ``pickle-protocol``) as soon as it accepts a connection, in Dask's framing: the byte
    count (uint64), the frame count and lengths (uint64 each), then the frames. Any other
    listener either sends nothing (an HTTP server waits for a request) or bytes that do not
    parse as that; both are told apart here within ``timeout`` seconds and before any
    allocation a peer could choose (dask.distributed itself would wait for ever, or trust
    a garbage length and run out of memory).

    Parameters
    ----------
    host : str
    port : int
    timeout : float
        Seconds for the whole exchange [s].

    Returns
    -------
    dict
        The scheduler's handshake.

    Raises
    ------
    OSError
        The connection cannot be made (refused, unreachable, timed out).
    _NotDask
        The peer is not a Dask scheduler (the reason).
    """
    import msgpack  # a dependency of dask.distributed

    deadline = time.monotonic() + timeout
    with socket.create_connection((host, port), timeout=timeout) as sock:
        (total,) = struct.unpack("<Q", _read_exactly(sock, 8, deadline))
        if not 16 <= total <= MAX_HANDSHAKE:
            raise _NotDask(f"its first bytes do not frame a Dask message (a length of "
                           f"{total} bytes)")
        body = _read_exactly(sock, total, deadline)
    (count,) = struct.unpack_from("<Q", body)
    if not 1 <= count <= 64 or 8 * (1 + count) > total:
        raise _NotDask(f"its first message does not frame a Dask handshake ({count} frames)")
    lengths = struct.unpack_from(f"<{count}Q", body, 8)
    if 8 * (1 + count) + sum(lengths) != total:
        raise _NotDask("its first message's frame lengths do not add up")
    start = 8 * (1 + count)
    for length in lengths:
        try:
            msg = msgpack.unpackb(body[start:start + length], raw=False,
                                  strict_map_key=False)
        except (ValueError, TypeError, msgpack.ExtraData, msgpack.FormatError,
                msgpack.StackError):
            msg = None
        if isinstance(msg, dict) and "python" in msg:
            return msg
        start += length
    raise _NotDask("its first message is not a Dask handshake")


def _refusal(address: str, text: str) -> InputError:
    return InputError(f"accuracy.scheduler: cannot use {address!r}: "
                      + (" ".join(str(text).split()) or "no reason given"))


def check_scheduler(address: str) -> None:
    """Connect to the Dask scheduler at ``address`` once, or say in one line why not.

    A ``tcp://`` address (or ``host:port``) is first probed with :func:`probe_scheduler`,
    so that a listener that is not a Dask scheduler is named within
    :data:`CONNECT_TIMEOUT` seconds instead of hanging or exhausting memory.

    Parameters
    ----------
    address : str
        E.g. ``tcp://10.0.0.5:8786``.

    Raises
    ------
    InputError
        ``accuracy.scheduler: …`` when dask.distributed is not installed (the extra
        ``cluster``), the address is malformed, nothing listens there, the listener is not
        a Dask scheduler, or the scheduler does not answer within :data:`CONNECT_TIMEOUT`.
    """
    try:
        from dask.distributed import Client
        from distributed.comm.addressing import parse_address, parse_host_port
    except ImportError:
        raise InputError("accuracy.scheduler: needs dask.distributed: pip install "
                         "'clothsim[cluster]'") from None

    if not address.strip():
        raise _refusal(address, "empty; give a running scheduler's address, e.g. "
                                "tcp://10.0.0.5:8786")
    try:
        scheme, location = parse_address(address)
        if scheme == "inproc":  # a scheduler inside this process: none exists at the start
            raise ValueError("an inproc:// address names a scheduler inside this process; "
                             "give the tcp:// address of a running scheduler")
        if scheme == "tcp":
            host, port = parse_host_port(location)
            if not 0 < port < 65536:
                raise ValueError(f"port {port} is out of range (1 to 65535)")
            probe_scheduler(host, port, timeout=CONNECT_TIMEOUT)
    except _NotDask as exc:
        raise _refusal(address, f"not a Dask scheduler: {exc}") from None
    except (OSError, ValueError, TypeError) as exc:   # refused, unreachable, malformed
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise _refusal(address, why or type(exc).__name__) from None
    try:
        with Client(address, timeout=f"{CONNECT_TIMEOUT}s"):
            pass
    except (OSError, ValueError, TypeError, MemoryError) as exc:   # TimeoutError: OSError
        raise _refusal(address, str(exc) or type(exc).__name__) from None


def map_jobs(func: Callable, items: Iterable[Sequence], *, jobs: int = 1,
             scheduler: str | None = None, each: Callable | None = None) -> list:
    """``[func(*item) for item in items]``, possibly in parallel workers.

    Parameters
    ----------
    func : callable
        A picklable function (module level) of the item's fields.
    items : iterable of sequence
        The arguments of each call.
    jobs : int, default 1
        Worker processes (joblib's loky backend); 1 runs in this process.
    scheduler : str, optional
        Address of a Dask scheduler: run through joblib's dask backend instead.
    each : callable, optional
        Called in this process with each result as it arrives (e.g. to move a progress bar).

    Returns
    -------
    list
        The results, in the order of ``items``.
    """
    items = list(items)
    if scheduler is None and (jobs == 1 or len(items) < 2):
        out = []
        for item in items:
            out.append(func(*item))
            if each is not None:
                each(out[-1])
        return out
    import joblib

    if scheduler is not None:
        from dask.distributed import Client  # only with --scheduler

        with Client(scheduler), joblib.parallel_backend("dask"):
            out = joblib.Parallel()(joblib.delayed(func)(*item) for item in items)
        for r in out if each is not None else ():
            each(r)
        return out
    out = []
    for r in joblib.Parallel(n_jobs=jobs, backend="loky", return_as="generator")(
            joblib.delayed(func)(*item) for item in items):
        out.append(r)
        if each is not None:
            each(r)
    return out
