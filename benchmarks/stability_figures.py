"""Print the measured figures of the numerical stability suite (docs/stability.md).

Run from the repository root::

    .venv/bin/python benchmarks/stability_figures.py

The figures come from the same ``measure_*`` helpers the tests assert on
(tests/test_stability_solver.py, tests/test_stability_exact.py), so the table and the
tests cannot drift apart.
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import test_stability_exact as ex  # noqa: E402
import test_stability_solver as so  # noqa: E402


def main() -> None:
    warnings.simplefilter("ignore")
    print("case 1  stiffness sweep (4x4, h=1/30, cap 1000 iterations, tolerance 1e-6)")
    for r in so.measure_stiffness_sweep():
        print(f"    k={r['k']:.0e}  iterations={r['iterations']:5d}  residual={r['residual']:.2e}"
              f"  warned={bool(r['warnings'])}  finite={r['finite']}")
    print("case 2  max per-step relative energy increase (Newton 1e-12, 20 steps)")
    for h in (1 / 24, 0.1, 1.0):
        r = so.measure_energy_increase(h)
        print(f"    h={h:.4g}  {r['max_relative_increase']:.2e}  (energy lost {r['energy_lost']:.3f} J)")
    print(f"case 3  max relative increase of g-hat over half steps: "
          f"{so.measure_degenerate_monotone()['max_relative_increase']:.2e}")
    print(f"        zero-rest spring length after 12 steps: {so.measure_zero_rest_collapse():.2e} m")
    for scale in (10.0, 0.01):
        r = so.measure_release(scale)
        print(f"case 4  scale {scale:g}: start max|l/r-1|={r['start_strain']:.3g} "
              f"-> {r['strain']:.2e} after 200 steps")
    for r in so.measure_mass_extremes():
        print(f"case 5  m={r['vertex_mass']:.0e} k={r['k']:.0e}: cond1={r['cond']:.3g}")
    print(f"case 6  free fall max error: local-global {ex.measure_free_fall():.2e} m, "
          f"newton {ex.measure_free_fall('newton'):.2e} m")
    print(f"        release vs refactor: {ex.measure_release_vs_refactor():.2e} m")
    r = ex.measure_invariance()
    print(f"case 10 rotation {r['rotation']:.2e} m; translation {r['translation_per_metre']:.2e} m/m")
    print(f"case 11 oscillator max deviation: {ex.measure_oscillator():.2e} m")
    r = ex.measure_convergence_order()
    print(f"case 12 slope {r['slope']:.4f}; errors {[f'{e:.3e}' for e in r['errors']]}")
    print(f"case 13 max |A - A^T| / max |A|: {so.measure_symmetry():.1e}")


if __name__ == "__main__":
    main()
