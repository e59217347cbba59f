"""Every code block of README.md and docs/**/*.md works as written.

* ``python`` blocks run, each in a fresh temporary working folder with the repository on
  ``sys.path``; a block reading the assignment's files (``jacobson-a8``, third party, never
  downloaded by the tests) skips when they are absent. A block that is deliberately partial
  is preceded in the page by ``<!-- not-run: reason -->``.
* Shell blocks (``sh``, ``bash``, ``shell``, ``console``, or unlabelled blocks that look like
  commands) work copied into a fresh shell at the repository root: each command starts with
  ``.venv/bin/``, ``make``, ``cd``, ``git``, ``sh scripts/`` or is ``. .venv/bin/activate``
  (after which bare ``clothsim`` and ``python`` are allowed in the same block). In a block
  with ``$ `` prompts only the prompted lines are commands; the others are output.
* The cheap commands the pages show (``--version``, ``--help``, ``scenes``,
  ``scenes --show NAME``, ``validate NAME``) are run with ``bash -c`` from the repository
  root, using the repository's ``.venv`` (skipped when it has none).
"""

from __future__ import annotations

import os
import re
import runpy
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from .data_sets import SKIP_ASSIGNMENT, have_assignment

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
GENERATED = {"_build", "auto_examples", "api"}
PAGES = [ROOT / "README.md"] + sorted(
    p for p in DOCS.rglob("*.md") if not GENERATED & set(p.relative_to(DOCS).parts[:-1]))
# pages owned elsewhere whose shell lines may still be bare `python ...` (reported, not fatal)
TOLERATED = {"docs/accuracy.md"}

SHELL_LANGS = {"sh", "bash", "shell", "console"}
NOT_RUN = re.compile(r"<!--\s*not-run:\s*(\S.*?)\s*-->")
COMMANDISH = re.compile(r"^(\$ |\.venv/|(make|cd|git|sh|python3?|clothsim|pip|cp)(\s|$)|\. |"
                        r"[A-Z_]+=\S+ )")
ALLOWED = re.compile(r"^(\.venv/bin/\S+|make(\s|$)|cd(\s|$)|git\s|sh scripts/|(cp|mkdir|ls)\s)")
ACTIVATE = ". .venv/bin/activate"
AFTER_ACTIVATE = re.compile(r"^(clothsim|python3?)(\s|$)")
NAME = r"[a-z0-9][a-z0-9-]*"  # a built-in scene (placeholders such as SCENE are not run)
CHEAP = re.compile(rf"^\.venv/bin/clothsim (--version|-h|--help|scenes|scenes --show {NAME}|"
                   rf"validate {NAME}|[a-z][a-z-]* (-h|--help))$")


@dataclass
class Block:
    page: Path
    line: int          # 1-based line of the opening fence
    lang: str
    code: str
    not_run: str | None

    @property
    def name(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"


def blocks(page: Path) -> list[Block]:
    """The fenced code blocks of a Markdown page (MyST directives such as ``{toctree}``
    excluded)."""
    out, lines = [], page.read_text(encoding="utf-8").splitlines()
    i = 0
    while i < len(lines):
        m = re.match(r"^(\s*)(`{3,}|~{3,})\s*([^\s`]*)", lines[i])
        if not m:
            j = i
            while j < len(lines) and lines[j].startswith("    ") and lines[j].strip():
                j += 1
            if j > i and (i == 0 or not lines[i - 1].strip()) and COMMANDISH.match(
                    lines[i].strip()):  # an indented block of commands: checked too
                out.append(Block(page, i + 1, "indented",
                                 "\n".join(s.strip() for s in lines[i:j]) + "\n", None))
            i = max(j, i + 1)
            continue
        fence, lang, start = m.group(2), m.group(3), i
        j = i + 1
        while j < len(lines) and not lines[j].strip().startswith(fence):
            j += 1
        prev = next((s for s in reversed(lines[:start]) if s.strip()), "")
        marker = NOT_RUN.search(prev)
        if not lang.startswith("{"):
            out.append(Block(page, start + 1, lang.lower(), "\n".join(lines[start + 1:j]) + "\n",
                             marker.group(1) if marker else None))
        i = j + 1
    return out


def is_shell(block: Block) -> bool:
    if block.lang in SHELL_LANGS or block.lang == "indented":
        return True
    if block.lang:
        return False
    first = next((s.strip() for s in block.code.splitlines() if s.strip()), "")
    return bool(COMMANDISH.match(first))


def commands(block: Block) -> list[str]:
    """The command lines of a shell block: continuation lines joined, comments stripped."""
    raw = block.code.splitlines()
    prompted = block.lang == "console" or any(s.startswith("$ ") for s in raw)
    joined, buf = [], ""
    for s in raw:
        if prompted and not buf:
            if not s.startswith("$ "):
                continue  # output
            s = s[2:]
        s = s.strip() if buf else s
        buf += s.rstrip("\\").rstrip() + " " if s.rstrip().endswith("\\") else s
        if not s.rstrip().endswith("\\"):
            joined.append(buf)
            buf = ""
    out = []
    for s in joined:
        s = re.sub(r"(^|\s)#.*$", "", s).strip()
        if s:
            out.append(s)
    return out


def split_chain(cmd: str) -> list[str]:
    """``a && b; c || d`` as its commands (separators inside quotes kept)."""
    parts, buf, quote, i = [], "", None, 0
    while i < len(cmd):
        c = cmd[i]
        if quote:
            quote = None if c == quote else quote
        elif c in "'\"":
            quote = c
        elif cmd.startswith(("&&", "||"), i) or c == ";":
            parts.append(buf.strip())
            buf, i = "", i + (1 if c == ";" else 2)
            continue
        buf += c
        i += 1
    return [p for p in parts + [buf.strip()] if p]


def bad_lines(block: Block) -> list[str]:
    """The command lines that would not work copied into a fresh shell at the root."""
    bad, activated = [], False
    for cmd in commands(block):
        for part in split_chain(cmd):
            part = re.sub(r"^([A-Z_][A-Z0-9_]*=\S*\s+)+", "", part)  # VAR=value prefixes
            if part == ACTIVATE:
                activated = True
            elif not (ALLOWED.match(part) or (activated and AFTER_ACTIVATE.match(part))):
                bad.append(f"{block.page.relative_to(ROOT)}:{block.line}: {cmd}")
                break
    return bad


ALL = [b for p in PAGES for b in blocks(p)]
PYTHON = [b for b in ALL if b.lang in ("python", "py")]
SHELL = [b for b in ALL if is_shell(b)]


def _page_param(page: Path):
    rel = str(page.relative_to(ROOT))
    bad = [line for b in SHELL if b.page == page for line in bad_lines(b)]
    if rel in TOLERATED and bad:
        return pytest.param(page, id=rel, marks=pytest.mark.xfail(
            strict=False, reason="shell lines not in .venv/bin form: " + "; ".join(bad)))
    return pytest.param(page, id=rel)


@pytest.mark.parametrize("page", [_page_param(p) for p in PAGES])
def test_shell_lines_work_in_a_fresh_shell(page):
    bad = [line for b in SHELL if b.page == page for line in bad_lines(b)]
    assert not bad, "use .venv/bin/... (or . .venv/bin/activate first):\n" + "\n".join(bad)


@pytest.mark.parametrize("block", PYTHON, ids=[b.name for b in PYTHON])
def test_python_blocks_run(block, tmp_path, monkeypatch):
    if block.not_run:
        pytest.skip(f"marked not-run in the page: {block.not_run}")
    code = block.code
    if "jacobson" in code and not have_assignment():
        pytest.skip(SKIP_ASSIGNMENT)
    import matplotlib

    matplotlib.use("Agg", force=True)
    monkeypatch.chdir(tmp_path)
    monkeypatch.syspath_prepend(str(ROOT))
    script = tmp_path / "block.py"
    script.write_text(code, encoding="utf-8")
    runpy.run_path(str(script), run_name="__main__")


CHEAP_LINES = sorted({c for b in SHELL for c in commands(b) if CHEAP.match(c)})


def test_the_pages_show_cheap_commands():
    assert any(c == ".venv/bin/clothsim --version" for c in CHEAP_LINES), CHEAP_LINES
    assert any(c.startswith(".venv/bin/clothsim scenes --show ") for c in CHEAP_LINES)


@pytest.mark.parametrize("line", CHEAP_LINES)
def test_cheap_commands_run_from_the_root(line):
    if not (ROOT / ".venv" / "bin" / "clothsim").is_file():
        pytest.skip(f"{ROOT / '.venv/bin/clothsim'} is absent (run `make test` to create it)")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    r = subprocess.run(["bash", "-c", line], cwd=ROOT, env=env, capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 0, f"{line}: exit {r.returncode}\n{r.stdout[-2000:]}{r.stderr[-2000:]}"
    assert r.stdout.strip(), f"{line}: printed nothing"


def test_python_lines_run_with_the_environment():
    """``.venv/bin/python -c`` lines that need no earlier run, with the repository's
    interpreter (or the one running the tests when the repository has no ``.venv``)."""
    venv_python = ROOT / ".venv" / "bin" / "python"
    python = str(venv_python) if venv_python.is_file() else sys.executable
    lines = sorted({c for b in SHELL for c in commands(b)
                    if c.startswith(".venv/bin/python -c ") and "out/" not in c})
    if not lines:
        pytest.skip("no .venv/bin/python -c lines in the pages")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    for line in lines:
        cmd = line.replace(".venv/bin/python", f'"{python}"', 1)
        r = subprocess.run(["bash", "-c", cmd], cwd=ROOT, env=env, capture_output=True,
                           text=True, timeout=120)
        assert r.returncode == 0, f"{line}: {r.stderr[-2000:]}"


# ---------------------------------------------------------------- the checker can fail
def _block(code: str, lang: str = "sh") -> Block:
    return Block(ROOT / "README.md", 1, lang, code, None)


def test_the_shell_check_can_fail():
    assert bad_lines(_block("clothsim run\n"))
    assert bad_lines(_block("python -m benchmarks\n"))
    assert bad_lines(_block(".venv/bin/clothsim scenes && pytest -q\n"))
    assert not bad_lines(_block(".venv/bin/clothsim scenes && cp a b\n"))  # plain POSIX tools
    assert not bad_lines(_block(". .venv/bin/activate\nclothsim --version\npython -V\n"))
    assert not bad_lines(_block("CLOTHSIM_DATA=data .venv/bin/clothsim run x  # c\n"))
    console = _block("$ .venv/bin/clothsim run hanging\nhanging: 30 frames written\n", "console")
    assert commands(console) == [".venv/bin/clothsim run hanging"]
    assert not bad_lines(console)
    assert is_shell(_block("make demo\n", "")) and not is_shell(_block("out/\n  a.vtu\n", ""))
    assert split_chain("a && b 'c; d' ; e") == ["a", "b 'c; d'", "e"]
    assert not is_shell(_block("clothsim: error: x.toml: cloth.size: bad\n", ""))
    assert commands(_block(".venv/bin/clothsim run \\\n  --frames 3\n")) == [
        ".venv/bin/clothsim run --frames 3"]


def test_indented_commands_are_checked(tmp_path):
    page = tmp_path / "p.md"
    page.write_text("Run\n\n    python -m benchmarks x\n\ntext\n", encoding="utf-8")
    (found,) = blocks(page)
    assert found.lang == "indented" and is_shell(found)
    assert commands(found) == ["python -m benchmarks x"]


def test_not_run_marker_is_read(tmp_path):
    page = tmp_path / "p.md"
    page.write_text("a\n\n<!-- not-run: partial -->\n```python\nx = y\n```\n\n```python\n1\n```\n",
                    encoding="utf-8")
    found = blocks(page)
    assert [(b.line, b.not_run) for b in found] == [(4, "partial"), (8, None)]
