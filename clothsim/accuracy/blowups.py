"""What a solver run that blows up raises, for the study to record it and go on."""

from __future__ import annotations

import numpy as np

from ..errors import ClothsimError

BLOW_UPS = (ClothsimError, FloatingPointError, OverflowError, ValueError, ZeroDivisionError,
            np.linalg.LinAlgError)
"""What a configuration that blows up raises (a non-finite state or force, a failed
factorization): recorded as diverged, the study goes on."""
