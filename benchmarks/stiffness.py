"""Stiffness slows local/global: relative error after 200 iterations on an 11 × 11 sheet.

Reported in the paper's lineage: about 1e-12 at k = 1e2, 2e-9 at k = 1e4, 4e-5 at k = 1e6
(scene not stated).
Measured on two 1 kg, 1 m, 11 × 11 scenes at h = 1/30 s, bending springs at k / 10, the
step after 5 steps of motion, x* = the study's certified reference
(``clothsim.accuracy.certified_reference``: Newton to its rounding floor, checked from a
second start); a step the study would not measure (at rest, trivial) is reported as such:

- ``curtain``: vertical sheet hanging from its two top corners (the documented scene);
- ``falling sheet``: horizontal sheet held at two corners (paper's Fig. 1 setup); it
  buckles as it falls and compressed springs slow local/global far more.

Printed: the error and its ratio to the paper's figure (log10 ratio = digits apart).
"""

from __future__ import annotations

import math
import warnings

from clothsim.accuracy import trace_solver
from clothsim.accuracy.problems import classify
from clothsim.accuracy.reference import certified_reference
from clothsim.solvers import LocalGlobalSolver

from . import curtain, report

PAPER = {1e2: 1e-12, 1e4: 2e-9, 1e6: 4e-5}
SCENES = {"curtain": "xy", "falling sheet": "xz"}


def measure(k: float, *, plane: str = "xy", n: int = 11, iterations: int = 200,
            warmup_steps: int = 5) -> float:
    """Relative error ‖x_200 − x*‖ / ‖x* − x_n‖ of plain local/global at stiffness k."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = curtain(n, stiffness=k, bending=k / 10, plane=plane, method="newton",
                      iterations=50, tolerance=1e-12)
        sim.run(warmup_steps)
        problem = sim.problem()
        ref = certified_reference(sim.model, problem)
        kind = classify(sim.model, problem, ref.x)[0]
        if kind != "measured" or ref.two_minima:
            print(f"   plane {plane}, k={k:g}: the step is {kind} (two minima: {ref.two_minima}): "
                  f"no solver error to measure", flush=True)
            return math.nan
        x_star = ref.x
        lg = LocalGlobalSolver(sim.model, check_conditioning=False)
        tr = trace_solver(lg, problem, x_star, iterations=iterations, min_error=0.0)
    return float(tr.error[min(iterations, len(tr.error) - 1)])


def main() -> None:
    for scene, plane in SCENES.items():
        errors = {k: measure(k, plane=plane) for k in PAPER}
        for k, paper in PAPER.items():
            err = errors[k]
            if math.isnan(err):
                continue
            report(f"{scene} k={k:.0e}: relative error after 200 iterations", err, ".2e")
            report(f"{scene} k={k:.0e}: measured/paper ratio (paper {paper:.0e})",
                   err / paper, ".3g")
        if math.isnan(errors[1e6]) or math.isnan(errors[1e2]):
            continue
        report(f"{scene}: error ratio k=1e6 / k=1e2 (paper 4e7)",
               errors[1e6] / max(errors[1e2], 1e-300), ".3g")
        assert errors[1e6] > errors[1e2], "stiffer springs should converge slower"
