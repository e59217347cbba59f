"""Hostile input, round 3: the magnitudes round 2 left to the Python API, the Makefile's
paths with spaces, and the earlier rounds' fixes re-checked on variants they were not built
for.

Each case is a reproducer of a finding (it failed before its fix): one line naming the key
or argument, or a run that stays finite and moves.
"""

from __future__ import annotations

import numpy as np
import pytest

import clothsim as cs
from clothsim.cli import main
from clothsim.errors import InputError


def _one_line(capsys, code, expected_code=2) -> str:
    err = capsys.readouterr().err
    assert code == expected_code and err.count("\n") == 1, (code, err)
    assert "Error:" not in err and "Traceback" not in err, err
    return err.strip().removeprefix("clothsim: error: ")


def _model(k=800.0, mass=1.0):
    mesh = cs.grid(11, 11, size=(1.0, 1.0), center=(0.0, 1.0, 0.0), plane="xy")
    return cs.Model.build(mesh, cs.grid_springs(mesh, structural=k, shear=k, bending=k / 10),
                          total_mass=mass)


def _effects(g=-9.81):
    return [cs.Gravity((0.0, g, 0.0)), cs.Pin([110, 120])]


# ------------------------------------------------------------------ the Python API's magnitudes
# (Simulation(...) arguments, the field the error names, a piece of the condition it states);
# before: FactorizationError or OverflowError from CHOLMOD / Python, NonFiniteStateError at
# the first step, or a cloth that silently never moved (residual 0, 10 iterations)
API_REFUSED = {
    "h=1e300": (dict(h=1e300), "h", "h² = inf s² overflows float64"),  # was FactorizationError
    "h=1e300 newton": (dict(h=1e300, solver="newton"), "h", "overflows float64"),  # OverflowError
    "h=1e300 symplectic": (dict(h=1e300, solver="symplectic-euler"), "h", "overflows float64"),
    "h=1e-300": (dict(h=1e-300), "h", "h² = 0 s² underflows float64"),  # was: frozen
    "h=5e-324": (dict(h=5e-324), "h", "underflows float64"),
    "h=1e7": (dict(h=1e7), "h", "the mass is lost in M + h²L"),  # was: frozen (residual 0)
    "h=1e-12": (dict(h=1e-12), "effects[0].acceleration",
                "the motion is lost every step and the cloth would never move"),  # was: frozen
    "mass=1e300": (dict(mass=1e300), "model.vertex_mass", "makes the energy overflow"),
    "mass=1e-300": (dict(mass=1e-300), "h", "h²L_ii/m_i = 9.03e+302"),  # was: frozen
    "mass=1e-20": (dict(mass=1e-20), "h", "the mass is lost in M + h²L"),  # was: frozen
    "k=1e300": (dict(k=1e300), "h", "the mass is lost in M + h²L"),  # was: frozen
    "k=1e20": (dict(k=1e20), "h", "use h < 0.00021 s"),  # was: frozen
    "gravity 1e300": (dict(g=-1e300), "effects[0].acceleration", "h²|f|·√n"),
    "gravity 1e-30": (dict(g=-1e-30), "effects[0].acceleration", "a step longer than 1.8e+07 s"),
    "k=-1": (dict(k=-1.0), "springs.structural", "must be non-negative"),
    "h=nan": (dict(h=float("nan")), "h", "must be a finite number"),
}


@pytest.mark.parametrize("case", list(API_REFUSED))
def test_the_python_api_refuses_magnitudes_float64_cannot_step(case):
    args, field, says = API_REFUSED[case]
    args = dict(args)
    k, mass, g = args.pop("k", 800.0), args.pop("mass", 1.0), args.pop("g", -9.81)
    with pytest.raises(InputError) as info:
        model = _model(k=k, mass=mass)
        args.setdefault("h", 1 / 30)
        cs.Simulation(model, effects=_effects(g), **args)
    message = str(info.value)
    assert "\n" not in message and message.startswith(f"{field}: "), message
    assert says in message, message
    assert getattr(info.value, "field", None) in (field, None), info.value.field


@pytest.mark.parametrize("k, mass, g, h", [
    (0.0, 1.0, -9.81, 1 / 30),       # no springs: free fall
    (1e-300, 1.0, -9.81, 1 / 30),    # springs too soft to matter
    (800.0, 1e100, -9.81, 1 / 30),   # heavy: falls freely
    (800.0, 1.0, -1e100, 1 / 30),    # a huge gravity within the bounds: moves, finite
    (800.0, 1.0, -1e9, 1 / 30),
    (800.0, 1.0, -9.81, 1e-8),       # the shortest step that resolves gravity here
    (800.0, 1.0, -9.81, 1e4),        # long: M + h²L still factors in float64
])
def test_magnitudes_within_the_bounds_run_finite_and_move(k, mass, g, h):
    sim = cs.Simulation(_model(k=k, mass=mass), h=h, effects=_effects(g))
    x0 = sim.state.positions.copy()
    sim.run(3)
    x = sim.state.positions
    assert np.isfinite(x).all() and np.isfinite(sim.state.velocities).all()
    assert np.abs(x - x0).max() > 0, "the cloth froze"  # gravity moves the free vertices


def test_the_bound_on_a_short_step_is_where_the_motion_is_lost():
    """1e-8 s runs (gravity moves the cloth by 1e-15 m a step, above ε·1.5 m = 3.3e-16 m);
    1e-9 s is refused: x + h²g rounds back to x there and the velocity stays 0 for ever;
    2e-9 s too: only the lowest row would fall (its coordinates round more finely), the
    cloth torn by rounding."""
    mesh = cs.grid(11, 11, size=(1.0, 1.0), center=(0.0, 1.0, 0.0), plane="xy")
    model = cs.Model.build(mesh, cs.grid_springs(mesh, structural=0.0), total_mass=1.0)
    x0 = mesh.vertices
    for h, moving in ((1e-9, 0), (2e-9, 11)):  # what a step would move: nothing, one row
        moved = (x0 + h * h * np.array([0.0, -9.81, 0.0]) != x0).any(axis=1)
        assert np.count_nonzero(moved) == moving
        with pytest.raises(InputError, match="would never move"):
            cs.Simulation(model, h=h, effects=[cs.Gravity()])
    sim = cs.Simulation(model, h=1e-8, effects=[cs.Gravity()])
    sim.run(2)
    assert (sim.state.velocities[:, 1] < 0).all()


@pytest.mark.parametrize("change, key, says", [
    ("scene.fps=1e9", "effects[0].acceleration", "a step of h = 1e-09 s"),
    ("effects[0].acceleration=[0, -1e-30, 0]", "effects[0].acceleration", "never move"),
    ("effects[0].acceleration=[0, -1e300, 0]", "effects[0].acceleration", "h²|f|·√n"),
    ("springs.structural=1e20", "springs.structural", "the mass is lost in M + h²L"),
    ("cloth.mass=1e-300", "springs.structural", "the mass is lost in M + h²L"),
    ("cloth.mass=1e300", "cloth.mass", "makes the energy overflow"),
    ("scene.fps=1e-300", "scene.fps", "must be between"),
    ("scene.h=inf", "scene.h", "must be a finite number, got inf"),
])
def test_scene_magnitudes_exit_2_naming_the_key(tmp_path, capsys, change, key, says):
    out = tmp_path / "o"
    code = main(["run", "hanging", "--frames", "2", "--no-preview", "--out", str(out),
                 "--set", change])
    line = _one_line(capsys, code)
    assert line.startswith(f"--set {change}: {key}: ") and says in line, line
    assert not out.exists()


@pytest.mark.parametrize("h, says", [("1e300", "must be between"), ("1e-300", "must be between"),
                                     ("inf", "must be a finite number"),
                                     ("nan", "must be a finite number")])
def test_a_scene_files_h_out_of_float64s_reach_is_one_line(tmp_path, capsys, h, says):
    p = tmp_path / "s.toml"
    p.write_text(f"[scene]\nh = {h}\n")
    line = _one_line(capsys, main(["validate", str(p)]))
    assert line.startswith(f"{p}: scene.h: {says}"), line


def test_an_effect_after_the_cloth_files_pins_is_named_by_its_own_index(tmp_path, capsys):
    """A spring table's attachment is a pin that comes before the declared effects: the
    Simulation's effects[1] is the scene's effects[0]."""
    (tmp_path / "t.txt").write_text("0 -1 1000 0\n")
    p = tmp_path / "s.toml"
    p.write_text('[cloth]\nresolution = [5, 5]\n[springs]\ntable = "t.txt"\n'
                 '[[effects]]\nkind = "gravity"\nacceleration = [0, -1e-30, 0]\n')
    line = _one_line(capsys, main(["validate", str(p)]))
    assert line.startswith(f"{p}: effects[0].acceleration: gravity's largest"), line
