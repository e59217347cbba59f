"""The scene schema is data: docs/scenes.md holds its generated reference verbatim, and the
validator accepts exactly the keys it lists."""

from pathlib import Path

import pytest

from clothsim.scene import Scene, SceneError, schema_markdown
from clothsim.scene.schema import KEYS, default, keys

DOCS = Path(__file__).resolve().parents[2] / "docs" / "scenes.md"


def test_docs_hold_the_generated_reference():
    text = DOCS.read_text(encoding="utf-8")
    block = text.split("<!-- schema:begin -->\n")[1].split("<!-- schema:end -->")[0]
    assert block == schema_markdown(), ("docs/scenes.md is out of date; paste "
                                        "clothsim.scene.schema_markdown() between the markers")
    for k in KEYS:
        assert f"| `{k.name}` |" in block


def test_every_schema_key_is_accepted_and_every_other_rejected():
    for table in ("scene", "solver"):
        for name in keys(table):
            with pytest.raises(SceneError) as info:
                Scene.from_dict({table: {name: object()}})
            assert f"{table}.{name}:" in str(info.value)
            assert "unknown key" not in str(info.value)
        with pytest.raises(SceneError, match=rf"{table}.nonsense: unknown key"):
            Scene.from_dict({table: {"nonsense": 1}})


def test_defaults_come_from_the_schema():
    s = Scene.from_dict({})
    for name in ("frames", "fps", "substeps"):
        assert s.data["scene"][name] == default("scene", name)
    for name in ("method", "iterations", "backend"):
        assert s.data["solver"][name] == default("solver", name)
    assert s.data["cloth"]["resolution"] == default("cloth", "resolution")
