"""Effects a scene can declare; only declared ones are built and run.

See :mod:`clothsim.effects.base` for the hooks an effect implements and docs/effects.md for
the models. :data:`EFFECTS` maps a scene's ``kind`` to the class; the scene parser calls
``EFFECTS[kind](**params)``.
"""

from .base import Effect, PinSet, overrides
from .box import Box
from .damping import Damping
from .force import Force
from .gravity import Gravity
from .impulse import Impulse
from .obstacles import Obstacle
from .pins import Pin
from .plane import Plane
from .sphere import Sphere
from .strain_limit import StrainLimit
from .wind import Wind

EFFECTS: dict[str, type[Effect]] = {
    "gravity": Gravity,
    "force": Force,
    "pin": Pin,
    "plane": Plane,
    "sphere": Sphere,
    "box": Box,
    "impulse": Impulse,
    "wind": Wind,
    "damping": Damping,
    "strain-limit": StrainLimit,
}

__all__ = ["Effect", "PinSet", "overrides", "Gravity", "Force", "Pin", "Plane", "Sphere", "Box",
           "Obstacle", "Impulse", "Wind", "Damping", "StrainLimit", "EFFECTS"]
