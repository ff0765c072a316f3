"""The stick-slip model as an analogue circuit: mapping, parts, decks, experiments.

The runner (ngspice, raw files, :func:`analogue.simulate`) lives in the sibling modules
``ngspice``, ``store`` and ``simulate``.
"""
from .mapping import CircuitSpec, CircuitMapping, map_model
from .netlist import Deck, build_deck
from .experiments import Experiment, load_experiment, regenerate_netlists

__all__ = ["CircuitSpec", "CircuitMapping", "map_model", "Deck", "build_deck",
           "Experiment", "load_experiment", "regenerate_netlists"]
