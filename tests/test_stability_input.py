"""Bad input on the core API (issue 5): NaN or infinite numbers, negative stiffness, non-
positive mass or h, too few iterations, bad pins → InputError with one line naming the
field and the index."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import clothsim as cs
from clothsim.errors import InputError
from clothsim.gallery import GRAVITY
from clothsim.gallery import grid_cloth as make_grid_model

NAN, INF = float("nan"), float("inf")


def grid_parts():
    mesh = cs.grid(4, 4, size=(1.0, 1.0), plane="xz")
    springs = cs.grid_springs(mesh, structural=100.0, shear=100.0, bending=10.0)
    return mesh, springs


def with_value(a, index, value):
    a = np.array(a, dtype=np.float64)
    a[index] = value
    return a


def bad_positions(value):
    mesh, _ = grid_parts()
    cs.Mesh(with_value(mesh.vertices, (3, 1), value), mesh.triangles)


def bad_mass(value):
    mesh, springs = grid_parts()
    cs.Model.build(mesh, springs, vertex_mass=with_value(np.full(16, 0.1), 7, value))


def bad_stiffness(value):
    _, s = grid_parts()
    cs.Springs(s.spring_vertices, with_value(s.spring_stiffness, 5, value),
               s.spring_rest_length, s.spring_family)


def bad_state(value):
    model = make_grid_model(4)
    x = with_value(model.mesh.vertices, (2, 0), value)
    cs.Simulation(model, h=0.1, state=cs.State(x, np.zeros_like(x))).step()


def bad_velocity(value):
    model = make_grid_model(4)
    x = model.mesh.vertices.copy()
    cs.Simulation(model, h=0.1, state=cs.State(x, with_value(np.zeros_like(x), (9, 2), value))
                  ).step()


def simulation(**options):
    model = make_grid_model(4)
    effects = options.pop("effects", [cs.Gravity(GRAVITY)])
    cs.Simulation(model, effects=effects, **{"h": 1 / 30, **options}).step()


CASES = [
    # (label, callable, message pattern)
    ("positions NaN", lambda: bad_positions(NAN), r"^vertices\[3, 1\]: must be a finite number"),
    ("positions inf", lambda: bad_positions(INF), r"^vertices\[3, 1\]: must be a finite number"),
    ("state NaN", lambda: bad_state(NAN), r"^state\.positions\[2, 0\]: must be a finite"),
    ("velocity inf", lambda: bad_velocity(-INF), r"^state\.velocities\[9, 2\]: must be a finite"),
    ("mass NaN", lambda: bad_mass(NAN), r"^vertex_mass\[7\]: must be a finite number"),
    ("mass inf", lambda: bad_mass(INF), r"^vertex_mass\[7\]: must be a finite number"),
    ("mass negative", lambda: bad_mass(-1.0),
     r"^vertex_mass\[7\]: must be non-negative, got -1\.0"),
    ("total mass", lambda: cs.Model.build(*grid_parts(), total_mass=-2.0),
     r"^mass: must be positive"),
    ("stiffness NaN", lambda: bad_stiffness(NAN), r"^spring_stiffness\[5\]: must be a finite"),
    ("stiffness negative", lambda: bad_stiffness(-3.0),
     r"^spring_stiffness\[5\]: must be non-negative, got -3\.0"),
    ("family stiffness inf", lambda: cs.grid_springs(grid_parts()[0], structural=INF),
     r"^springs\.structural: must be a finite number"),
    ("family stiffness negative", lambda: cs.grid_springs(grid_parts()[0], shear=-1.0),
     r"^springs\.shear: must be non-negative"),
    ("h NaN", lambda: simulation(h=NAN), r"^h: must be a finite number"),
    ("h inf", lambda: simulation(h=INF), r"^h: must be a finite number"),
    ("h zero", lambda: simulation(h=0.0), r"^h: the time step must be positive, got 0\.0"),
    ("h negative", lambda: simulation(h=-0.1), r"^h: the time step must be positive"),
    ("gravity NaN", lambda: cs.Gravity((0.0, NAN, 0.0)),
     r"^gravity\.acceleration\[1\]: must be a finite number"),
    ("iterations zero", lambda: simulation(iterations=0), r"^solver\.iterations: must be an "
     r"integer >= 1, got 0"),
    ("iterations negative", lambda: simulation(iterations=-5), r"^solver\.iterations:"),
    ("tolerance NaN", lambda: simulation(tolerance=NAN), r"^solver\.tolerance: must be a finite"),
    ("pin out of range", lambda: simulation(effects=[cs.Pin([0, 16])]),
     r"^pin\.vertices\[1\]: vertex 16 out of range 0\.\.15"),
    ("pin negative", lambda: simulation(effects=[cs.Pin([-1, 2])]),
     r"^pin\.vertices\[0\]: vertex -1 out of range"),
    ("pin duplicated", lambda: simulation(effects=[cs.Pin([3, 5, 3])]),
     r"^pin\.vertices: vertex 3 is listed twice"),
    ("pin in two pins", lambda: simulation(effects=[cs.Pin([3]), cs.Pin([3], method="penalty")]),
     r"^effects\.pin: vertex 3 is pinned by more than one pin"),
    ("pin stiffness NaN", lambda: cs.Pin([0], method="penalty", stiffness=NAN),
     r"^pin\.stiffness: must be a finite number"),
]


@pytest.mark.parametrize("label, make, pattern", CASES, ids=[c[0] for c in CASES])
def test_bad_input_raises_one_line_input_error(label, make, pattern):
    with pytest.raises(InputError, match=pattern) as info:
        make()
    assert "\n" not in str(info.value)


@settings(max_examples=25, deadline=None)
@given(field=st.sampled_from(["positions", "vertex_mass", "spring_stiffness"]),
       data=st.data(), value=st.sampled_from([NAN, INF, -INF]))
def test_nan_at_random_index_is_named(field, data, value):
    mesh, springs = grid_parts()
    if field == "positions":
        i = data.draw(st.integers(0, mesh.vertex_count - 1), label="vertex")
        j = data.draw(st.integers(0, 2), label="coordinate")
        with pytest.raises(InputError, match=rf"^vertices\[{i}, {j}\]: ") as info:
            cs.Mesh(with_value(mesh.vertices, (i, j), value), mesh.triangles)
    elif field == "vertex_mass":
        i = data.draw(st.integers(0, mesh.vertex_count - 1), label="vertex")
        with pytest.raises(InputError, match=rf"^vertex_mass\[{i}\]: ") as info:
            cs.Model.build(mesh, springs, vertex_mass=with_value(np.ones(16), i, value))
    else:
        i = data.draw(st.integers(0, springs.spring_count - 1), label="spring")
        with pytest.raises(InputError, match=rf"^spring_stiffness\[{i}\]: ") as info:
            springs.with_stiffness(with_value(springs.spring_stiffness, i, value))
    assert "\n" not in str(info.value) and "finite" in str(info.value)


def test_blow_up_mid_run_is_named_not_propagated():
    """A non-finite external force appearing mid-run stops the step naming the effect and vertex."""

    class Faulty(cs.Effect):
        kind = "faulty"

        def add_force(self, t, state, f):
            if state.step == 2:
                f[4, 1] = NAN

    model = make_grid_model(4)
    sim = cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(GRAVITY), Faulty()])
    sim.run(2)
    with pytest.raises(cs.NonFiniteStateError,
                       match=r"external forces became non-finite .*faulty's force on vertex 4 "
                             r"is \[0\.0, nan, 0\.0\]"):
        sim.step()
    assert np.isfinite(sim.state.positions).all()
