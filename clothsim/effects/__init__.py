"""Effects a scene can declare; only declared ones are built and run.

See :mod:`clothsim.effects.base` for the hooks an effect implements.
"""

from .base import Effect, PinSet, overrides
from .gravity import Gravity
from .pins import Pin

EFFECTS: dict[str, type[Effect]] = {
    "gravity": Gravity,
    "pin": Pin,
}

__all__ = ["Effect", "PinSet", "overrides", "Gravity", "Pin", "EFFECTS"]
