"""What ``clothsim check`` says about a broken coursework port: one run per planted fault.

Writes the coursework cases, runs the project's Python solution of the assignment
(examples/ports/mass_springs.py) on the ``net`` case as it is and with each fault of its
``FAULTS`` (and the Voronoi sheet with a local step that is not normalized: the port's
iterations then stop short of the model they head for), checks every run with the
``clothsim check`` command, and writes the commands and their real output to
docs/data/port-causes.md (included by docs/ports.md). Run from
the repository root: ``.venv/bin/python -m benchmarks port_causes`` (about 20 s on an
idle machine).
"""

from __future__ import annotations

import importlib.util
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "data" / "port-causes.md"
WORK = Path("out") / "port-causes"          # relative to ROOT: the commands as printed
#: (case, fault) runs: every fault on the net, where the 50 iterations converge, and the
#: unnormalized local step on the Voronoi sheet, where they do not
RUNS = [("net", None), *(("net", f) for f in ("gravity-sign", "rest-length", "stiffness",
                                              "unnormalized", "unpinned")),
        ("sheet-voronoi", "gravity-mass"), ("sheet-voronoi", "unnormalized")]


def _solution():
    path = ROOT / "examples" / "ports" / "mass_springs.py"
    spec = importlib.util.spec_from_file_location("mass_springs", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _run(command: list[str]) -> str:
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True)
    if done.returncode not in (0, 1):
        raise RuntimeError(f"{' '.join(command)}: exit {done.returncode}: {done.stderr}")
    return done.stdout.strip()


def main() -> list[str]:
    faults = _solution().FAULTS
    if (ROOT / WORK).exists():
        shutil.rmtree(ROOT / WORK)
    cases = WORK / "coursework"
    _run([".venv/bin/clothsim", "conformance", "--profile", "coursework", "--out", str(cases)])
    lines = ["Printed by `.venv/bin/python -m benchmarks port_causes` (the commands below, "
             "run from the repository root):", "", "```console",
             f"$ .venv/bin/clothsim conformance --profile coursework --out {cases}"]
    summaries = []
    for case, fault in RUNS:
        run = WORK / f"{case}-{fault or 'correct'}"
        solve = [sys.executable, "examples/ports/mass_springs.py", str(cases / case), str(run)]
        solve += ["--fault", fault] if fault else []
        _run(solve)
        check = [".venv/bin/clothsim", "check", str(cases / case / "scene.toml"), str(run)]
        text = _run(check)
        summaries.append(text.splitlines()[-1])
        flag = f" --fault {fault}" if fault else ""
        lines += ["", f"$ .venv/bin/python examples/ports/mass_springs.py {cases / case} "
                  f"{run}{flag}", "$ " + " ".join(check), text]
        print(f"{case} {fault or 'correct'}: {summaries[-1][:150]}")
    lines.append("```")
    lines += ["", "| fault (`--fault`) | what the port does |", "|---|---|"]
    lines += [f"| `{name}` | {what.replace('|', chr(92) + '|')} |"
              for name, what in faults.items()]
    OUT.write_text("\n".join(lines) + "\n", encoding="utf-8")
    print(f"   written to {OUT.relative_to(ROOT)}")
    return summaries


if __name__ == "__main__":
    main()
