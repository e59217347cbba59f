"""clothsim export writes the contact planes each step holds (contacts.txt, contacts.npz), so
a port implementing the hold mode can solve the same constrained steps."""

import tomllib

import numpy as np

from clothsim.ports.export import export_port
from clothsim.scene import Scene, builtin_scene_text


def scene(mode: str) -> Scene:
    doc = tomllib.loads(builtin_scene_text("drop-on-square"))
    doc["cloth"]["resolution"] = [9, 9]
    doc["contact"] = {"mode": mode}
    return Scene.from_dict(doc, source="drop-on-square.toml")


def test_export_writes_the_held_planes_of_every_step(tmp_path):
    frames = 20
    manifest = export_port(scene("hold"), tmp_path / "ref", frames=frames, iterate_steps=1)
    assert {"contacts.txt", "contacts.npz"} <= set(manifest["files"])
    out = tmp_path / "ref"
    text = np.loadtxt(out / "contacts.txt", ndmin=2)
    arrays = np.load(out / "contacts.npz")
    np.testing.assert_array_equal(text[:, 0], arrays["step"])
    np.testing.assert_array_equal(text[:, 1], arrays["vertex"])
    np.testing.assert_array_equal(text[:, 2:5], arrays["normal"])       # %.17g: exact
    np.testing.assert_array_equal(text[:, 5], arrays["offset"])
    # the same planes the simulation's step problems hold
    sim = scene("hold").build_simulation()
    for k in range(frames):
        p = sim.problem()
        rows = arrays["step"] == k
        np.testing.assert_array_equal(arrays["vertex"][rows], p.contact_vertices)
        np.testing.assert_array_equal(arrays["normal"][rows], p.contact_normals)
        np.testing.assert_array_equal(arrays["offset"][rows], p.contact_offsets)
        sim.step()
    assert len(np.unique(arrays["step"])) > frames // 3        # the cloth lands on the box
    # on the box every held vertex ends its step on its plane (held, settled on the face,
    # or released where the solve put it)
    X = np.load(out / "trajectory.npz")["positions"]
    after = X[arrays["step"] + 1, arrays["vertex"]]
    gap = np.einsum("ij,ij->i", after, arrays["normal"]) - arrays["offset"]
    assert np.abs(gap).max() < 1e-12


def test_post_solve_export_has_no_contact_files(tmp_path):
    manifest = export_port(scene("post-solve"), tmp_path / "ref", frames=3, iterate_steps=1)
    assert "contacts.txt" not in manifest["files"]
    assert not (tmp_path / "ref" / "contacts.txt").exists()
