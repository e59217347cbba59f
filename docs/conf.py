"""Sphinx configuration of the clothsim documentation (``make docs``).

MyST Markdown pages, numpydoc API reference, and the sphinx-gallery of lessons in
``examples/`` (executed at every build; each lesson also downloadable as a notebook).
The scene reference in scenes.md is generated from the schema in the code (a test keeps it equal).
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))  # document (and run the gallery against) this checkout
os.environ.setdefault("MPLBACKEND", "Agg")

import clothsim  # noqa: E402

project = "clothsim"
author = "the clothsim contributors"
copyright = "2026, the clothsim contributors"  # noqa: A001 (Sphinx's name)
release = version = clothsim.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "**.ipynb_checkpoints", "auto_examples/*.ipynb",
                    "auto_examples/*.py", "data", "img/README*"]
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence"]
myst_heading_anchors = 3
suppress_warnings = ["myst.header"]  # pages written for GitHub start at any heading level

autodoc_default_options = {"members": True, "show-inheritance": False}
autodoc_member_order = "bysource"
autodoc_typehints = "none"
autosummary_generate = True
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_validation_checks: set[str] = set()  # tests/test_docs.py checks the sections

html_theme = "pydata_sphinx_theme"
html_title = f"clothsim {version}"
html_theme_options = {"navigation_depth": 2, "show_toc_level": 2}

sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": str(HERE / "auto_examples"),
    "filename_pattern": r"/plot_",
    "abort_on_example_error": True,
    "download_all_examples": True,
    "remove_config_comments": True,
    "matplotlib_animations": False,
    "within_subsection_order": "FileNameSortKey",
    "show_memory": False,
}


_LITERAL = re.compile(r"(``.*?``)")


def _escape_bars(app, what, name, obj, options, lines) -> None:
    """Docstrings write norms as |x|, which reStructuredText reads as substitutions: escape
    every | outside inline literals (grid-table rows are left alone)."""
    for i, line in enumerate(lines):
        stripped = line.strip()
        if "|" not in line or stripped.startswith("+-") or (
                stripped.startswith("|") and stripped.endswith("|") and len(stripped) > 2
                and stripped.count("|") > 2):
            continue
        parts = _LITERAL.split(line)
        lines[i] = "".join(p if p.startswith("``") else p.replace("|", "\\|") for p in parts)


def setup(app):
    app.connect("autodoc-process-docstring", _escape_bars, priority=100)


#: API pages: title and the module prefixes each page documents. Every module of the
#: package is found by walking it (a new module cannot be left out); each goes on the first
#: page whose prefix it has.
API_PAGES = {
    "model": ("Meshes, springs, models", [
        "clothsim.mesh", "clothsim.polygon", "clothsim.mesh_checks", "clothsim.voronoi",
        "clothsim.springs", "clothsim.model", "clothsim.gallery"]),
    "solvers": ("Solvers and the time step", [
        "clothsim.simulation", "clothsim.magnitudes", "clothsim.state", "clothsim.problem",
        "clothsim.contacts",
        "clothsim.objective", "clothsim.solvers", "clothsim.factorization",
        "clothsim.factor_mode"]),
    "effects": ("Effects", ["clothsim.effects"]),
    "scenes-and-runs": ("Scenes, runs and files", [
        "clothsim.scene", "clothsim.runner", "clothsim.interrupts", "clothsim.io",
        "clothsim.datasets", "clothsim.cli"]),
    "pictures": ("Pictures", ["clothsim.plotting", "clothsim.painter", "clothsim.camera",
                              "clothsim.display"]),
    "analysis": ("Matrices, energy, accuracy, ports", [
        "clothsim.matrices", "clothsim.reference", "clothsim.energy", "clothsim.accuracy",
        "clothsim.ports"]),
}


def _modules() -> list[str]:
    """Every module of the clothsim package in this checkout, sorted (packages included)."""
    import pkgutil

    import clothsim

    names = ["clothsim"] + [m.name for m in pkgutil.walk_packages(clothsim.__path__,
                                                                   "clothsim.")]
    return sorted(n for n in names if not n.endswith("__main__"))


def _is_package(name: str) -> bool:
    return (ROOT.joinpath(*name.split(".")) / "__init__.py").is_file()


def _page_of(name: str) -> str | None:
    for page, (_, prefixes) in API_PAGES.items():
        if any(name == p or name.startswith(p + ".") for p in prefixes):
            return page
    return None


def _api_pages() -> None:
    """Write docs/api/<page>.rst with one ``automodule`` per module of the package."""
    pages: dict[str, list[str]] = {page: [] for page in API_PAGES}
    for name in _modules():
        page = _page_of(name)
        if page is not None:
            pages[page].append(name)
    for page, (title, _) in API_PAGES.items():
        lines = [title, "=" * len(title), ""]
        for name in pages[page]:
            lines += [f".. automodule:: {name}"]
            if _is_package(name):  # only what the package itself defines: its re-exports
                lines += ["   :ignore-module-all:"]  # are documented where they are defined
            lines += [""]
        text = "\n".join(lines)
        out = HERE / "api" / f"{page}.rst"
        if not out.exists() or out.read_text(encoding="utf-8") != text:
            out.write_text(text, encoding="utf-8")


_api_pages()
