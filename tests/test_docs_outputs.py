"""Every command output a page shows is what the command prints, to the digits shown.

A ``console`` block (or any block with ``$ `` prompts) of README.md or docs/**/*.md that shows
output lines under its commands is run: its commands, in order, with ``bash`` in a fresh
working folder that looks like the repository root (``.venv``, ``examples``, ``docs`` and
``clothsim`` linked in, nothing beside it), and each output line of the page must
match one line the commands printed. Text must match exactly; each number must equal the
printed number rounded to the digits the page shows (``4.837e-11`` matches 4.8372e-11, not
4.8421e-11). A block preceded by ``<!-- not-run: reason -->`` is skipped with the reason.
"""

from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

import pytest

from .data_sets import SKIP_ASSIGNMENT, have_assignment
from .test_docs_pages import ALL, ROOT, Block

NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")
LINKED = (".venv", "examples", "docs", "clothsim", "pyproject.toml")


def shown_outputs(block: Block) -> list[tuple[list[str], list[str]]]:
    """(commands, output lines) of each prompted command of a block that shows output."""
    out, cmds, lines = [], [], []
    for s in block.code.splitlines():
        if s.startswith("$ "):
            if lines:
                out.append((cmds, lines))
                cmds, lines = [], []
            cmds.append(re.sub(r"\s+#.*$", "", s[2:]).strip())
        elif s.strip() and cmds:
            lines.append(s.rstrip())
    if cmds:
        out.append((cmds, lines))
    return out


def with_output(block: Block) -> bool:
    return any(lines for _, lines in shown_outputs(block))


def _pattern(shown: str) -> tuple[re.Pattern, list[str]]:
    """A regex matching ``shown`` with every number free, and the numbers shown."""
    parts, numbers, last = [], [], 0
    for m in NUMBER.finditer(shown):
        parts.append(re.escape(shown[last:m.start()]))
        parts.append(f"({NUMBER.pattern})")
        numbers.append(m.group())
        last = m.end()
    parts.append(re.escape(shown[last:]))
    return re.compile("^" + "".join(parts).strip() + "$"), numbers


def _same_to_digits(shown: str, printed: str) -> bool:
    """``printed`` rounded as ``shown`` is written gives ``shown``."""
    if "e" in shown.lower():
        mantissa = shown.lower().split("e")[0]
        decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
        return f"{float(printed):.{decimals}e}" == f"{float(shown):.{decimals}e}"
    decimals = len(shown.split(".")[1]) if "." in shown else 0
    return f"{float(printed):.{decimals}f}" == f"{float(shown):.{decimals}f}"


def line_matches(shown: str, printed: str) -> bool:
    """Does a printed line say what the page shows, to the digits shown?

    Parameters
    ----------
    shown, printed : str
        The page's output line and one line the command printed.

    Returns
    -------
    bool
    """
    pattern, numbers = _pattern(shown.strip())
    m = pattern.match(printed.strip())
    return bool(m) and all(_same_to_digits(a, b) for a, b in zip(numbers, m.groups()))


def test_line_matching_can_fail():
    shown = "PASS: positions, 61 frames, max error 4.837e-11 m"
    assert line_matches(shown, "PASS: positions, 61 frames, max error 4.83712e-11 m")
    assert not line_matches(shown, "PASS: positions, 61 frames, max error 4.842e-11 m")
    assert not line_matches(shown, "FAIL: positions, 61 frames, max error 4.837e-11 m")
    assert line_matches("hanging: 30 frames written to out/hang",
                        "hanging: 30 frames written to out/hang")
    assert line_matches("took 0.50 s", "took 0.5049 s")
    assert not line_matches("took 0.51 s", "took 0.5049 s")


def _workspace(tmp_path: Path) -> Path:
    work = tmp_path / "repo"
    work.mkdir()
    for name in LINKED:
        (work / name).symlink_to(ROOT / name)
    return work


OUTPUT_BLOCKS = [b for b in ALL if with_output(b)]
# Pages a benchmark prints whose commands are a whole study (about 40 and 16 s of CPU, over
# a tenth of make test): CI checks them with -m slow. What their commands show stays in the
# fast run: the hold-mode check of each planted fault, with and without the port's planes
# (tests/ports/test_check_held.py::test_planted_contact_faults_are_named), the causes named
# for each fault of mass_springs.py (tests/ports/test_causes.py), and every other page's
# output here.
SLOW_PAGES = ("docs/data/held-port-check.md", "docs/data/port-causes.md")


def _param(block: Block):
    slow = block.name.startswith(SLOW_PAGES)
    return pytest.param(block, id=block.name, marks=[pytest.mark.slow] if slow else [])


def test_the_slow_pages_are_pages_with_output():
    """A renamed or emptied page cannot leave SLOW_PAGES naming nothing."""
    for page in SLOW_PAGES:
        assert any(b.name.startswith(page + ":") for b in OUTPUT_BLOCKS), page


@pytest.mark.parametrize("block", [_param(b) for b in OUTPUT_BLOCKS])
def test_shown_output_is_printed(block, tmp_path):
    if block.not_run:
        pytest.skip(block.not_run)
    if not (ROOT / ".venv" / "bin" / "clothsim").exists():
        pytest.skip("no .venv at the repository root (make setup builds it)")
    if "jacobson" in block.code and not have_assignment():
        pytest.skip(SKIP_ASSIGNMENT)
    work = _workspace(tmp_path)
    # the data sets as the tests see them (CLOTHSIM_DATA if set, no downloads)
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTHON")}
    missing = []
    for cmds, shown in shown_outputs(block):
        printed = []
        for cmd in cmds:
            r = subprocess.run(["bash", "-c", cmd], cwd=work, env=env, capture_output=True,
                               text=True, timeout=300)
            printed += (r.stdout + r.stderr).splitlines()
        missing += [f"{cmds[-1]!r} shows {s!r}" for s in shown
                    if not any(line_matches(s, p) for p in printed)]
    assert not missing, (f"{block.name}: output the commands no longer print "
                         f"(regenerate the page):\n" + "\n".join(missing))
