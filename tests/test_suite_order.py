"""make test's order of files (tests/conftest.py): the longest files first, each whole."""

from pathlib import Path

from .conftest import LONGEST_FIRST, pytest_collection_modifyitems

TESTS = Path(__file__).resolve().parent


def test_every_file_named_longest_first_exists_once():
    assert len(set(LONGEST_FIRST)) == len(LONGEST_FIRST)
    missing = [name for name in LONGEST_FIRST if not (TESTS / name).is_file()]
    assert not missing, f"tests/conftest.py LONGEST_FIRST names files that are gone: {missing}"


class _Item:
    def __init__(self, name, test):
        self.path, self.test = TESTS / name, test


def test_the_named_files_go_first_in_their_order_and_keep_their_tests_order():
    first, second = LONGEST_FIRST[:2]
    items = [_Item("test_mesh.py", "a"), _Item(second, "b"), _Item(first, "c"),
             _Item(second, "d"), _Item("test_mesh.py", "e"), _Item(first, "f")]
    pytest_collection_modifyitems(items)
    assert [i.test for i in items] == ["c", "f", "b", "d", "a", "e"]
