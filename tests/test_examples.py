"""Every example runs, checks its own physics, writes its plot, and gives its known figure."""

import importlib.util
from pathlib import Path

import pytest

EXAMPLES = sorted((Path(__file__).parents[1] / "examples").glob("*.py"))
# the figure each example's main() returns, and the range it must fall in
KNOWN = {
    "hanging_cloth": (0.005, 0.2),            # sag of the lowest vertex [m]
    "local_global_vs_newton": (0.01, 0.3),    # relative error after 10 iterations
}


def load(path):
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example(path, tmp_path):
    value = load(path).main(tmp_path)
    assert any(tmp_path.iterdir()), "the example wrote nothing"
    if path.stem in KNOWN:
        lo, hi = KNOWN[path.stem]
        assert lo < value < hi
