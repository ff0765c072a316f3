"""Circuit-versus-theory comparisons and the ``metrics.json`` schema.

One :class:`Comparison` per observable: the circuit estimate with its statistical standard
error, the theory value it is held against (exact finite-noise numerics of the ideal sgn model,
or the paper's weak-noise formula), the z-score, and the error budget that decides whether a
deviation is explained: statistics, diode smoothing, noise sample interval, integration.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

__all__ = ["Budget", "Comparison", "compare", "validate_metrics", "THEORY_KINDS"]

THEORY_KINDS = ("exact", "weak-noise")
Z_LIMIT = 3.0


@dataclass(frozen=True)
class Budget:
    """Systematic error estimates (absolute, in the observable's units), each signed where the
    sign is known: circuit - ideal model, as predicted or measured by an independent route."""

    smoothing: float = 0.0      # diode tanh width: exact(eps) - exact(0)
    bandwidth: float = 0.0      # held noise: SDE with held vs white noise, same increments
    integration: float = 0.0    # ngspice tolerances (same noise, tighter reltol)
    sampling: float = 0.0       # output grid / histogram binning
    finite_noise: float = 0.0   # weak-noise comparisons: exact(gamma) - (gamma -> infinity)
    element: float = 0.0        # the model family's circuit elements (issue 9): cubic network
    #                             approximation, inductor series resistance, shot pulse shape;
    #                             a real diode bridge's DC law against its tanh (issue 18)

    def total(self) -> float:
        return sum(abs(v) for v in asdict(self).values())

    def dominant(self) -> str:
        items = {k: abs(v) for k, v in asdict(self).items()}
        return max(items, key=lambda name: items[name])


@dataclass(frozen=True)
class Comparison:
    experiment: str
    observable: str
    circuit: float
    circuit_stderr: float
    theory: float
    theory_kind: str
    z: float
    within_budget: bool
    budget: Budget = field(default_factory=Budget)
    note: str = ""

    def as_dict(self) -> dict:
        d = asdict(self)
        d["budget"]["total"] = self.budget.total()
        d["budget"]["statistical"] = Z_LIMIT * self.circuit_stderr
        d["budget"]["dominant"] = (self.budget.dominant()
                                   if self.budget.total() > Z_LIMIT * self.circuit_stderr
                                   else "statistical")
        for k, v in list(d.items()):
            if isinstance(v, float) and not math.isfinite(v):
                d[k] = None  # JSON has no NaN
        return d


def compare(experiment: str, observable: str, circuit: float, stderr: float, theory: float,
            theory_kind: str = "exact", budget: Budget | None = None, note: str = "") -> Comparison:
    """z = (circuit - theory)/stderr; within budget if |circuit - theory| <= 3 stderr + the
    sum of the systematic terms (a conservative, linear sum)."""
    if theory_kind not in THEORY_KINDS:
        raise ValueError(f"theory_kind must be one of {THEORY_KINDS}, got {theory_kind!r}")
    budget = budget or Budget()
    diff = float(circuit) - float(theory)
    z = diff / stderr if stderr > 0 else (0.0 if diff == 0 else math.copysign(math.inf, diff))
    ok = abs(diff) <= Z_LIMIT * stderr + budget.total()
    return Comparison(experiment, observable, float(circuit), float(stderr), float(theory),
                      theory_kind, float(z), bool(ok), budget, note)


_REQUIRED: dict[str, type | tuple[type, ...]] = {"experiment": str, "observable": str, "circuit": (int, float),
             "circuit_stderr": (int, float), "theory": (int, float), "theory_kind": str,
             "z": (int, float, type(None)), "within_budget": bool}


def validate_metrics(obj: dict) -> None:
    """Raise ValueError unless ``obj`` follows the metrics.json schema."""
    if not isinstance(obj, dict):
        raise ValueError("metrics must be a JSON object")
    for key in ("comparisons", "provenance"):
        if key not in obj:
            raise ValueError(f"metrics.json lacks {key!r}")
    failures = obj.get("failures", [])
    if not isinstance(failures, list):
        raise ValueError("metrics.json 'failures' must be a list")
    for i, f in enumerate(failures):
        if not isinstance(f, dict) or not all(isinstance(f.get(k), str)
                                              for k in ("section", "stage", "error")):
            raise ValueError(f"failure {i} must have string 'section', 'stage' and 'error'")
    # a report whose every experiment failed still records why (failures), with no comparisons
    if not isinstance(obj["comparisons"], list) or not (obj["comparisons"] or failures):
        raise ValueError("metrics.json 'comparisons' must be a non-empty list")
    for i, c in enumerate(obj["comparisons"]):
        for k, typ in _REQUIRED.items():
            if k not in c:
                raise ValueError(f"comparison {i} lacks {k!r}")
            if not isinstance(c[k], typ) or (typ == (int, float) and isinstance(c[k], bool)):
                raise ValueError(f"comparison {i}: {k!r} has type {type(c[k]).__name__}")
        if c["theory_kind"] not in THEORY_KINDS:
            raise ValueError(f"comparison {i}: theory_kind {c['theory_kind']!r} not in {THEORY_KINDS}")
        if c["circuit_stderr"] < 0:
            raise ValueError(f"comparison {i}: negative circuit_stderr")
    prov = obj["provenance"]
    for k in ("parameters", "seeds", "ngspice_version", "deck_hashes", "wall_time_s"):
        if k not in prov:
            raise ValueError(f"provenance lacks {k!r}")
    # optional (added keys: older documents lack them): seconds from the start, or null
    for k in ("paper_wall_time_s", "beyond_wall_time_s", "critical_path_s"):
        v = prov.get(k)
        if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float))
                              or not v >= 0):
            raise ValueError(f"provenance {k!r} must be a number of seconds >= 0 or null, "
                             f"got {v!r}")
