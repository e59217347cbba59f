"""How many digits a port printed: :func:`significant_digits` (the most significant digits
any value needs: 6 for ``%g``, 9 for ``%.9g``, 15 to 17 for a float64 written in full),
:func:`float32_valued` (whether the values are float32 numbers), :func:`unit` (the relative
rounding of d digits) and :func:`describe`. Read off the numbers themselves, for
:mod:`clothsim.ports.precision`, which turns them into the check's tolerances.
"""

from __future__ import annotations

import numpy as np

#: Values examined at most (evenly spaced over the data): the precision of printed numbers
#: shows in any few thousand of them.
SAMPLE = 20000
#: A float64 written in full needs 15 to 17 digits; fewer than this is printed precision.
FULL = 15
#: Distinct values needed before their digits count as the printed precision: a handful of
#: short numbers (a velocity of 0.01, a grid of 0.25 spacing) are exact, not rounded.
DISTINCT = 30


def _sample(x) -> np.ndarray:
    flat = np.asarray(x, np.float64).ravel()
    flat = flat[np.isfinite(flat) & (flat != 0)]
    if len(flat) > SAMPLE:
        flat = flat[np.linspace(0, len(flat) - 1, SAMPLE).astype(np.int64)]
    return flat


def _digits(value: float) -> int:
    mantissa = repr(abs(float(value))).split("e")[0].replace(".", "")
    return max(1, len(mantissa.strip("0")))


def significant_digits(x) -> int:
    """The most significant digits any value of ``x`` needs to be read back exactly.

    Parameters
    ----------
    x : array_like
        A port's numbers as read (float64).

    Returns
    -------
    int
        1 to 17: 6 for numbers printed with ``%g``, 17 (or 16) for a float64 written in
        full; 17 when there are fewer than :data:`DISTINCT` distinct nonzero finite values
        (too few to tell printed numbers from exact ones).
    """
    values = np.unique(_sample(x))
    if len(values) < DISTINCT:
        return 17
    return max(_digits(v) for v in values)


def float32_valued(x, digits: int | None = None) -> bool:
    """True when (nearly) every value is a float32 number, written exactly or in ≥ 9 digits.

    A float32 printed with ``digits`` ≥ 9 significant digits reads back, in float64, as
    that float32 rounded to ``digits`` digits; a float64 result almost never does (float32
    has only about 7.2 digits). Below 9 digits the two cannot be told apart: False.

    Parameters
    ----------
    x : array_like
        The port's numbers as read (float64).
    digits : int, optional
        Their :func:`significant_digits` (computed when not given).

    Returns
    -------
    bool
    """
    values = _sample(x)
    if not len(values):
        return False
    digits = significant_digits(values) if digits is None else int(digits)
    as32 = values.astype(np.float32).astype(np.float64)
    if digits >= 17:
        same = as32 == values
    elif digits >= 9:
        same = np.array([float(f"{v:.{digits}g}") for v in as32]) == values
    else:
        return False
    return float(np.mean(same)) > 0.99


def unit(digits: int) -> float:
    """Relative rounding of a number printed with ``digits`` significant digits: ½ 10^(1−d).

    Parameters
    ----------
    digits : int

    Returns
    -------
    float
    """
    return 0.5 * 10.0 ** (1 - int(digits))


def describe(digits: int) -> str:
    """The phrase the verdict uses: "printed with 6 significant digits".

    Parameters
    ----------
    digits : int

    Returns
    -------
    str
    """
    return f"printed with {digits} significant digit{'s' if digits != 1 else ''}"


__all__ = ["FULL", "describe", "float32_valued", "significant_digits", "unit"]
