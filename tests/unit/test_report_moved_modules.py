"""The modules that moved from ``analogue.report`` to the study layer (issue 20) still import
under their old names, as the very same module objects, with a DeprecationWarning."""
from __future__ import annotations

import importlib

import pytest

from analogue.report import MOVED


@pytest.mark.parametrize("name", sorted(MOVED))
def test_old_name_is_the_study_module(name):
    new = importlib.import_module(MOVED[name])
    with pytest.warns(DeprecationWarning, match=f"analogue.report.{name} moved"):
        import sys
        sys.modules.pop(f"analogue.report.{name}", None)
        old = importlib.import_module(f"analogue.report.{name}")
    assert old is new
    assert new.__name__ == MOVED[name]


def test_unknown_submodule_still_fails():
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module("analogue.report.no_such_module")
