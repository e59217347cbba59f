"""The scene key behind a Simulation's refusal or warning.

A scene builds its :class:`~clothsim.simulation.Simulation` with the pins its cloth files
declare (a spring table's attachments, an assignment's ``b``) before its own
``[[effects]]``, so the simulation's ``effects[i]`` is not the scene's. These functions map
what the simulation names back to the key a user wrote.
"""

from __future__ import annotations

import re
import warnings

from ..errors import InputError, SceneError
from .checks import locate


def scene_path(scene, model, field: str) -> str | None:
    """The scene key of a Simulation's ``effects[i]…`` field, or None for any other field.

    Parameters
    ----------
    scene : Scene
    model : Model
        The model the simulation was built on.
    field : str
        E.g. ``"effects[1].velocity"``.

    Returns
    -------
    str or None
        E.g. ``"effects[0].velocity"`` in a scene whose spring table adds one pin.
    """
    if at := re.fullmatch(r"effects\[(\d+)\](.*)", field):
        return scene._effects(model)[int(at[1])][0] + at[2]
    return None


def located(scene, exc: InputError, model, h: float) -> SceneError:
    """The scene error for a Simulation's refusal: the effect whose binding fails alone,
    else the scene key of the field the refusal names.

    Parameters
    ----------
    scene : Scene
    exc : InputError
        What the simulation raised.
    model : Model
    h : float
        Time step [s].

    Returns
    -------
    SceneError
    """
    for path, effect in scene._effects(model):
        try:
            effect.bind(model, h)
        except InputError as err:
            if not path.startswith("effects["):  # a pin the cloth's files declare
                if err.field == "pin.stiffness" and "pin_stiffness" in scene.data["cloth"]:
                    return scene._error("cloth.pin_stiffness", str(err).split(": ", 1)[1])
                label = "b" if path == "cloth.file" else "attachments"
                return scene._error(path, f"{label}: {err}")
            return scene._error(*locate(err, path, effect.kind, path))
    msg = " ".join(str(exc).split())
    fld, _, rest = msg.partition(": ")
    fld = getattr(exc, "field", None) or fld
    if (path := scene_path(scene, model, fld)) and rest:
        return scene._error(path, rest)
    if rest and fld.startswith("solver."):
        return scene._error(fld, rest)
    if rest and fld.startswith("effects."):
        return scene._error("effects", rest)
    return scene._error("", msg)


def warn_again(scene, model, caught) -> None:
    """Issue the warnings a Simulation gave while it was built, each ``effects[i]: …``
    renamed to the scene's own key.

    Parameters
    ----------
    scene : Scene
    model : Model
    caught : list of warnings.WarningMessage
        From ``warnings.catch_warnings(record=True)`` around the build.
    """
    for w in caught:
        field, sep, rest = str(w.message).partition(": ")
        path = scene_path(scene, model, field) if sep else None
        warnings.warn(f"{path}: {rest}" if path else w.message, w.category, stacklevel=3)


__all__ = ["located", "scene_path", "warn_again"]
