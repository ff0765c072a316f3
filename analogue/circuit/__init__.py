"""The stick-slip model as an analogue circuit: mapping, parts, decks, experiments.

The runner (ngspice, raw files, :func:`analogue.simulate`) lives in the sibling modules
``ngspice``, ``store``, ``runner`` (:class:`Runner`: how decks run), ``decks`` (running them)
and ``simulate``.  The names below load on first use, so that importing
one of those modules (as the command line's signal handling does) does not pull in PySpice.
"""
from __future__ import annotations

import importlib
from typing import Any

__all__ = ["CircuitSpec", "CircuitMapping", "map_model", "Deck", "build_deck",
           "Experiment", "load_experiment", "regenerate_netlists", "Runner"]

_HOME = {"CircuitSpec": "mapping", "CircuitMapping": "mapping", "map_model": "mapping",
         "Deck": "netlist", "build_deck": "netlist",
         "Experiment": "experiments", "load_experiment": "experiments",
         "regenerate_netlists": "experiments", "Runner": "runner"}


def __getattr__(name: str) -> Any:
    if name in _HOME:
        return getattr(importlib.import_module(f".{_HOME[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
