"""Reports: draw the figures and write the pages (``index.html``, ``metrics.json``) of a study.

What a report computes (the runs by role, the circuit-free theory, the comparisons and their
error budgets, the metrics) lives in :mod:`analogue.study`; the modules that held it here first
(``analogue.report.runs``, ``.comparisons``, ``.theory_curves``, ``.budget``, ``.metrics``,
``.observables``, ``.critical_path``) still import, as the study layer's modules themselves
(deprecated: import them from :mod:`analogue.study`).
"""
from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings

# old name under analogue.report -> its home in the study layer (issue 20)
MOVED = {name: f"analogue.study.{name}" for name in (
    "runs", "comparisons", "theory_curves", "budget", "metrics", "observables", "critical_path")}


class _MovedLoader(importlib.abc.Loader):
    def __init__(self, target: str):
        self.target = target

    def create_module(self, spec):
        return importlib.import_module(self.target)

    def exec_module(self, module) -> None:
        pass  # the study module is already executed


class _MovedFinder(importlib.abc.MetaPathFinder):
    """``import analogue.report.runs`` gives :mod:`analogue.study.runs` itself (one module
    object, so a monkeypatch through either name reaches both), with a DeprecationWarning."""

    def find_spec(self, fullname, path=None, target=None):
        prefix, _, leaf = fullname.rpartition(".")
        if prefix != __name__ or leaf not in MOVED:
            return None
        warnings.warn(f"{fullname} moved to {MOVED[leaf]}; import it from there",
                      DeprecationWarning, stacklevel=2)
        return importlib.util.spec_from_loader(fullname, _MovedLoader(MOVED[leaf]))


if not any(isinstance(f, _MovedFinder) for f in sys.meta_path):
    sys.meta_path.append(_MovedFinder())


class _CallableModule(type(sys)):  # type: ignore[misc]
    """``analogue.report`` is this package and the Python entry point at once:
    ``analogue.report("stick", quick=True)`` is :func:`analogue.report.pipeline.report`, and
    ``from analogue.report import figures`` still imports the module (a package's attribute
    is set by the import system, so a function could not take the name)."""

    def __call__(self, experiment, out=None, **kwargs):
        from .pipeline import report  # the page's modules load only when a report is made
        return report(experiment, out, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
