"""One way to spread the study's independent computations over workers (joblib).

:func:`map_jobs` runs ``func(*item)`` for every item, serially, in ``jobs`` joblib (loky)
worker processes, or on a Dask cluster through joblib's dask backend, and returns the
results in the items' order. Every function it runs in the study is deterministic (one
solve, one reference, one trajectory), so the results do not depend on ``jobs``.
:func:`check_scheduler` tries a Dask scheduler's address before a study starts, so that a
wrong one is a one-line error at once instead of a failure after the recording.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence

from ..errors import InputError

#: seconds a study waits for its Dask scheduler to answer before it gives up
CONNECT_TIMEOUT = 10


def check_scheduler(address: str) -> None:
    """Connect to the Dask scheduler at ``address`` once, or say in one line why not.

    Parameters
    ----------
    address : str
        E.g. ``tcp://10.0.0.5:8786``.

    Raises
    ------
    InputError
        ``accuracy.scheduler: …`` when dask.distributed is not installed (the extra
        ``cluster``) or the scheduler does not answer within :data:`CONNECT_TIMEOUT`.
    """
    try:
        from dask.distributed import Client
    except ImportError:
        raise InputError("accuracy.scheduler: needs dask.distributed: pip install "
                         "'clothsim[cluster]'") from None
    try:
        with Client(address, timeout=f"{CONNECT_TIMEOUT}s"):
            pass
    except (OSError, ValueError, TypeError) as exc:   # TimeoutError is an OSError
        text = " ".join(str(exc).split()) or type(exc).__name__
        raise InputError(f"accuracy.scheduler: cannot use {address!r}: {text}") from None


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
