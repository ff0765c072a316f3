"""The stick-slip model as an analogue circuit: mapping, parts, decks.

The runner (ngspice, raw files, :func:`analogue.simulate`) lives in the sibling modules
``ngspice``, ``store``, ``runner`` (:class:`Runner`: how decks run), ``decks`` (running them)
and ``simulate``.  The names below load on first use, so that importing
one of those modules (as the command line's signal handling does) does not pull in PySpice.
An experiment (a TOML file: model, circuit, report settings) is the study layer's
(:mod:`analogue.study.experiments`); ``analogue.circuit.experiments`` still imports, as that
module itself.
"""
from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
from typing import Any

__all__ = ["CircuitSpec", "CircuitMapping", "map_model", "Deck", "build_deck",
           "Experiment", "load_experiment", "regenerate_netlists", "Runner"]

_HOME = {"CircuitSpec": "mapping", "CircuitMapping": "mapping", "map_model": "mapping",
         "Deck": "netlist", "build_deck": "netlist",
         "Experiment": "..study.experiments", "load_experiment": "..study.experiments",
         "regenerate_netlists": "..study.experiments", "Runner": "runner"}
# the experiment moved to the study layer; its old module name is the same module object
_MOVED = {f"{__name__}.experiments": "analogue.study.experiments"}


class _MovedLoader(importlib.abc.Loader):
    def __init__(self, target: str):
        self.target = target

    def create_module(self, spec):
        return importlib.import_module(self.target)

    def exec_module(self, module) -> None:
        pass  # already executed under its own name


class _MovedFinder(importlib.abc.MetaPathFinder):
    def find_spec(self, fullname, path=None, target=None):
        if fullname not in _MOVED:
            return None
        return importlib.util.spec_from_loader(fullname, _MovedLoader(_MOVED[fullname]))


if not any(isinstance(f, _MovedFinder) for f in sys.meta_path):
    sys.meta_path.append(_MovedFinder())


def __getattr__(name: str) -> Any:
    if name in _HOME:
        home = _HOME[name]
        module = home if home.startswith(".") else f".{home}"
        return getattr(importlib.import_module(module, __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
