"""Pins a cloth's files declare, and how ``[cloth] pin_method`` / ``pin_stiffness`` hold them.

Two kinds of file declare pins:

- a ``jacobson`` cloth's JSON ``b`` list. The assignment's ``main.cpp`` holds these by a
  penalty spring of rest length 0 and stiffness w = 1e10 N/m to the initial position, so
  that is the default (:data:`ASSIGNMENT_PIN_STIFFNESS`);
- a spring table's attachment rows (``b`` = −1): penalty pins of the row's stiffness.

``pin_method = "constraint"`` holds them exactly instead (removed from the unknowns);
``pin_stiffness`` replaces the stiffness of every such penalty pin. Pins declared as
``[[effects]] kind = "pin"`` have their own ``method`` and ``stiffness`` and are not
affected.
"""

from __future__ import annotations

from ..effects import Pin
from .checks import Invalid

#: The assignment's pin penalty w [N/m] (``main.cpp``: ``const double w = 1e10``).
ASSIGNMENT_PIN_STIFFNESS = 1e10


def declared_pins(cloth: dict, assignment_pins, table) -> list[tuple[str, Pin]]:
    """The pin effects the cloth's files declare, each with the scene key it comes from.

    Parameters
    ----------
    cloth : dict
        The validated ``[cloth]`` table (``pin_method``, optional ``pin_stiffness`` [N/m]).
    assignment_pins : ndarray of int, shape (p,), or None
        A ``jacobson`` cloth's pinned vertices (0-based), None for other shapes.
    table : SpringTable or None
        The spring table, whose attachment rows are pins (None without a table).

    Returns
    -------
    list of (str, Pin)
        ``("cloth.file", Pin)`` for the assignment's pins, then ``("springs.table", Pin)``
        per attachment stiffness (one exact Pin with ``pin_method = "constraint"``).

    Raises
    ------
    Invalid
        At ``cloth.pin_stiffness`` when it is given but the files declare no pin.
    """
    method, k = cloth["pin_method"], cloth.get("pin_stiffness")
    if k is not None and not ((assignment_pins is not None and len(assignment_pins))
                              or (table is not None and len(table.attached))):
        raise Invalid("cloth.pin_stiffness", "the cloth's files declare no pins (a jacobson "
                      "JSON's b, a spring table's attachment rows), so it would hold nothing; "
                      "a pin effect has its own 'stiffness'")
    out = []
    if assignment_pins is not None:
        out.append(("cloth.file", Pin(assignment_pins, method=method,
                                      stiffness=ASSIGNMENT_PIN_STIFFNESS if k is None else k)))
    if table is not None and len(table.attached):
        if method == "constraint":
            out.append(("springs.table", Pin(table.attached)))
        elif k is not None:
            out.append(("springs.table", Pin(table.attached, method="penalty", stiffness=k)))
        else:
            for stiffness in dict.fromkeys(table.attached_stiffness.tolist()):
                vs = table.attached[table.attached_stiffness == stiffness]
                out.append(("springs.table", Pin(vs, method="penalty", stiffness=stiffness)))
    return out


__all__ = ["ASSIGNMENT_PIN_STIFFNESS", "declared_pins"]
