"""Simulation: the effect protocol as the simulation applies it, and bad input."""

import logging

import numpy as np
import pytest

import clothsim as cs
from clothsim.effects.base import HOOKS, Effect, overrides
from clothsim.errors import InputError, NonFiniteStateError
from clothsim.gallery import GRAVITY, grid_cloth, hanging_cloth


def test_a_pin_shared_by_two_simulations_is_an_error():
    model, (gravity, pin) = hanging_cloth(5)
    first = cs.Simulation(model, h=1 / 30, effects=[gravity, pin])
    with pytest.raises(InputError, match=r"effects\[0\] \(pin\): already bound to another "
                                         r"simulation; create one effect per simulation"):
        cs.Simulation(model, h=1 / 30, effects=[pin])
    # the first simulation is untouched: its pinned corners stay put
    first.run(5)
    top = [20, 24]
    np.testing.assert_array_equal(first.state.positions[top], model.mesh.vertices[top])


def test_effects_are_fixed_when_the_simulation_is_built():
    """A later change to Simulation.effects would be ignored (issues 34, 35): every way a
    list allows one is refused by name, and the simulation runs exactly what it was built
    with."""
    model, (gravity, pin) = hanging_cloth(5)
    sim = cs.Simulation(model, h=1 / 30, effects=[pin])
    ref = cs.Simulation(model, h=1 / 30, effects=[cs.Pin([20, 24])])
    wind = cs.Force((1.0, 0.0, 0.0))
    attempts = [lambda: sim.effects.append(gravity), lambda: sim.effects.extend([gravity]),
                lambda: sim.effects.insert(0, gravity), lambda: sim.effects.remove(pin),
                lambda: sim.effects.pop(), lambda: sim.effects.clear(),
                lambda: sim.effects.__setitem__(0, gravity),
                lambda: sim.effects.__delitem__(0)]
    for attempt in attempts:
        with pytest.raises(InputError, match=r"^Simulation\.effects: fixed when the simulation "
                                             r"is built .* pass every effect to Simulation"):
            attempt()
    with pytest.raises(InputError, match=r"^Simulation\.effects: fixed"):
        sim.effects += [wind]
    with pytest.raises(InputError, match=r"^Simulation\.effects: fixed"):
        sim.effects = [pin, gravity]
    assert list(sim.effects) == [pin] and sim.effects_built == ["pin"]
    # read access is a tuple's: indexing, iteration, len, equality, concatenation
    assert sim.effects[0] is pin and len(sim.effects) == 1 and sim.effects == (pin,)
    assert isinstance(sim.effects, tuple) and sim.effects + (wind,) == (pin, wind)
    sim.run(3)                             # no gravity: the cloth stays at rest, as built
    ref.run(3)
    np.testing.assert_array_equal(sim.state.positions, model.mesh.vertices)
    np.testing.assert_array_equal(sim.state.positions, ref.state.positions)
    # the massless pin clothsim adds is in the tuple too, first
    massless = cs.Model.build(model.mesh, model.springs,
                              vertex_mass=np.r_[0.0, model.vertex_mass[1:]])
    auto = cs.Simulation(massless, h=1 / 30, effects=[cs.Gravity()])
    assert auto.effects_built == ["pin", "gravity"] and isinstance(auto.effects, tuple)
    with pytest.raises(InputError, match=r"^Simulation\.effects"):
        auto.effects.append(cs.Gravity())


def test_failed_construction_does_not_claim_the_effects():
    model = grid_cloth(4)
    pin = cs.Pin([0, 3])
    with pytest.raises(InputError):
        cs.Simulation(model, h=-1.0, effects=[pin])
    cs.Simulation(model, h=0.1, effects=[pin])   # still free to use


def test_hooks_receive_h_from_bind():
    seen = {}

    class Recorder(Effect):
        kind = "recorder"

        def adjust_target(self, t, state, y):
            seen["h"] = self.h
            return y

    sim = cs.Simulation(grid_cloth(3), h=0.025, effects=[Recorder()])
    sim.step()
    assert seen["h"] == 0.025
    assert HOOKS[-1] == "connect_pins"
    assert [h for h in HOOKS if overrides(Recorder(), h)] == ["adjust_target"]


def test_connect_pins_is_handed_the_pin_query():
    class Listener(Effect):
        kind = "listener"

        def connect_pins(self, pinned):
            self.pinned = pinned

    model = grid_cloth(4)
    listener = Listener()
    cs.Simulation(model, h=0.1, effects=[cs.Pin([3, 0]), listener])
    np.testing.assert_array_equal(listener.pinned(0.1), [0, 3])


@pytest.mark.parametrize("state, match", [
    (lambda x: cs.State(x, np.zeros_like(x), time=float("nan")), "state.time"),
    (lambda x: cs.State(x[:-1], np.zeros_like(x[:-1])), r"state.positions: expected shape"),
    (lambda x: cs.State(x, np.zeros((3, 3))), "state.velocities: expected shape"),
])
def test_bad_state_is_named(state, match):
    model = grid_cloth(4)
    with pytest.raises(InputError, match=match):
        cs.Simulation(model, h=0.1, state=state(model.mesh.vertices.copy()))


def test_record_converged_is_none_without_tolerance_and_a_bool_with_one():
    model, effects = hanging_cloth(5)
    rec = cs.Simulation(model, h=1 / 30, effects=effects).step()
    assert rec.converged is None
    model, effects = hanging_cloth(5)
    rec = cs.Simulation(model, h=1 / 30, effects=effects, tolerance=1e-6,
                        iterations=500).step()
    assert rec.converged is True and rec.residual <= 1e-6


def test_obstacle_overlapping_the_cloth_at_start_warns_with_the_count(caplog):
    model = grid_cloth(5, center=(0.0, 0.0, 0.0))          # flat in xz at y = 0
    with caplog.at_level(logging.WARNING, logger="clothsim.simulation"):
        sphere = cs.Sphere((0.0, 0.0, 0.0), 0.3)
        cs.Simulation(model, h=0.1, effects=[cs.Gravity(GRAVITY), sphere])
    # inside the contact surface: the sphere grown by its "auto" thickness
    inside = int(np.count_nonzero(np.linalg.norm(model.mesh.vertices, axis=1)
                                  < 0.3 + sphere.margin))
    assert inside > 0
    assert f"{inside} of 25 cloth vertices start inside" in caplog.text
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="clothsim.simulation"):
        cs.Simulation(model, h=0.1, effects=[cs.Sphere((0.0, -1.0, 0.0), 0.3)])
    assert "start inside" not in caplog.text


def test_pin_release_must_not_be_negative():
    with pytest.raises(InputError, match="pin.release: must be a time >= 0"):
        cs.Pin([0], release=-1.0)


def test_huge_plane_normal_is_normalized_and_huge_sphere_rejected():
    plane = cs.Plane((0, 0, 0), (1e300, 1e300, 0))
    np.testing.assert_allclose(plane.normal, [2 ** -0.5, 2 ** -0.5, 0.0], rtol=1e-15)
    with pytest.raises(InputError, match="sphere.radius: must be at most"):
        cs.Sphere((0, 0, 0), 1e200)


def test_a_blowup_raises_and_keeps_the_last_finite_state():
    """Explicit Euler far above its stability limit overflows: the step that produces a
    non-finite state raises NonFiniteStateError (not InputError: the input was fine) and
    the simulation keeps the state before it."""
    model = grid_cloth(4, k=1e9, plane="xy")
    sim = cs.Simulation(model, h=1 / 30, solver="symplectic-euler", check_stability=False,
                        effects=[cs.Gravity(GRAVITY), cs.Pin([12, 15])])
    with np.errstate(all="ignore"), pytest.raises(NonFiniteStateError) as info:
        for _ in range(200):
            sim.step()
    assert not isinstance(info.value, InputError)
    assert str(info.value).startswith("the state became non-finite at ")
    assert np.isfinite(sim.state.positions).all() and np.isfinite(sim.state.velocities).all()
    assert sim.state.step < 200
