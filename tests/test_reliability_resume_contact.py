"""--resume on a cloth in contact: bit for bit, as an uninterrupted run (docs/reliability.md).

In the obstacles' default contact mode, ``"hold"``, a step starts from the contacts the
previous step held (which vertices, their planes, sticking or sliding, normal forces:
:class:`clothsim.effects.holding.Holding`). The run record keeps the solver's state but
not that one, so a run resumed while the cloth lies on the box starts with no contact held
and leaves the uninterrupted trajectory at once (1–2 cm at the next frame on
drop-on-square, drape-sphere and impulse, at 9² to 65²). The test below is the promise;
it is marked xfail (strict) until the effects' state is saved with the solver's.
"""

import numpy as np
import pytest

from clothsim.runner import run_scene
from clothsim.scene import load_scene


def resumed_and_full(tmp_path, *overrides):
    scene = load_scene("drop-on-square", ["cloth.resolution=[9, 9]", *overrides])
    part, full = tmp_path / "part", tmp_path / "full"
    run_scene(scene, part, frames=25, preview=False)        # on the box by frame 20
    run_scene(scene, part, frames=30, preview=False, resume=True)
    run_scene(scene, full, frames=30, preview=False)
    return (np.load(part / "trajectory.npz")["positions"],
            np.load(full / "trajectory.npz")["positions"])


def test_resume_in_post_solve_contact_is_bit_for_bit(tmp_path):
    a, b = resumed_and_full(tmp_path, 'contact.mode="post-solve"')
    assert np.array_equal(a, b)


@pytest.mark.xfail(strict=True, reason="the held contacts are not saved for --resume: "
                   "a resumed run starts with none held")
def test_resume_in_held_contact_is_bit_for_bit(tmp_path):
    a, b = resumed_and_full(tmp_path)
    assert np.array_equal(a[:26], b[:26])                  # the frames before the resume
    assert np.array_equal(a, b), f"{np.abs(a - b).max():.3e} m apart after the resume"
