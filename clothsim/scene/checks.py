"""Checks of single values in a scene document, each failing with the key path.

Every checker raises :class:`Invalid` at the key ``path`` it is given (made a
:class:`~clothsim.errors.SceneError` by the caller) with a one-line reason. Numbers are
never booleans or strings, always finite; integers too large for a float are named.
"""

from __future__ import annotations

import difflib
import inspect
import math
import re

from ..errors import InputError
from .schema import MAX_NAME, TOP_KEYS, sci

ECHO = 60  # characters of a user's value echoed in a message


class Invalid(Exception):
    """A validation failure at a key path.

    Parameters
    ----------
    path : str
        The key path, e.g. ``"effects[2].stiffness"``.
    detail : str
        One-line reason. Both are kept as attributes.
    """

    def __init__(self, path: str, detail: str):
        super().__init__(detail)
        self.path, self.detail = path, detail


def shorten(text: str, limit: int = ECHO) -> str:
    """``text`` cut to ``limit`` characters, with "…" when cut.

    Parameters
    ----------
    text : str
    limit : int
        Characters kept.

    Returns
    -------
    str
    """
    return text if len(text) <= limit else text[:limit] + "…"


def show(value) -> str:
    """A value as a message shows it: plain Python floats, truncated when long.

    Parameters
    ----------
    value : object

    Returns
    -------
    str
        Its ``repr`` cut to 60 characters (numpy scalars as Python's; huge integers by size).
    """
    if hasattr(value, "item") and getattr(value, "ndim", None) == 0:  # numpy scalar
        value = value.item()
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 10 ** 30:
        return f"an integer of {len(str(abs(value)))} digits"
    return shorten(repr(value))


def type_name(value) -> str:
    """"<type> <value>" for messages, e.g. ``"string 'down'"``.

    Parameters
    ----------
    value : object

    Returns
    -------
    str
    """
    names = {bool: "boolean", int: "integer", float: "float", str: "string", list: "array",
             tuple: "array", dict: "table"}
    return f"{names.get(type(value), type(value).__name__)} {show(value)}"


def suggest(key: str, known) -> str:
    """"; did you mean 'x'?" or "; expected one of ..." for an unknown key.

    Parameters
    ----------
    key : str
    known : iterable of str
        The accepted keys or names.

    Returns
    -------
    str
        The hint, to append to a message.
    """
    key = str(key)
    close = [k for k in known if len(key) >= 3 and k.startswith(key)]
    close = close or difflib.get_close_matches(key, list(known), n=1, cutoff=0.6)
    return f"; did you mean '{close[0]}'?" if close else f"; expected one of {', '.join(known)}"


def is_number(v) -> bool:
    """Whether ``v`` is an int or float and not a boolean.

    Parameters
    ----------
    v : object

    Returns
    -------
    bool
    """
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def number(v, path, *, positive=False, nonnegative=False, maximum=None) -> float:
    """A finite float from an int or float (not a boolean, not a string).

    Parameters
    ----------
    v : object
        The scene value, in the key's unit.
    path : str
    positive, nonnegative : bool
        Require > 0 or >= 0.
    maximum : float, optional
        Upper bound (inclusive).

    Returns
    -------
    float

    """
    if not is_number(v):
        raise Invalid(path, f"expected a number, got {type_name(v)}")
    try:
        f = float(v)
    except OverflowError:
        raise Invalid(path, f"{show(v)} is beyond the floating-point range "
                            f"(±1.8e308)") from None
    if not math.isfinite(f):
        raise Invalid(path, f"must be a finite number, got {f!r}")
    if positive and f <= 0:
        raise Invalid(path, f"must be positive, got {f!r}")
    if nonnegative and f < 0:
        raise Invalid(path, f"must be non-negative, got {f!r}")
    if maximum is not None and f > maximum:
        raise Invalid(path, f"must be at most {maximum:g}, got {f!r}")
    return f


def integer(v, path, *, minimum=None, maximum=None) -> int:
    """An int (a float with an integer value is accepted), within [minimum, maximum].

    Parameters
    ----------
    v : object
    path : str
    minimum, maximum : int, optional
        Inclusive bounds.

    Returns
    -------
    int

    """
    if isinstance(v, float) and math.isfinite(v) and v.is_integer():
        v = int(v)
    if not isinstance(v, int) or isinstance(v, bool):
        raise Invalid(path, f"expected an integer, got {type_name(v)}")
    if minimum is not None and v < minimum:
        raise Invalid(path, f"must be an integer >= {minimum}, got {show(v)}")
    if maximum is not None and v > maximum:
        raise Invalid(path, f"must be an integer <= {sci(maximum)} (larger is almost surely "
                            f"a mistake and would run for ages), got {show(v)}")
    return v


def string(v, path, *, choices=None) -> str:
    """A string, optionally one of ``choices``.

    Parameters
    ----------
    v : object
    path : str
    choices : sequence of str, optional
        The accepted values (the error suggests the closest).

    Returns
    -------
    str

    """
    if not isinstance(v, str):
        raise Invalid(path, f"expected a string, got {type_name(v)}")
    if choices is not None and v not in choices:
        close = difflib.get_close_matches(v, list(choices), n=1)
        hint = f"; did you mean '{close[0]}'?" if close else ""
        raise Invalid(path, f"must be one of {', '.join(map(repr, choices))}, got "
                            f"{show(v)}{hint}")
    return v


def vector(v, path, length, *, positive=False) -> list[float]:
    """An array of ``length`` finite numbers (each checked by :func:`number`).

    Parameters
    ----------
    v : object
        The scene value, e.g. a point [m] or an acceleration [m/s²].
    path : str
        Its key path; an element's error names ``path[i]``.
    length : int
        Required number of elements.
    positive : bool
        Require every element > 0.

    Returns
    -------
    list of float, length ``length``

    """
    if not isinstance(v, (list, tuple)) or len(v) != length:
        raise Invalid(path, f"expected an array of {length} numbers, got {type_name(v)}")
    return [number(x, f"{path}[{i}]", positive=positive) for i, x in enumerate(v)]


def safe_name(v, path="scene.name") -> str:
    """A name that is safe as a folder name: ``[A-Za-z0-9_.-]``, no leading dot, ≤ 100.

    Parameters
    ----------
    v : object
    path : str

    Returns
    -------
    str

    """
    v = string(v, path)
    if (not re.fullmatch(r"[\w.-]+", v, flags=re.ASCII) or v.startswith(".")
            or len(v) > MAX_NAME):
        raise Invalid(path, f"use letters, digits, '_', '.' and '-' only, not starting with "
                            f"'.', at most {MAX_NAME} characters (it names the output "
                            f"folder), got {show(v)}")
    return v


def table(v, path) -> dict:
    """``v`` if it is a table (dict).

    Parameters
    ----------
    v : object
    path : str

    Returns
    -------
    dict

    """
    if not isinstance(v, dict):
        raise Invalid(path, f"expected a table, got {type_name(v)}")
    return v


def check_keys(t: dict, path: str, known) -> None:
    """Reject a key of ``t`` not in ``known`` (suggesting the closest known key).

    Parameters
    ----------
    t : dict
        A scene table.
    path : str
        Its key path ("" for the top level).
    known : iterable of str
        The accepted keys.

    Raises
    ------
    Invalid
        At ``path.key`` for the first unknown key.
    """
    for key in t:
        if key not in known:
            raise Invalid(f"{path}.{key}" if path else str(key),
                          f"unknown key '{shorten(str(key))}'" + suggest(key, known))


def check_finite_everywhere(value, path: str) -> None:
    """TOML allows nan and inf literals: reject them anywhere in the document.

    Also rejects integers beyond the float range, which would overflow later.

    Parameters
    ----------
    value : object
        A scene document or part of it (nested dicts and lists).
    path : str
        Its key path ("" for the document).

    Raises
    ------
    Invalid
        At the first offending value's key path.
    """
    stack = [(value, path)]
    while stack:
        v, p = stack.pop()
        if isinstance(v, float) and not math.isfinite(v):
            raise Invalid(p, f"must be a finite number, got {v!r}")
        if isinstance(v, int) and not isinstance(v, bool) and abs(v) > 1.7976931348623157e308:
            raise Invalid(p, f"{show(v)} is beyond the floating-point range (±1.8e308)")
        if isinstance(v, dict):
            items = [(f"{p}.{k}" if p else str(k), x) for k, x in v.items()]
        elif isinstance(v, (list, tuple)):
            items = [(f"{p}[{i}]", x) for i, x in enumerate(v)]
        else:
            continue
        stack.extend((x, q) for q, x in reversed(items))


def constructor_keys(cls) -> tuple[list[str], bool]:
    """Constructor keyword names of an effect class, and whether it takes ``**kwargs``.

    Parameters
    ----------
    cls : type
        An effect class.

    Returns
    -------
    names : list of str
    open : bool
    """
    params = inspect.signature(cls).parameters.values()
    names = [p.name for p in params if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]
    return names, any(p.kind is p.VAR_KEYWORD for p in params)


def locate(exc: InputError, default_path: str, kind: str | None = None,
           prefix: str | None = None) -> tuple[str, str]:
    """(key path, reason) of a core :class:`InputError`.

    Uses ``exc.field`` when the raiser set it; otherwise the core's convention that a
    message starts with ``"<field>: "``. A field ``"<kind>.<key>"`` of an effect becomes
    ``"<prefix>.<key>"``; other fields are prefixed with ``default_path``'s table.

    Parameters
    ----------
    exc : InputError
        The error raised by the core library.
    default_path : str
        Key path used when the message names no known field.
    kind, prefix : str, optional
        The effect kind and its key path (e.g. ``"effects[1]"``) when ``exc`` came from an effect.

    Returns
    -------
    path : str
        The scene key path to report.
    reason : str
        The message, one line, without the field it names.
    """
    # one line; a word over 200 characters (a value echoed whole) cut to 60 and "…"
    message = re.sub(rf"(\S{{{ECHO}}})\S{{141,}}", "\\1…", " ".join(str(exc).split()))
    fld = getattr(exc, "field", None)
    if fld is not None:
        rest = message[len(fld) + 2:] if message.startswith(f"{fld}: ") else message
    else:
        head, sep, rest = message.partition(": ")
        if not sep or not head or " " in head.replace(", ", ","):
            return default_path, message
        fld = head
    if kind is not None and prefix is not None:
        for lead in (f"effects.{kind}", kind):
            if fld == lead or fld.startswith((lead + ".", lead + "[")):
                return prefix + fld[len(lead):], rest
        return prefix, message
    if fld.split(".")[0].split("[")[0] in TOP_KEYS:
        return fld, rest
    if fld.split(".")[0].split("[")[0] in _CLOTH_FIELDS:
        return f"cloth.{fld}", rest
    return default_path, message


_CLOTH_FIELDS = ("vertex_mass", "mass_lumping", "mass", "resolution", "size", "center", "plane",
                 "outline", "spacing", "vertices", "triangles", "strands")

__all__ = ["Invalid", "shorten", "show", "type_name", "suggest", "is_number", "number",
           "integer", "string", "vector", "safe_name", "table", "check_keys",
           "check_finite_everywhere", "locate", "constructor_keys"]
