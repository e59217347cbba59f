"""The hash a run records of its scene and model, which ``--resume`` checks
(:func:`scene_hash`): the resolved scene's text and the model's arrays, in two parts so
that :func:`clothsim.runner.run_scene` hashes the arrays on a thread while the simulation
is built."""

from __future__ import annotations

import copy
import hashlib
import json

import numpy as np


def scene_hash(scene, model) -> str:
    """SHA-256 (hex, 16 digits) of the resolved scene (without ``scene.frames`` and the
    ``[output]`` table, which change no state) and the model's arrays: what ``resume``
    checks before continuing a run.

    Parameters
    ----------
    scene : Scene
        The resolved scene.
    model : Model
        Built from it: vertices [m], springs, stiffnesses [N/m], rest lengths [m], masses [kg].

    Returns
    -------
    str
        16 hexadecimal digits.
    """
    digest = scene_digest(scene)
    digest_model(digest, model)
    return digest.hexdigest()[:16]


def scene_digest(scene):
    """:func:`scene_hash`'s SHA-256 object after the resolved scene's text.

    Parameters
    ----------
    scene : Scene

    Returns
    -------
    hashlib._Hash
    """
    doc = copy.deepcopy(scene.to_dict())
    doc.get("scene", {}).pop("frames", None)
    doc.pop("output", None)
    return hashlib.sha256(json.dumps(doc, sort_keys=True, default=str).encode())


def digest_model(digest, model) -> None:
    """Feed the model's arrays to ``digest`` (their bytes, read in place: hashlib lets go of
    Python's lock over them, so this runs on a second core beside the simulation's build).

    Parameters
    ----------
    digest : hashlib._Hash
        :func:`scene_digest`'s.
    model : Model

    Returns
    -------
    None
    """
    s = model.springs
    for a in (model.mesh.vertices, model.mesh.triangles, model.mesh.strands, s.spring_vertices,
              s.spring_stiffness, s.spring_rest_length, model.vertex_mass):
        digest.update(np.ascontiguousarray(a).reshape(-1).view(np.uint8))


__all__ = ["scene_hash", "scene_digest", "digest_model"]
