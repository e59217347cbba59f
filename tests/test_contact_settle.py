"""benchmarks.contact_settle's own arithmetic: the hem band, the held normal forces in units
of the weight and the noise, and its report on a tiny drape."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

from benchmarks.contact_settle import border_band, held_forces, settle
from clothsim.contacts import ContactSet
from clothsim.effects.holding import Holding
from clothsim.mesh import grid


@pytest.mark.parametrize("n, rings", [(9, 0), (9, 1), (9, 3), (12, 2), (5, 2)])
def test_border_band_is_the_rings_of_a_grid(n, rings):
    """On an n × n grid (diagonals included) the band of r rings is every vertex within
    r rows or columns of the border: n² − (n − 2(r + 1))² vertices."""
    mesh = grid(n, n)
    band = border_band(mesh, rings).reshape(n, n)
    i, j = np.indices((n, n))
    ring = np.minimum.reduce([i, j, n - 1 - i, n - 1 - j])
    assert np.array_equal(band, ring <= rings)
    assert band.sum() == n * n - max(n - 2 * (rings + 1), 0) ** 2


def test_border_band_of_a_single_triangle_and_no_triangles():
    from clothsim.mesh import Mesh

    tri = Mesh(np.eye(3), np.array([[0, 1, 2]]))
    assert border_band(tri, 0).all()
    strand = Mesh(np.eye(3)[:2], np.zeros((0, 3), np.int64), strands=np.array([[0, 1]]))
    assert not border_band(strand, 2).any()   # no triangle: no border


def test_held_forces_in_units_of_weight_and_noise():
    """A pressed vertex, a pulled one and a sticking one whose tangential planes carry
    force: only the normal part counts, divided by m g and by the noise."""
    x = np.zeros((4, 3))
    n = np.array([[0.0, 1.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
    h = Holding(x, np.array([0, 2, 3]), n, np.array([False, False, True]))
    planes = h.planes
    assert len(planes) == 5                      # 3 normals, 2 tangents of the sticking one
    planes.forces = np.array([0.3, -0.1, 0.2, 5.0, -7.0])
    planes.noise = 0.05
    weight = np.array([0.1, 9.0, 0.2, 0.4])
    v, per_weight, per_noise = held_forces(h, weight)
    assert v.tolist() == [0, 2, 3]
    assert per_weight == pytest.approx([3.0, -0.5, 0.5])
    assert per_noise == pytest.approx([6.0, -2.0, 4.0])
    planes.noise = 0.0                            # an exact solve: the sign alone
    _, _, per_noise = held_forces(h, weight)
    assert per_noise.tolist() == [np.inf, -np.inf, np.inf]
    empty = Holding()
    assert empty.planes.__class__ is ContactSet
    assert [len(a) for a in held_forces(empty, weight)] == [0, 0, 0]


def test_settle_reports_the_last_frames_and_the_sphere():
    """A 9² drape for 14 frames (the cloth reaches the sphere in its 6th): one line per
    reported frame with the four groups, and the below-equator summary last."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lines = list(settle("drape-sphere", 9, frames=14, last=3))
    assert len(lines) == 4
    for f, line in zip((11, 12, 13), lines):
        m = re.match(rf"frame +{f}: max \|v\| ([\d.]+) m/s \(held ([\d.]+), hem ([\d.]+), "
                     rf"near ([\d.]+), free ([\d.]+)\); (\d+) vertices", line)
        assert m, line
        top, *parts = (float(g) for g in m.groups()[:5])
        assert top == pytest.approx(max(parts), abs=1e-4)
    assert re.match(r"held below the sphere's equator after the last step: \d+ of [1-9]\d* "
                    r"held", lines[-1]), lines[-1]


def test_resolve_solves_one_step_again_from_the_same_state():
    """Frame 8 of a 9² drape (the cloth on the sphere), solved again with 50 iterations
    (the scene's: the run's own step, distance 0 from itself) and with 5: a truncated
    solve lands elsewhere; the state it starts from is the same for both."""
    from benchmarks.contact_settle import resolve

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lines = list(resolve("drape-sphere", 9, 8, (50, 5, 50)))
    pattern = (r"frame 8 solved with (\d+) iterations: residual \S+, max \|v\| ([\d.]+) m/s "
               r"\(hem ([\d.]+)\), \d+ vertices at 0.02 m/s or faster; positions ([\d.]+) mm "
               r"from the first; (\d+) held below the equator, normal force / \(m g\) \S+, "
               r"(\d+) pulled away \(noise \S+ m g\)")
    got = [re.match(pattern, line) for line in lines]
    assert all(got), lines
    assert [int(m.group(1)) for m in got] == [50, 5, 50]
    assert float(got[0].group(4)) == 0.0
    assert float(got[1].group(4)) > 0.0           # 5 iterations: not the same answer
    assert float(got[2].group(4)) == 0.0          # the same state again: the same step
    assert got[0].group(2) == got[2].group(2)
    assert all(int(m.group(6)) <= int(m.group(5)) for m in got)


def test_main_prints_the_report_and_the_resolved_step(capsys):
    from benchmarks.contact_settle import main

    main(["--size", "9", "--frames", "12", "--last", "1"])
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("frame  11: max |v|") and out[1].startswith("held below")
    main(["--size", "9", "--resolve", "7", "--iterations", "50", "20"])
    out = capsys.readouterr().out.splitlines()
    assert [line.split(" iterations")[0] for line in out] == [
        "frame 7 solved with 50", "frame 7 solved with 20"]
