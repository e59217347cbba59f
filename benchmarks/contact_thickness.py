"""The contact thickness chosen with numbers: how far the obstacle shows through the cloth.

Run from the repository root::

    .venv/bin/python -m benchmarks contact_thickness                  # 25², 49² (minutes)
    .venv/bin/python -m benchmarks.contact_thickness --sizes 65       # one size more

Each row is the built-in scene (``drop-on-square``, ``drape-sphere``) at n × n vertices in
the default ``[contact] mode = "hold"``, its box or sphere given a ``thickness`` δ of 0, of
a fixed fraction of the grid spacing ℓ (0.25 ℓ; 0.35 ℓ ≈ ℓ/(2√2), what a box edge seen
straight on needs), or ``"auto"`` (the default). Measured by
:func:`benchmarks.contact.measure_contact`: the deepest the declared solid stands in front
of a triangle it meets over the last second (*through cloth*), also as a fraction of ℓ,
the largest spring stretch over the last second and the deepest vertex inside the contact
surface over the run. Rows are stored in ``docs/data/contact-thickness.json`` (a run
replaces the row of the same scene, size and thickness) and the page
``docs/data/contact-thickness.md`` is rewritten from all of them.
"""

from __future__ import annotations

import argparse
import json
import warnings

from . import ROOT
from .contact import SCENES, measure_contact, store
from .iteration_cost import commit

CHOICES = ("0", "0.25l", "0.35l", "auto")
JSON = ROOT / "docs" / "data" / "contact-thickness.json"
PAGE = ROOT / "docs" / "data" / "contact-thickness.md"


def thickness_value(choice: str, resolution: int, size: float = 1.0):
    """The ``thickness`` of a choice: ``"auto"``, or a number [m] (``"0.35l"`` is 0.35 ℓ
    for a cloth of ``size`` m with ``resolution`` vertices per side)."""
    if choice == "auto":
        return "auto"
    if choice.endswith("l"):
        return float(choice[:-1]) * size / (resolution - 1)
    return float(choice)


def page(runs: list[dict]) -> str:
    """The Markdown table of ``runs`` (by scene, size, thickness)."""
    order = {s: i for i, s in enumerate(SCENES)}
    runs = sorted(runs, key=lambda r: (order.get(r["scene"], 9), r["resolution"],
                                       CHOICES.index(r["choice"])))
    out = ["Printed by `.venv/bin/python -m benchmarks contact_thickness` (sizes run "
           "separately with `.venv/bin/python -m benchmarks.contact_thickness --sizes N`; "
           "each row names the commit it was measured at).", "",
           "| scene | n² | thickness | δ [m] | through cloth [m] | through cloth / ℓ | "
           "max stretch | max depth inside [m] | commit |",
           "|---|---|---|---|---|---|---|---|---|"]
    for r in runs:
        ell = 1.0 / (r["resolution"] - 1)
        out.append(f"| {r['scene']} | {r['resolution']}² | {r['choice']} | "
                   f"{max(r['margins']):.2e} | {r['through_cloth']:.1e} | "
                   f"{r['through_cloth'] / ell:.3f} | {r['max_stretch']:.3f} | "
                   f"{r['max_inside']:.1e} | {r['commit']} |")
    return "\n".join(out) + "\n"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[25, 49])
    parser.add_argument("--scenes", nargs="+", choices=SCENES, default=list(SCENES))
    parser.add_argument("--choices", nargs="+", choices=CHOICES, default=list(CHOICES))
    args = parser.parse_args([] if argv is None else argv)
    warnings.simplefilter("ignore")
    runs = json.loads(JSON.read_text(encoding="utf-8"))["runs"] if JSON.is_file() else []
    where = commit()
    for n in args.sizes:
        for scene in args.scenes:
            for choice in args.choices:
                r = measure_contact(scene, n, "hold", thickness=thickness_value(choice, n))
                r.update(choice=choice, commit=where)
                print(f"{scene} {n}^2 thickness {choice} ({max(r['margins']):.2e} m): "
                      f"through cloth {r['through_cloth']:.1e} m, max stretch "
                      f"{r['max_stretch']:.3f}, max depth inside {r['max_inside']:.1e} m",
                      flush=True)
                runs = store(runs, r, ("scene", "resolution", "choice"), JSON, PAGE, page)


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])
