"""What ``clothsim check`` says about hold-mode ports: clothsim's own export, a printed one,
and a port with one fault in its contact handling at a time.

Exports drop-on-square (25², 15 frames, through the landing on the box) and checks it;
runs examples/ports/held_port.py as it is (printed with ``%g``) and with each of its
faults, with its contacts.txt and without it; checks every run with the ``clothsim check``
command and writes the commands and their real output to docs/data/held-port-check.md
(included by docs/ports.md). Run from the repository root:
``.venv/bin/python -m benchmarks held_port_check`` (about 20 s of CPU).
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

from .port_causes import ROOT, _run

OUT = ROOT / "docs" / "data" / "held-port-check.md"
WORK = Path("out") / "held-port-check"        # relative to ROOT: the commands as printed
FRAMES = 15
#: (fault, extra arguments of held_port.py)
RUNS = [("none", ["--format", "%g"]), ("post-solve", []), ("post-solve", ["--no-contacts"]),
        ("frictionless", []), ("frictionless", ["--no-contacts"]), ("flipped", []),
        ("flipped", ["--no-contacts"])]


def main() -> list[str]:
    if (ROOT / WORK).exists():
        shutil.rmtree(ROOT / WORK)
    scene = "drop-on-square"
    steps = ["--steps", str(FRAMES)]
    export = [".venv/bin/clothsim", "export", scene, "--out", str(WORK / "export"),
              "--frames", str(FRAMES)]
    check = [".venv/bin/clothsim", "check", scene, str(WORK / "export"), *steps]
    lines = ["Printed by `.venv/bin/python -m benchmarks held_port_check` (the commands "
             "below, run from the repository root):", "", "```console",
             "$ " + " ".join(export), _run(export), "$ " + " ".join(check), _run(check)]
    summaries = [lines[-1].splitlines()[-1]]
    for fault, extra in RUNS:
        run = WORK / (fault + ("-bare" if "--no-contacts" in extra else "")
                      + ("-g" if "%g" in extra else ""))
        port = [sys.executable, "examples/ports/held_port.py", scene, "--fault", fault,
                "--frames", str(FRAMES), "--out", str(run), *extra]
        _run(port)
        check = [".venv/bin/clothsim", "check", scene, str(run), *steps]
        text = _run(check)
        summaries.append(text.splitlines()[-1])
        shown = " ".join(f"'{a}'" if "%" in a else a for a in port[1:])
        lines += ["", f"$ .venv/bin/python {shown}", "$ " + " ".join(check), text]
        print(f"{run.name}: {summaries[-1][:150]}")
    lines.append("```")
    OUT.write_text("\n".join(lines) + "\n", encoding="utf-8")
    print(f"   written to {OUT.relative_to(ROOT)}")
    return summaries


if __name__ == "__main__":
    main()
