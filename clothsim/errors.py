"""Exceptions and warnings raised by clothsim.

Every error about bad input is a :class:`InputError` whose message is one line that names
the field (or index) and says what is wrong, so the command line can print it as is.
"""

from __future__ import annotations

import numpy as np


class ClothsimError(Exception):
    """Base class of clothsim's errors."""


class InputError(ClothsimError, ValueError):
    """Bad input: the message names the field and what is wrong with it.

    Parameters
    ----------
    message : str
        One line, conventionally ``"<field>: <what is wrong>"``.
    field : str, optional
        The field (argument, key path or index) the message is about, e.g.
        ``"vertex_mass[3]"``; ``None`` when the raiser did not name it separately.
    """

    def __init__(self, message: str = "", field: str | None = None):
        super().__init__(message)
        self.field = field

    def __reduce__(self):  # keep .field across pickling (e.g. from a worker process)
        return type(self), (str(self), self.field)


class SceneError(InputError):
    """A scene file is wrong; the message is ``"<file>: <key.path>: <what is wrong>"``.

    Attributes
    ----------
    source : str
        The scene file (or ``"<dict>"``).
    path : str
        Key path inside it, e.g. ``"effects[2].radius"`` (may be empty); also ``.field``
        (``None`` when empty).
    detail : str
        What is wrong (one line).
    """

    def __init__(self, source: str, path: str, detail: str):
        self.source, self.path = str(source), path
        self.detail = " ".join(str(detail).split())  # always one line
        where = f"{self.source}: {path}: " if path else f"{self.source}: "
        super().__init__(where + self.detail, field=path or None)

    def __reduce__(self):
        return type(self), (self.source, self.path, self.detail)


class FactorizationError(ClothsimError):
    """The system matrix could not be factored (for example, it is not positive definite)."""


class NonFiniteStateError(ClothsimError):
    """A step produced non-finite positions or velocities (a blow-up, not bad input); the
    simulation keeps its last finite state."""


class ClothsimWarning(UserWarning):
    """Base class of clothsim's warnings (the test suite turns them into errors)."""


class ConvergenceWarning(ClothsimWarning):
    """An iterative solve hit its iteration limit above the requested tolerance."""


class ConditioningWarning(ClothsimWarning):
    """The system matrix is badly conditioned; results may have lost digits."""


class BackendWarning(ClothsimWarning):
    """A requested backend is unavailable and a fallback is used."""


class MeshWarning(ClothsimWarning):
    """A mesh is usable but suspicious (unreferenced or duplicate vertices, several parts)."""


def check_finite(name: str, value) -> np.ndarray:
    """Return ``value`` as a float64 array; raise :class:`InputError` naming the first bad index.

    Parameters
    ----------
    name : str
        Field name used in the message, e.g. ``"vertex_mass"``.
    value : array_like
        Numbers to check.

    Returns
    -------
    ndarray
        ``value`` as float64, same shape (no copy when it already is one).

    Raises
    ------
    InputError
        When an entry is NaN or infinite, e.g. "vertex_mass[3]: must be a finite number",
        or ``value`` is not real numbers (booleans, complex numbers, text are not coerced).
    """
    raw = np.asarray(value)
    if raw.dtype.kind not in "iuf" and not (raw.dtype == object and raw.size == 0):
        what = {"b": "booleans", "c": "complex numbers", "U": "text", "S": "bytes",
                "O": "Python objects"}.get(raw.dtype.kind, str(raw.dtype))
        raise InputError(f"{name}: must be real numbers, got {what}", field=name)
    arr = np.asarray(raw, dtype=np.float64)
    bad = ~np.isfinite(arr)
    if bad.any():
        index = np.unravel_index(int(np.flatnonzero(bad)[0]), arr.shape)
        where = f"{name}[{', '.join(str(int(i)) for i in index)}]" if arr.ndim else name
        raise InputError(f"{where}: must be a finite number, got {float(arr[index])!r}",
                         field=where)
    return arr


def check_positive(name: str, value, *, allow_zero: bool = False) -> np.ndarray:
    """Like :func:`check_finite`, and also require every entry > 0 (>= 0 with ``allow_zero``).

    Parameters
    ----------
    name : str
        Field name used in the message.
    value : array_like
        Numbers to check.
    allow_zero : bool, default False
        Accept zeros.

    Returns
    -------
    ndarray
        ``value`` as float64, same shape.

    Raises
    ------
    InputError
        When an entry is not finite, or not positive (negative with ``allow_zero``).
    """
    arr = check_finite(name, value)
    bad = arr < 0 if allow_zero else arr <= 0
    if bad.any():
        index = np.unravel_index(int(np.flatnonzero(bad)[0]), arr.shape)
        where = f"{name}[{', '.join(str(int(i)) for i in index)}]" if arr.ndim else name
        rel = "non-negative" if allow_zero else "positive"
        raise InputError(f"{where}: must be {rel}, got {float(arr[index])!r}", field=where)
    return arr
