"""analogue: stick-slip friction with noise, as theory and as an ngspice circuit.

Public entry points: :class:`Model`, :class:`Ensemble`, :func:`simulate` (the circuit in
ngspice), the theory packages :mod:`analogue.theory.weak_noise` and
:mod:`analogue.theory.exact`, and the estimators in :mod:`analogue.estimators`.
"""
from .model import Model, MechanicalParameters
from .ensemble import Ensemble

__all__ = ["Model", "MechanicalParameters", "Ensemble", "simulate"]
__version__ = "0.1.0"


_SUBMODULES = ("theory", "estimators", "montecarlo", "circuit", "report", "plots")


def __getattr__(name):
    # The circuit runner pulls in PySpice and friends; import it only when asked for.
    if name == "simulate":
        from .circuit.simulate import simulate
        return simulate
    if name in _SUBMODULES:
        import importlib
        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module 'analogue' has no attribute {name!r}")
