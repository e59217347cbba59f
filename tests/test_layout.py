"""The package's layout: data flows one way along the pipeline.

Every import between clothsim modules is read from the source (imports inside functions
included), and the test fails on an import cycle, on an import that climbs back up the
pipeline, on a module over 400 lines, and on a heavy package loaded by ``import clothsim``.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "clothsim"

#: The pipeline, lowest first. A module may import its own stage and the stages below it.
STAGES = [
    {"errors"},
    {"mesh", "polygon", "mesh_checks", "voronoi"},
    {"springs"},
    {"model"},
    {"matrices", "reference", "energy", "factorization", "factor_mode"},
    {"problem", "objective", "contacts"},
    {"solvers"},
    {"effects"},
    {"simulation", "state", "magnitudes", "blowups"},
    {"gallery"},
    {"io"},
    {"datasets"},
    {"scene"},
    {"display", "camera", "painter", "plotting", "pictures"},
    {"runner", "runfolder", "interrupts"},
    {"accuracy", "ports"},
    {"cli", "__main__", "__init__"},
]
STAGE_OF = {name: i for i, names in enumerate(STAGES) for name in names}
HEAVY = ("meshio", "matplotlib", "sksparse", "tqdm", "joblib", "dask", "threadpoolctl",
         "pooch", "requests")


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def is_package(path: Path) -> bool:
    return path.name == "__init__.py"


def imported_modules(path: Path, known: set[str]) -> set[str]:
    """clothsim modules ``path`` imports anywhere in its body (resolved to known modules)."""
    name = module_name(path)
    package = name if is_package(path) else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                root = ".".join(base + ([node.module] if node.module else []))
            else:
                root = node.module or ""
            # `from . import energy` names a module; `from .x import f` resolves to x below
            targets = [f"{root}.{alias.name}" for alias in node.names]
        else:
            continue
        for target in targets:
            while target and target not in known:
                target = target.rpartition(".")[0]
            if target and target.startswith("clothsim") and target != name:
                found.add(target)
    return found


@pytest.fixture(scope="module")
def graph() -> dict[str, set[str]]:
    files = {module_name(p): p for p in PACKAGE.rglob("*.py")}
    known = set(files)
    return {name: imported_modules(path, known) for name, path in files.items()}


def stage(module: str) -> int:
    parts = module.split(".")
    return STAGE_OF[parts[1] if len(parts) > 1 else "__init__"]


def test_every_module_has_a_stage(graph):
    unknown = sorted(m for m in graph if m != "clothsim" and m.split(".")[1] not in STAGE_OF)
    assert not unknown, f"modules missing from STAGES: {unknown}"


def test_no_import_cycle(graph):
    # the package __init__ files re-export their submodules; a cycle through them is real
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph.get(node, ())):
            if nxt == "clothsim":          # only the top-level __init__ and cli import it
                continue
            if state.get(nxt) == 1:
                return stack[stack.index(nxt):] + [nxt]
            if nxt not in state and (cycle := visit(nxt)):
                return cycle
        stack.pop()
        state[node] = 2
        return None

    for module in sorted(graph):
        if module not in state and (cycle := visit(module)):
            pytest.fail("import cycle: " + " -> ".join(cycle))


def test_no_upward_import(graph):
    upward = [f"{m} imports {t}" for m, targets in sorted(graph.items()) if m != "clothsim"
              for t in sorted(targets) if t != "clothsim" and stage(t) > stage(m)]
    upward += [f"{m} imports the top-level package" for m, t in sorted(graph.items())
               if "clothsim" in t and m not in ("clothsim.cli", "clothsim.__main__")]
    assert not upward, "imports climbing back up the pipeline:\n" + "\n".join(upward)


def test_no_module_over_400_lines():
    long = {module_name(p): n for p in PACKAGE.rglob("*.py")
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > 400}
    assert not long, f"modules over 400 lines: {long}"


def test_import_clothsim_loads_no_heavy_package():
    code = ("import sys, clothsim; "
            f"print(','.join(m for m in {HEAVY!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=PACKAGE.parent).stdout.strip()
    assert out == "", f"`import clothsim` loads {out}"
