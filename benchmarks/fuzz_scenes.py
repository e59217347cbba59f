"""The hypothesis fuzz of scene files and ``--set`` changes, counted for docs/reliability.md.

Two generators, shared with the tests (``tests/scene/test_bad_input.py``,
``tests/test_reliability_hostile_set.py``):

- :func:`mutated_scene`: a valid scene (:data:`VALID`) with one value replaced by a hostile
  one (:data:`BAD_VALUES`: wrong types, 1e300, 10**400, nan, inf, 5000 characters, …), a
  value nested one level deeper, a key renamed, or an unknown key added;
- :func:`set_change`: one ``--set KEY=VALUE`` on that valid scene, its key a path of the
  scene (or a typo of one, an index out of range, a path into a value) and its value a
  hostile TOML text (:data:`BAD_TEXTS`).

Each case goes through ``clothsim validate`` as a user would; :func:`outcome` sorts the
result: *accepted* (exit 0), *refused* (exit 2, one line naming the file and a key, or the
``--set``; ``run`` then refuses it identically and writes nothing) or *wrong* (anything
else: exit 1, a traceback, a Python exception name, several lines). Run
``.venv/bin/python -m benchmarks fuzz_scenes`` (about a minute); it prints the counts and
writes ``docs/data/fuzz.md``, which docs/reliability.md includes. Hypothesis runs
derandomized, so the counts are the same on every run of the same code.
"""

from __future__ import annotations

import copy
import io
import re
import subprocess
import tempfile
from collections import Counter
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

OUT = Path(__file__).resolve().parents[1] / "docs" / "data" / "fuzz.md"
EXAMPLES = 300  # per generator, for the docs

VALID = {
    "scene": {"name": "m", "frames": 2, "fps": 30, "substeps": 1},
    "cloth": {"shape": "grid", "size": [1.0, 1.0], "resolution": [4, 4],
              "center": [0.0, 1.0, 0.0], "plane": "xz", "mass": 1.0},
    "springs": {"structural": 100.0, "shear": 100.0, "bending": 10.0},
    "solver": {"method": "local-global", "iterations": 3},
    "effects": [{"kind": "gravity", "acceleration": [0.0, -9.81, 0.0]},
                {"kind": "pin", "vertices": [0, 3], "method": "penalty", "stiffness": 1e4},
                {"kind": "sphere", "center": [0.0, 0.0, 0.0], "radius": 0.3, "friction": 0.1},
                {"kind": "plane", "point": [0.0, -1.0, 0.0], "normal": [0.0, 1.0, 0.0]},
                {"kind": "wind", "velocity": [1.0, 0.0, 0.0]},
                {"kind": "damping", "model": "velocity", "coefficient": 0.01}],
}
"""A valid scene: a 4 × 4 cloth with one effect of most kinds."""

BAD_VALUES = [
    True, False, "0.5", "down", "", "x" * 5000, 10 ** 400, -(10 ** 400), 2 ** 63, -1, 0,
    1e300, -1e300, 1e-300, float("nan"), float("inf"), -0.0, [], [1, 2], [[1.0]], {},
    {"a": 1}, [True] * 3, 3.5, 123456789, 1e160, 5e-324,
]
"""Hostile values a scene file may hold (TOML has nan, inf and integers of any size)."""

BAD_TEXTS = [
    "1e300", "-1e300", "1e160", "5e-324", "-1", "0", "nan", "inf", "-inf", "true", "[]",
    "[1, 2]", "[1e300, 0, 0]", "[0, -1e200, 0]", "[[1]]", "{a = 1}", '"x"', "down", "",
    "'unterminated", "[1, 2", "1" + "0" * 400, "3.5", "123456789", "[0, 0, 0]",
    '"constraint"', '"penalty"', "[31, 31]", "[2, 2]", "[[-1, 0], [-1, -1]]",
]
"""Hostile ``--set`` value texts (TOML, or bare words taken as text)."""


def toml_value(v) -> str:
    """``v`` written as a TOML value (nan and inf as TOML spells them).

    Parameters
    ----------
    v : bool, int, float, str, list or dict

    Returns
    -------
    str
    """
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f'"{k}" = {toml_value(x)}' for k, x in v.items()) + "}"
    raise TypeError(v)


def to_toml(doc: dict) -> str:
    """A scene document as TOML text (``[[effects]]`` as an array of tables when it is one).

    Parameters
    ----------
    doc : dict

    Returns
    -------
    str
    """
    lines = []
    for key, value in doc.items():
        if key == "effects" and isinstance(value, list) and all(isinstance(e, dict)
                                                                for e in value):
            for e in value:
                lines.append("[[effects]]")
                lines += [f'"{k}" = {toml_value(x)}' for k, x in e.items()]
        elif isinstance(value, dict):
            lines.append(f'["{key}"]')
            lines += [f'"{k}" = {toml_value(x)}' for k, x in value.items()]
        else:
            lines.insert(0, f'"{key}" = {toml_value(value)}')
    return "\n".join(lines) + "\n"


def leaves(doc, path=()):
    """Every key path of ``doc`` (tables, arrays and values), depth first.

    Parameters
    ----------
    doc : dict or list
    path : tuple
        The path so far.

    Yields
    ------
    tuple of (str or int)
    """
    if isinstance(doc, dict):
        for k, v in doc.items():
            yield from leaves(v, path + (k,))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            yield from leaves(v, path + (i,))
    if path:
        yield path


@st.composite
def mutated_scene(draw) -> dict:
    """:data:`VALID` with one hostile change (a hypothesis strategy).

    Returns
    -------
    dict
        The mutated document.
    """
    doc = copy.deepcopy(VALID)
    path = draw(st.sampled_from(sorted(leaves(doc), key=str)), label="path")
    parent = doc
    for k in path[:-1]:
        parent = parent[k]
    how = draw(st.sampled_from(["value", "nest", "rename", "extra"]), label="how")
    if how == "value":
        parent[path[-1]] = draw(st.sampled_from(BAD_VALUES), label="value")
    elif how == "nest":
        parent[path[-1]] = {"deeper": [parent[path[-1]]]}
    elif how == "rename" and isinstance(parent, dict):
        parent[path[-1] + "_x"] = parent.pop(path[-1])
    elif isinstance(parent, dict):
        parent["surprise"] = draw(st.sampled_from(BAD_VALUES), label="extra")
    return doc


def _dotted(path: tuple) -> str:
    out = ""
    for k in path:
        out += f"[{k}]" if isinstance(k, int) else (f".{k}" if out else str(k))
    return out


@st.composite
def set_change(draw) -> str:
    """One hostile ``KEY=VALUE`` for ``--set`` on :data:`VALID` (a hypothesis strategy).

    Returns
    -------
    str
    """
    key = _dotted(draw(st.sampled_from(sorted(leaves(VALID), key=str)), label="path"))
    how = draw(st.sampled_from(["as is", "typo", "deeper", "index", "new table", "bare"]),
               label="how")
    if how == "typo":
        key = key[:-1] if len(key) > 1 else key + "x"
    elif how == "deeper":
        key += draw(st.sampled_from([".x", "[0]", "[0].x", "[99]"]), label="deeper")
    elif how == "index":
        key = re.sub(r"\[\d+\]", draw(st.sampled_from(["[6]", "[99]", "[-1]", "[]"]),
                                      label="index"), key) if "[" in key else key + "[0]"
    elif how == "new table":
        key = draw(st.sampled_from(["scenes.frames", "effect[0].kind", ".x", "a..b", "cloth.",
                                    "solver.method.name", "=", " "]), label="key")
    elif how == "bare":
        return draw(st.sampled_from([key, f"{key}=", f"={key}", f"{key}=={key}"]),
                    label="bare")
    return f"{key}={draw(st.sampled_from(BAD_TEXTS), label='value')}"


def _cli(args: list[str]) -> tuple[int, str]:
    from clothsim import cli

    err = io.StringIO()
    with redirect_stderr(err), redirect_stdout(io.StringIO()):
        code = cli.main(args)
    return code, err.getvalue()


def named_key(line: str, scene_file: Path, sets=()) -> str:
    """The key a refusal names (``""`` when it names only the ``--set``), indices as [i].

    Parameters
    ----------
    line : str
        The error line without ``clothsim: error:``.
    scene_file : Path
    sets : list of str

    Returns
    -------
    str
    """
    for source in [str(scene_file), ", ".join(f"--set {s}" for s in sets),
                   *(f"--set {s}" for s in sets)]:
        if source and line.startswith(source + ": "):
            head, sep, _ = line[len(source) + 2:].partition(": ")
            return re.sub(r"\[-?\d+\]", "[i]", head) if sep and " " not in head else ""
    return ""


def outcome(scene_file: Path, sets: list[str] = ()) -> tuple[str, str]:
    """What ``clothsim validate SCENE [--set …]`` does with one case, sorted.

    Parameters
    ----------
    scene_file : Path
        The scene (its folder also takes ``run``'s output, which must stay empty).
    sets : list of str
        ``KEY=VALUE`` changes.

    Returns
    -------
    (str, str)
        ``("accepted" | "refused" | "wrong", the error line or why it is wrong)``; a
        refusal's key is the part between the source and the message.
    """
    flags = [a for s in sets for a in ("--set", s)]
    code, text = _cli(["validate", str(scene_file), *flags])
    if code == 0:
        return "accepted", ""
    line = text.removeprefix("clothsim: error: ").rstrip("\n")
    source = re.escape(str(scene_file))
    named = (re.match(rf"^{source}: [^:\s][^:]*: \S", line)
             or re.match(r"^--set .+?: \S", line))
    if (code != 2 or text.count("\n") != 1 or not text.startswith("clothsim: error: ")
            or not named or len(text) > 600 or "Traceback" in text
            or re.search(r"\b[A-Z]\w*(Error|Exception):", text) or "np.float64" in text):
        return "wrong", f"exit {code}: {text[:300]!r}"
    out = scene_file.parent / "o"
    code2, text2 = _cli(["run", str(scene_file), *flags, "--out", str(out), "--no-preview"])
    if code2 != 2 or text2 != text or list(out.glob("*")):
        return "wrong", f"run: exit {code2}, {text2[:200]!r}, wrote {list(out.glob('*'))}"
    return "refused", line


def _count(strategy, case, key, examples: int) -> tuple[Counter, list[str], Counter]:
    counts, wrong, keys = Counter(), [], Counter()

    @settings(max_examples=examples, deadline=None, derandomize=True, database=None,
              suppress_health_check=list(HealthCheck))
    @given(strategy)
    def run(value):
        kind, line = case(value)
        counts[kind] += 1
        if kind == "wrong":
            wrong.append(line)
        elif kind == "refused":
            keys[key(value, line)] += 1
            counts["naming the --set"] += line.startswith("--set ")

    run()
    return counts, wrong, keys


def fuzz(examples: int = EXAMPLES) -> dict:
    """Run both generators through ``clothsim validate`` and count the outcomes.

    Parameters
    ----------
    examples : int
        Cases per generator.

    Returns
    -------
    dict
        ``{"scene files": (outcomes, wrong lines, keys named), "--set": (…)}``: Counters
        of "accepted"/"refused"/"wrong" and of the keys refusals name ("" for the --set
        alone), and the first lines of the wrong cases.
    """
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        count = [0]

        def folder(text: str) -> Path:
            d = tmp / f"s{count[0]}"
            count[0] += 1
            d.mkdir()
            (d / "scene.toml").write_text(text)
            return d / "scene.toml"

        def scene_case(doc):
            return outcome(folder(to_toml(doc)))

        def set_case(item):
            return outcome(folder(to_toml(VALID)), [item])

        def scene_key(doc, line):
            return named_key(line, tmp / f"s{count[0] - 1}" / "scene.toml")

        def set_key(item, line):
            return named_key(line, tmp / f"s{count[0] - 1}" / "scene.toml", [item])

        return {"scene files": _count(mutated_scene(), scene_case, scene_key, examples),
                "--set": _count(set_change(), set_case, set_key, examples)}


def commit() -> str:
    """The short commit of the code measured (``+dirty`` with uncommitted changes).

    Returns
    -------
    str
    """
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return head + ("+dirty" if dirty else "")


def main() -> None:
    import logging
    import warnings

    logging.disable(logging.WARNING)  # the obstacle overlap warnings of accepted cases
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        results = fuzz()
    lines = [f"commit {commit()}: hypothesis (derandomized), {EXAMPLES} cases per generator, "
             f"each through `clothsim validate` (and `run` for a refusal)"]
    for name, (counts, wrong, keys) in results.items():
        total = counts["accepted"] + counts["refused"] + counts["wrong"]
        lines.append(f"{name}: {total} cases; {counts['accepted']} accepted (exit 0); "
                     f"{counts['refused']} refused in one line naming "
                     + (f"the --set ({counts['naming the --set']} of them; the file is valid) "
                        f"and the key " if name == "--set" else "the file and a key ")
                     + f"(exit 2; `run` refused them identically and wrote nothing); "
                     f"{counts['wrong']} otherwise; {len([k for k in keys if k])} distinct keys "
                     f"named" + (f" ({keys['']} refusals name only the --set: a malformed "
                                 f"KEY=VALUE)" if name == "--set" else ""))
        lines += [f"  wrong: {w}" for w in wrong[:10]]
    print("\n".join(f"   {line}" for line in lines))
    OUT.write_text("Printed by `.venv/bin/python -m benchmarks fuzz_scenes`:\n\n```text\n"
                   + "\n".join(lines) + "\n```\n", encoding="utf-8")


if __name__ == "__main__":
    main()
