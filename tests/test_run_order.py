"""The run order of the suite (tests/conftest.py): the long files it puts first are there.

``pytest_collection_modifyitems`` leads each half of the collection with one group of
:data:`LONGEST`; a file moved or renamed would silently drop out of its group and could again
make a tail on one worker, so each name must be a test file of the suite.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

TESTS = Path(__file__).resolve().parent


def _longest() -> tuple[tuple[str, ...], ...]:
    spec = importlib.util.spec_from_file_location("tests_conftest_order", TESTS / "conftest.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return tuple(module.LONGEST)


def test_every_file_put_first_is_a_test_file_of_the_suite():
    groups = _longest()
    assert len(groups) == 2 and all(groups)
    names = [name for group in groups for name in group]
    assert len(set(names)) == len(names), names
    missing = [name for name in names if not (TESTS / name).is_file()
               or not Path(name).name.startswith("test_")]
    assert missing == [], f"LONGEST names files that are not there: {missing}"
