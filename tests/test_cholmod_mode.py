"""CHOLMOD's mode for the global step: chosen by size, overridable, recorded."""

import json

import numpy as np
import pytest

import clothsim as cs
from clothsim import factorization
from clothsim.cli import main
from clothsim.factorization import SUPERNODAL_FROM, choose_cholmod_mode

pytestmark = pytest.mark.skipif(not factorization.cholmod_available(),
                                reason="CHOLMOD (scikit-sparse) is not installed")


def test_small_grids_simplicial_large_supernodal_requests_honoured():
    assert choose_cholmod_mode(33 * 33)[0] == "simplicial"
    mode, reason = choose_cholmod_mode(SUPERNODAL_FROM)
    assert mode == "supernodal" and str(SUPERNODAL_FROM) in reason
    assert choose_cholmod_mode(10, "supernodal") == ("supernodal",
                                                     "supernodal: requested by solver.cholmod_mode")
    with pytest.raises(cs.InputError, match="solver.cholmod_mode"):
        choose_cholmod_mode(10, "fast")


def test_both_modes_give_the_same_step(monkeypatch):
    def step(mode=None):
        scene = cs.load_scene("hanging", [] if mode is None else [f"solver.cholmod_mode={mode}"])
        sim = scene.build_simulation()
        sim.step()
        return sim.state.positions, sim.solver.factorization

    x_auto, why = step()
    assert why.startswith("simplicial: 439 free vertices")
    x_super, why = step("supernodal")
    assert why == "supernodal: requested by solver.cholmod_mode"
    assert np.abs(x_auto - x_super).max() < 1e-12
    monkeypatch.setattr(factorization, "SUPERNODAL_FROM", 100)
    assert step()[1].startswith("supernodal: 439 free vertices >= 100")


def test_run_records_the_choice_and_newton_refuses_the_key(tmp_path):
    assert main(["run", "hanging", "--set", "solver.cholmod_mode=supernodal", "--frames", "1",
                 "--out", str(tmp_path / "r"), "--no-preview"]) == 0
    info = json.loads((tmp_path / "r" / "run.json").read_text())
    assert info["factorization"] == "supernodal: requested by solver.cholmod_mode"
    scene = cs.load_scene("hanging", ["solver.cholmod_mode=simplicial", "solver.method=newton"])
    with pytest.raises(cs.InputError, match="solver.cholmod_mode: applies to the local/global"):
        scene.build_simulation()


def test_a_refactorization_of_the_same_pattern_reuses_the_analysis():
    import dataclasses

    scene = cs.load_scene("hanging")
    sim = scene.build_simulation()
    solver = sim.solver
    p1 = sim.problem()
    solver.system(p1)
    p2 = dataclasses.replace(p1, h=p1.h / 2)           # h changed: same pattern
    x_reused = solver.solve(p2).x.copy()
    assert (solver.factor_count, solver.analysis_count) == (2, 1)
    fresh = cs.load_scene("hanging").build_simulation().solver
    assert np.abs(fresh.solve(p2).x - x_reused).max() < 1e-13
    assert fresh.analysis_count == 1
    solver.invalidate()                                # after invalidate: analyzed afresh
    solver.system(p2)
    assert solver.analysis_count == 2
