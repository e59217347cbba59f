"""Every gallery lesson runs (non-interactive Agg backend), passes its own assertions,
draws at least one figure, and the two lessons with a known figure give it."""

import runpy
from pathlib import Path

import pytest

EXAMPLES = sorted((Path(__file__).parents[1] / "examples").glob("plot_*.py"))
# the module-level figure a lesson computes, and the range it must fall in
KNOWN = {
    "plot_hanging_cloth": ("sag", 0.005, 0.2),                     # lowest vertex sag [m]
    "plot_local_global_vs_newton": ("error_after_10", 0.01, 0.3),  # relative error
}
SLOW = {"plot_error_vs_wall_time", "plot_stiffness_slows_convergence",
        "plot_coursework_scenes", "plot_drop_on_square"}


def test_there_are_at_least_14_lessons():
    assert len(EXAMPLES) >= 14


@pytest.mark.parametrize("path", [pytest.param(p, marks=pytest.mark.slow) if p.stem in SLOW
                                  else p for p in EXAMPLES], ids=[p.stem for p in EXAMPLES])
def test_example(path, tmp_path, monkeypatch):
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    monkeypatch.chdir(tmp_path)
    plt.close("all")
    try:
        namespace = runpy.run_path(str(path), run_name="__main__")
        assert plt.get_fignums(), "the lesson drew no figure"
    finally:
        plt.close("all")
    if path.stem in KNOWN:
        name, lo, hi = KNOWN[path.stem]
        assert lo < namespace[name] < hi


def test_examples_have_a_gallery_title_and_an_assertion():
    for path in EXAMPLES:
        text = path.read_text(encoding="utf-8")
        assert text.startswith('"""\n'), path.name
        title, underline = text.splitlines()[1:3]
        assert underline == "=" * len(title), path.name
        assert "\nassert " in text or "    assert " in text, path.name
        assert title.strip(), path.name
