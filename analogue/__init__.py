"""analogue: stick-slip friction with noise, as theory and as an ngspice circuit.

Public entry points: :class:`Model`, :class:`Ensemble`, :func:`simulate` (the circuit in
ngspice) with :class:`Runner` (how its decks run: store, workers, executor, timeout,
progress), :func:`open_ensemble` (netCDF files of ``Ensemble.to_netcdf`` / ``analogue export``),
:func:`load_runs` (an experiment's circuit runs by role), ``report(experiment, out=...,
quick=...)`` (what ``analogue report`` does, returning an :class:`analogue.study.run.StudyResult`;
``analogue.report`` is also the package of the page's modules), :func:`sweep` (an experiment
over a grid of parameters: circuit and exact theory, an xarray.Dataset), the theory packages :mod:`analogue.theory.weak_noise` and
:mod:`analogue.theory.exact`, and the estimators in :mod:`analogue.estimators`.

Where things live (layers, lowest first; an import only points down,
``tests/unit/test_import_layers.py`` checks it):

==========================  ============================================================
foundations                 ``checks`` (argument checks), ``cores`` (usable CPUs), ``files``
                            (atomic UTF-8 writes), ``noise_free`` (deterministic motion),
                            ``netcdf_layout``, ``paper`` (the paper's parameters)
model and data              ``model`` (:class:`Model`), ``variants`` (the family's variants as
                            types: friction law, spring, noise kind; found by dispatch),
                            ``ensemble`` (:class:`Ensemble`, simulated paths with provenance)
theory                      ``theory.weak_noise*`` (the paper's gamma -> inf results),
                            ``theory.exact`` / ``stationary`` / ``propagation`` /
                            ``exact_grid`` (Fokker-Planck), ``work_statistics`` (tilted
                            generator), ``family`` / ``kolmogorov_feller`` (family members,
                            shot noise), ``friction_law`` (any odd friction law, real diodes),
                            ``spectrum``, ``first_passage``, ``bias_transport``
estimators                  ``estimators.*``: densities, stationary moments, work, spectra,
                            first passage, jackknife/resampling, with standard errors
runs                        ``montecarlo`` (SDE reference), ``circuit.*`` (mapping, decks,
                            ngspice, the run store, :class:`Runner`, :func:`simulate`),
                            ``data`` (netCDF)
study                       ``study.*``: settings, seeds, the observable catalogue, the runs
                            by role (``runs``), circuit-free theory (``theory_curves``),
                            ``comparisons``, ``budget``, ``metrics``, the family members'
                            analysis (``members``), the schedule (``schedule``) and
                            ``run.run_study`` -> ``StudyResult``; ``experiments``
                            (TOML experiments)
pages                       ``report.*`` (figures, prose, the page from a ``StudyResult``;
                            ``analogue.report(...)`` itself), ``plots.*``, ``board.*`` (a
                            buildable board), ``export``
command line                ``cli``
==========================  ============================================================
"""
from .model import Model, MechanicalParameters, ShotNoise
from .ensemble import Ensemble

__all__ = ["Model", "MechanicalParameters", "ShotNoise", "Ensemble", "simulate", "Runner",
           "open_ensemble", "load_runs", "report", "sweep"]
__version__ = "0.1.0"


_SUBMODULES = ("theory", "estimators", "montecarlo", "circuit", "report", "plots")


def __dir__():
    """The module's names with the lazily loaded ones (``simulate``, ``Runner``, ``open_ensemble``,
    ``load_runs``, ``sweep`` and the subpackages), which :func:`__getattr__` imports on first use."""
    return sorted(set(globals()) | set(__all__) | set(_SUBMODULES))


def __getattr__(name):
    # The circuit runner pulls in PySpice and friends; import it only when asked for.
    if name == "simulate":
        from .circuit.simulate import simulate
        return simulate
    if name == "Runner":
        from .circuit.runner import Runner
        return Runner
    # xarray / netCDF and the report's run plan load only when asked for, too.
    if name == "open_ensemble":
        from .data import open_ensemble
        return open_ensemble
    if name == "load_runs":
        from .export import load_runs
        return load_runs
    # parameter sweeps (circuit + exact theory over a grid, an xarray.Dataset): study layer
    if name == "sweep":
        from .study.sweep import sweep
        return sweep
    if name in _SUBMODULES:
        import importlib
        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module 'analogue' has no attribute {name!r}")
