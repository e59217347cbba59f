"""The fixed-budget figure's uncertainty band lies below the points it bounds."""

import math
from types import SimpleNamespace

import pytest

from clothsim.accuracy.plots import fixed_budget_figure, plot_fixed_budget


def rows(errors):
    return [SimpleNamespace(method="local-global", iterations=k, tolerance=None,
                            solver_error_median=e, solver_error_p90=2 * e)
            for k, e in errors]


def band(fig):
    ax = fig.axes[0]
    (patch,) = [p for p in ax.patches if p.get_label() == "below the reference's uncertainty"]
    ys = patch.get_transform().transform(patch.get_path().vertices)[:, 1]
    return ax, ax.transData.inverted().transform([[0, y] for y in (ys.min(), ys.max())])[:, 1]


@pytest.mark.parametrize("errors, uncertainty", [
    ([(1, 0.3), (5, 0.2), (20, 0.1)], 1e-6),      # every point far above: the docs' hanging
    ([(1, 0.3), (5, 1e-3), (20, 1e-7)], 1e-6),     # some points below: not plotted
    ([(1, 2e-6), (5, 1.5e-6)], 1e-6),              # just above
])
def test_the_band_spans_from_the_bottom_up_to_the_uncertainty(errors, uncertainty):
    fig = fixed_budget_figure(rows(errors), uncertainty=uncertainty)
    ax, (bottom, top) = band(fig)
    low, high = ax.get_ylim()
    assert math.isclose(top, uncertainty, rel_tol=1e-6)
    assert math.isclose(bottom, low, rel_tol=1e-6) and low < uncertainty < high
    for line in ax.get_lines():
        y = [v for v in line.get_ydata() if math.isfinite(v)]
        if line.get_label().endswith("(median)"):
            assert y and min(y) > uncertainty and max(y) <= high


def test_no_band_without_an_uncertainty_and_the_file_is_written(tmp_path):
    fig = fixed_budget_figure(rows([(1, 0.3), (5, 0.1)]))
    assert not fig.axes[0].patches
    path = plot_fixed_budget(rows([(1, 0.3), (5, 0.1)]), tmp_path / "f.png", uncertainty=1e-9)
    assert path.read_bytes().startswith(b"\x89PNG")
