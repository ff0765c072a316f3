"""Shared test models, assertion helpers, fixtures and the tool markers.

Models: one name per parameter set, so that two tests using "the stick model" use the same
one (they differed before: a = 0.2 in the circuit tests, 0.3 in the weak-noise tests).
Import them with ``from conftest import STICK_A02`` (``tests/`` is on the path: see
``pythonpath`` in pyproject.toml).

Markers (registered in pyproject.toml):

* ``requires_ngspice``: skipped, with the reason, when no ``ngspice`` is on PATH;
* ``requires_chromium``: skipped, with the reason, when no headless Chromium is found.

``make test`` installs both (``scripts/install-system.sh --test``), so CI runs those tests.
"""
from __future__ import annotations

import json
import math
import shutil
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

from analogue import Model

# ---------------------------------------------------------------------------- models
# tau_m = 1, Delta = 0.7, gamma = 10 throughout; the force a picks the regime.
STICK_A02 = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)   # stick regime, circuit tests
STICK_FIG2 = Model(tau_m=1.0, delta=0.7, a=0.3, gamma=10.0)  # stick regime, paper Fig. 2
SLIP_A12 = Model(tau_m=1.0, delta=0.7, a=1.2, gamma=10.0)    # slip regime, paper Fig. 4
OU_A05 = Model(tau_m=1.0, delta=0.0, a=0.5, gamma=10.0)      # Delta = 0: Ornstein-Uhlenbeck

CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome")


# ------------------------------------------------------------------ assertion helpers
def assert_within_se(estimate: float, truth: float, stderr: float, *, k: float = 4.0,
                     bias: float = 0.0) -> None:
    """``|estimate - truth| <= k stderr + |bias|``: a statistical check whose tolerance comes
    from the estimator's standard error (plus a documented systematic bias)."""
    assert math.isfinite(stderr) and stderr >= 0, stderr
    gap = abs(estimate - truth)
    assert gap <= k * stderr + abs(bias), (
        f"estimate {estimate!r} vs {truth!r}: |diff| = {gap:.3g} > {k:g} x {stderr:.3g}"
        + (f" + bias {abs(bias):.3g}" if bias else ""))


def stationary_stats(e: Any, t_from: float, every: int = 1) -> tuple[float, float, float, float]:
    """``(mean, se, variance, se)`` of an ensemble's velocity pooled over its output times from
    ``t_from`` on (every ``every``-th), standard errors from the replicas: each replica's own
    average is one independent draw, so the correlation along a path is accounted for."""
    v = e.v[:, e.t >= t_from - 1e-9][:, ::every]
    mean_i = v.mean(axis=1)
    mean = float(mean_i.mean())
    sq_i = ((v - mean) ** 2).mean(axis=1)
    n = v.shape[0]
    return (mean, float(mean_i.std(ddof=1)) / math.sqrt(n),
            float(sq_i.mean()), float(sq_i.std(ddof=1)) / math.sqrt(n))


def assert_unit_normal(z: np.ndarray, *, k: float = 4.0) -> None:
    """Mean 0 and standard deviation 1 within k standard errors (i.i.d. normals)."""
    n = np.size(z)
    assert abs(float(np.mean(z))) < k / math.sqrt(n)
    assert abs(float(np.std(z)) - 1.0) < k / math.sqrt(2 * n)


def chromium() -> str | None:
    """Path of a headless-capable Chromium, or None."""
    for name in CHROMIUM_NAMES:
        path = shutil.which(name)
        if path:
            return path
    return None


def toml_text(doc: dict[str, Any]) -> str:
    """A TOML document (tomli-w is not a dependency): scalars and arrays first, then tables."""
    def value(x):
        if isinstance(x, bool):
            return "true" if x else "false"
        if isinstance(x, float):
            return "inf" if x == math.inf else "-inf" if x == -math.inf else "nan" if x != x else repr(x)
        if isinstance(x, int):
            return str(x)
        if isinstance(x, str):
            return json.dumps(x)  # JSON string escapes are TOML basic-string escapes
        if isinstance(x, list):
            return "[" + ", ".join(value(v) for v in x) + "]"
        raise TypeError(x)

    def table(d, prefix):
        lines = [f"{k} = {value(v)}" for k, v in d.items() if not isinstance(v, dict)]
        for k, v in d.items():
            if isinstance(v, dict):
                name = f"{prefix}.{k}" if prefix else k
                lines += ["", f"[{name}]", *table(v, name)]
        return lines
    return "\n".join(table(doc, "")) + "\n"


# ----------------------------------------------------------------------------- fixtures
@pytest.fixture
def cli(monkeypatch: pytest.MonkeyPatch) -> CliRunner:
    """A click runner for ``analogue``; ANALOGUE_DEBUG unset so errors are one line."""
    monkeypatch.delenv("ANALOGUE_DEBUG", raising=False)
    return CliRunner()


@pytest.fixture
def stick_model() -> Model:
    return STICK_A02


@pytest.fixture
def slip_model() -> Model:
    return SLIP_A12


# ------------------------------------------------------------------------------ markers
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    have_ngspice = shutil.which("ngspice") is not None
    have_chromium = chromium() is not None
    skip_ngspice = pytest.mark.skip(reason="ngspice is not on PATH (apt-get install ngspice; "
                                           "make test installs it)")
    skip_chromium = pytest.mark.skip(reason="headless Chromium not found (apt-get install "
                                            "chromium; make test installs it)")
    for item in items:
        if not have_ngspice and item.get_closest_marker("requires_ngspice"):
            item.add_marker(skip_ngspice)
        if not have_chromium and item.get_closest_marker("requires_chromium"):
            item.add_marker(skip_chromium)
