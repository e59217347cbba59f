"""Benchmarks: heavy measurements that back the numbers in docs/ (not part of the tests).

Run all with ``make bench`` (``.venv/bin/python -m benchmarks``) or some by name, e.g.
``.venv/bin/python -m benchmarks performance accuracy_bench``. The machine is shared and
noisy, so every benchmark prints its figures as RATIOS measured within one run, e.g.
``chebyshev/local-global wall-time ratio to 1e-6: 0.31``.

Scenes are built from the core API here, so a benchmark does not depend on scene files.
"""

from __future__ import annotations

import time
from pathlib import Path

import clothsim as cs
from clothsim import gallery

ROOT = Path(__file__).resolve().parent.parent
DOCS_IMG = ROOT / "docs" / "img"


def curtain(n: int, *, stiffness: float = 800.0, bending: float = 80.0, mass: float = 1.0,
            plane: str = "xy", method: str = "local-global", h: float = 1 / 30,
            iterations: int | None = 10, tolerance: float | None = None,
            **solver_options) -> cs.Simulation:
    """An n × n, 1 m × 1 m cloth of ``mass`` kg hanging from its two top corners
    (:func:`clothsim.gallery.curtain` with the benchmarks' parameter names).

    ``plane="xy"``: a vertical curtain (the documented accuracy scene); ``plane="xz"``: a
    horizontal sheet held at two corners that falls and swings (the paper's Fig. 1 setup).
    Structural and shear springs of ``stiffness`` [N/m], bending springs of ``bending``.
    """
    return gallery.curtain(n, k=stiffness, bending=bending, total_mass=mass, plane=plane,
                           h=h, method=method, iterations=iterations, tolerance=tolerance,
                           **solver_options)


def swing(n: int, *, stiffness: float = 800.0, bending: float = 80.0, mass: float = 1.0,
          method: str = "local-global", h: float = 1 / 30, iterations: int | None = 10,
          tolerance: float | None = None, **solver_options) -> cs.Simulation:
    """An n × n, 1 m × 1 m horizontal cloth hinged along one edge, released from rest.

    The trajectory-accuracy scene: every vertex of one edge (row 0 of the ``plane="xz"``
    grid) is pinned, and the sheet swings down like a pendulum, its free edge falling
    about 1 m in 0.5 s: a slow, large motion next to the springs' fast vibrations.
    Structural and shear springs of ``stiffness`` [N/m], bending springs of ``bending``.
    """
    return gallery.swing(n, k=stiffness, bending=bending, total_mass=mass, h=h,
                         method=method, iterations=iterations, tolerance=tolerance,
                         **solver_options)


def swing_factory(n: int, **kw):
    """A simulation factory ``(method, h, iterations, tolerance) -> Simulation`` for
    :func:`swing`."""

    def factory(method, h, iterations, tolerance):
        return swing(n, method=method, h=h, iterations=iterations, tolerance=tolerance, **kw)

    return factory


def curtain_factory(n: int, **kw):
    """A simulation factory ``(method, h, iterations, tolerance) -> Simulation``."""

    def factory(method, h, iterations, tolerance):
        return curtain(n, method=method, h=h, iterations=iterations, tolerance=tolerance, **kw)

    return factory


def report(name: str, value: float, fmt: str = ".3g") -> None:
    """Print one measured figure as ``name: value`` (the benchmark output format)."""
    print(f"  {name}: {value:{fmt}}", flush=True)


class Timer:
    """Context manager: ``with Timer() as t: ...; t.seconds``."""

    def __enter__(self):
        self._t0 = time.perf_counter()
        return self

    def __exit__(self, *exc):
        self.seconds = time.perf_counter() - self._t0
