"""Run the benchmarks: ``python -m benchmarks [NAME ...]`` (default: all but the long
``memory`` run, in order)."""

from __future__ import annotations

import importlib
import sys
import time

BENCHMARKS = ("stiffness", "stability_figures", "performance", "factor_modes", "iteration_cost",
              "accuracy_bench", "accuracy_quick", "port_causes", "port_causes_fixed",
              "held_port_check")
#: run only when named: the 257² × 500-frame memory run, the scale ladder up to 1025² and
#: the full accuracy study at 41² take minutes each; accuracy_docs regenerates the accuracy
#: page's two study reports (minutes)
LONG = ("memory", "scale_ladder", "accuracy_full", "accuracy_docs", "contact", "held_factor",
        "contact_thickness", "fuzz_scenes", "cpp_side_by_side", "replay_spread",
        "port_check_matrix", "first_contact_margins", "referee_matrix")  # fuzz_scenes: the
# fuzz behind docs/data/fuzz.md (a minute); first_contact_margins: the margins behind
# held_first; cpp_side_by_side: downloads and compiles a C++ port; replay_spread:
# docs/data/replay-spread.md; port_check_matrix: docs/data/port-check-matrix.md (minutes);
# referee_matrix: docs/data/referee-matrix.md (a few minutes)


def main(argv: list[str]) -> int:
    names = argv or list(BENCHMARKS)
    unknown = [n for n in names if n not in BENCHMARKS + LONG]
    if unknown:
        print(f"unknown benchmark {unknown[0]!r}; choose from {', '.join(BENCHMARKS + LONG)}",
              file=sys.stderr)
        return 2
    for name in names:
        print(f"== {name}", flush=True)
        t0 = time.perf_counter()
        importlib.import_module(f"benchmarks.{name}").main()
        print(f"   ({time.perf_counter() - t0:.1f} s)", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
