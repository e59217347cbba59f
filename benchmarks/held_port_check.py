"""What ``clothsim check`` says about hold-mode ports: clothsim's own export, a printed one,
a port with one fault in its contact handling at a time, and ports of another obstacle or
friction coefficient.

Exports drop-on-square (25², 15 frames, through the landing on the box) and checks it;
runs examples/ports/held_port.py as it is (printed with ``%g``), with each of its faults
(with its contacts.txt and without it) and with one obstacle setting changed in the
port's scene (``--set``: the box 1 cm larger or moved up 2 cm, the box's friction
coefficient 0 or doubled; on drape-sphere the sphere's radius or centre); checks every
run with the ``clothsim check`` command and writes a table of the verdicts and causes,
then the commands and their real output, to docs/data/held-port-check.md (included by
docs/ports.md). Run from the repository root:
``.venv/bin/python -m benchmarks held_port_check`` (about 3 min of CPU).
"""

from __future__ import annotations

import re
import shutil
import sys
from pathlib import Path

from .port_causes import ROOT, _run

OUT = ROOT / "docs" / "data" / "held-port-check.md"
WORK = Path("out") / "held-port-check"        # relative to ROOT: the commands as printed
FRAMES = 15
BOX, SPHERE = "drop-on-square", "drape-sphere"
#: Frames of each scene's runs (drape-sphere: as docs/ports.md's printed example).
FRAMES_OF = {BOX: FRAMES, SPHERE: 14}
#: (scene, name of the run, extra arguments of held_port.py)
RUNS = [
    (BOX, "none-g", ["--format", "%g"]),
    (BOX, "post-solve", ["--fault", "post-solve"]),
    (BOX, "post-solve-bare", ["--fault", "post-solve", "--no-contacts"]),
    (BOX, "frictionless", ["--fault", "frictionless"]),
    (BOX, "frictionless-bare", ["--fault", "frictionless", "--no-contacts"]),
    (BOX, "flipped", ["--fault", "flipped"]),
    (BOX, "flipped-bare", ["--fault", "flipped", "--no-contacts"]),
    (BOX, "no-stick", ["--fault", "no-stick", "--no-contacts"]),
    (BOX, "clinging", ["--fault", "clinging", "--no-contacts"]),
    (BOX, "box-larger", ["--set", "effects[1].min=[-0.26, -0.01, -0.26]",
                         "--set", "effects[1].max=[0.26, 0.51, 0.26]", "--no-contacts"]),
    (BOX, "box-up", ["--set", "effects[1].min=[-0.25, 0.02, -0.25]",
                     "--set", "effects[1].max=[0.25, 0.52, 0.25]", "--no-contacts"]),
    (BOX, "box-friction-0", ["--set", "effects[1].friction=0", "--no-contacts"]),
    (BOX, "box-friction-2x", ["--set", "effects[1].friction=0.6", "--no-contacts"]),
    (SPHERE, "sphere-radius", ["--set", "effects[1].radius=0.31", "--no-contacts"]),
    (SPHERE, "sphere-centre", ["--set", "effects[1].center=[0.02, 0.5, 0.0]",
                               "--no-contacts"]),
    (SPHERE, "sphere-clinging", ["--fault", "clinging", "--no-contacts"]),
    (SPHERE, "sphere-g", ["--format", "%g"]),
]


def cause(summary: str) -> str:
    """The cause a FAIL line names, in a few words (the table's column)."""
    for pattern in (r"clothsim's held steps with (.*?) \(replayed from",
                    r"clothsim's from the same state when it (.*?) \(\d",
                    r"(no single obstacle or contact setting reproduces)",
                    r"\((vertex \d+.*?) \(clothsim's contact force",
                    r"(vertex \d+[^;(]*)"):
        found = re.search(pattern, summary)
        if found:
            return found.group(1)
    return ""


def _quoted(args) -> str:
    return " ".join(f"'{a}'" if any(c in a for c in "%[ ") else a for a in args)


def main() -> list[str]:
    if (ROOT / WORK).exists():
        shutil.rmtree(ROOT / WORK)
    export = [".venv/bin/clothsim", "export", BOX, "--out", str(WORK / "export"),
              "--frames", str(FRAMES)]
    check = [".venv/bin/clothsim", "check", BOX, str(WORK / "export"), "--steps", str(FRAMES)]
    lines = ["$ " + " ".join(export), _run(export), "$ " + " ".join(check), _run(check)]
    rows = [("export", lines[-1].splitlines()[-1])]
    for scene, name, extra in RUNS:
        run = WORK / name
        frames = str(FRAMES_OF[scene])
        port = [sys.executable, "examples/ports/held_port.py", scene, "--frames", frames,
                "--out", str(run), *extra]
        _run(port)
        check = [".venv/bin/clothsim", "check", scene, str(run), "--steps", frames]
        text = _run(check)
        rows.append((name, text.splitlines()[-1]))
        lines += ["", f"$ .venv/bin/python {_quoted(port[1:])}", "$ " + " ".join(check), text]
        print(f"{name}: {rows[-1][1][:150]}")
    table = ["| port (out/held-port-check/…) | verdict | cause named |", "|---|---|---|"]
    for name, summary in rows:
        verdict = summary.split(" (")[0].split(", max error")[0]
        table.append(f"| {name} | {verdict} | {cause(summary) if 'FAIL' in summary else ''} |")
    page = (["Printed by `.venv/bin/python -m benchmarks held_port_check` (the commands "
             "below, run from the repository root; each port runs "
             f"{FRAMES} frames of drop-on-square or {FRAMES_OF[SPHERE]} of drape-sphere, "
             "at 25²):", ""] + table
            + ["", "```console"] + lines + ["```"])
    OUT.write_text("\n".join(page) + "\n", encoding="utf-8")
    print(f"   written to {OUT.relative_to(ROOT)}")
    return [s for _, s in rows]


if __name__ == "__main__":
    main()
