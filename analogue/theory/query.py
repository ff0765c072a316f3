"""Theory values as tables, for the ``analogue theory`` command (and notebooks).

:data:`QUANTITIES` (from :mod:`analogue.theory.quantities`) is the catalogue: for each quantity
the options it uses, the theories (``kind``) it offers and what it returns.
:func:`theory_table` refuses options a quantity does not use and kinds it does not offer, so an
answer is never silently something else than what was asked.  Values that do not exist (a
boundary in the slip regime, a crossing time of a path that does not cross) are NaN in
:attr:`TheoryTable.rows` with a reason in :meth:`TheoryTable.reason`;
:meth:`TheoryTable.as_json` turns them into ``null`` (strict JSON).
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .. import checks
from ..model import Model
from . import exact, weak_noise
from .exact import rate_function as _exact_rate_function
from .quantities import KINDS, OPTION_NAMES, QUANTITIES, Quantity
from .work_statistics import weak_noise_limit_rate_function as _limit_rate_function

__all__ = [
    "KINDS",
    "QUANTITIES",
    "Quantity",
    "TheoryTable",
    "theory_rows",
    "theory_table",
    "weak_noise_density",
]

@dataclass(frozen=True)
class TheoryTable:
    """The answer to one query: column names, rows (floats may be NaN: see :meth:`reason`)."""

    quantity: str
    kind: str | None
    header: list[str]
    rows: list[list[Any]]
    # column -> why it can be NaN (a text, or a function of the value giving one)
    reasons: dict[str, str | Callable[[float], str]] = field(default_factory=dict)

    def reason(self, column: str, value: object) -> str | None:
        """Why ``value`` in ``column`` is missing (None when it is a finite number or text)."""
        if not isinstance(value, float) or math.isfinite(value):
            return None
        if column in self.reasons:
            r = self.reasons[column]
            return r(value) if callable(r) else r
        return "infinite" if math.isinf(value) else "undefined (not a number)"

    def as_json(self, model: Model) -> dict[str, Any]:
        """Strict JSON data: every non-finite value becomes null, with its reason in the row's
        ``"null_reasons"``."""
        out = []
        for row in self.rows:
            rec: dict[str, Any] = {}
            why: dict[str, str | None] = {}
            for col, val in zip(self.header, row):
                if isinstance(val, float) and not math.isfinite(val):
                    rec[col] = None
                    why[col] = self.reason(col, val)
                else:
                    rec[col] = val
            if why:
                rec["null_reasons"] = why
            out.append(rec)
        # gamma = inf (pure shot noise) is a valid model value: null, with its reason
        params = model.as_dict()
        bad = {k for k, v in params.items() if isinstance(v, float) and not math.isfinite(v)}
        data: dict[str, Any] = {"model": {k: None if k in bad else v for k, v in params.items()}}
        if bad:
            data["model_null_reasons"] = {k: "infinite" if math.isinf(params[k]) else "not a number"
                                          for k in sorted(bad)}
        return {**data, "quantity": self.quantity, "kind": self.kind,
                "columns": list(self.header), "rows": out}

    def as_text(self) -> str:
        """Aligned columns (numbers right-aligned, text left-aligned); missing values are
        ``n/a`` with the reasons listed under the table."""
        cells: list[list[str]] = []
        notes: dict[str, None] = {}
        for row in self.rows:
            line = []
            for col, val in zip(self.header, row):
                why = self.reason(col, val)
                if why is not None:
                    notes.setdefault(f"{col}: {why}", None)
                    line.append("n/a")
                elif isinstance(val, float):
                    line.append(f"{val:.6g}")
                else:
                    line.append(str(val))
            cells.append(line)
        text_cols = {j for j in range(len(self.header))
                     if any(isinstance(r[j], str) for r in self.rows)}
        widths = [max([len(str(h))] + [len(c[j]) for c in cells])
                  for j, h in enumerate(self.header)]

        def fmt(items: list[str]) -> str:
            return "  ".join(s.ljust(wd) if j in text_cols else s.rjust(wd)
                             for j, (s, wd) in enumerate(zip(items, widths))).rstrip()

        lines = [fmt([str(h) for h in self.header])] + [fmt(c) for c in cells]
        lines += [f"n/a  {n}" for n in notes]
        return "\n".join(lines)


# ------------------------------------------------------------------------- validation
def _check(q: Quantity, kind: str | None, given: dict[str, object]) -> str | None:
    if kind is None:
        kind = q.default_kind()
    elif not q.kinds:
        raise ValueError(f"--kind: {q.name} has no choice of theory (it is {q.summary}); "
                         f"drop --kind")
    elif kind not in q.kinds:
        raise ValueError(f"--kind must be one of {', '.join(q.kinds)} for {q.name}, got {kind!r}")
    unused = [k for k, v in given.items() if v is not None and k not in q.options + q.optional]
    if unused:
        uses = ", ".join(OPTION_NAMES[o] for o in q.options + q.optional) or "no options"
        raise ValueError(f"{', '.join(OPTION_NAMES[u] for u in unused)}: not used by "
                         f"{q.name} (it uses {uses})")
    missing = [o for o in q.options if given.get(o) is None]
    if missing:
        raise ValueError(f"{q.name} needs {', '.join(OPTION_NAMES[m] for m in missing)}")
    return kind


def _floats(name: str, values: object) -> np.ndarray:
    arr = np.atleast_1d(np.asarray(values, dtype=float))
    if arr.ndim != 1 or arr.size == 0 or not np.all(np.isfinite(arr)):
        raise ValueError(f"{OPTION_NAMES[name]} must be one or more finite numbers")
    return arr


# ----------------------------------------------------------------------- weak noise
def weak_noise_density(model: Model, v: ArrayLike, t: float, v0: float) -> np.ndarray:
    """The paper's saddle-point propagator ``exp(-gamma A(v, t | v0))`` (eq. (12)) at any
    velocities ``v`` (one is enough), normalised on an internal grid wide enough that the
    density at its edges is below 1e-12 of its peak (:func:`weak_noise.propagator` normalises
    on the grid it is given, which must then cover the distribution)."""
    v = _floats("v", v)
    centre = float(model.deterministic(v0, t))
    half = 10.0 * model.velocity_scale
    for _ in range(12):
        grid = np.unique(np.concatenate([np.linspace(centre - half, centre + half, 4001),
                                         [0.0, v0]]))
        grid = grid[(grid >= centre - half) & (grid <= centre + half)]
        A = np.asarray(weak_noise.action(model, grid, t, v0), dtype=float)
        a_min = float(np.min(A))
        f = np.exp(-model.gamma * (A - a_min))
        if f[0] < 1e-12 and f[-1] < 1e-12:
            break
        half *= 2.0
    else:
        raise RuntimeError("weak-noise propagator: could not bracket the distribution")
    z = float(np.trapezoid(f, grid))
    A_v = np.asarray(weak_noise.action(model, v, t, v0), dtype=float)
    return np.exp(-model.gamma * (A_v - a_min)) / z


# ------------------------------------------------------------------------------ query
def _boundary_reasons(model: Model, v0: float) -> dict[str, str | Callable[[float], str]]:
    if abs(model.a) > model.delta:
        stick = (f"does not exist for |a| > Delta (slip regime: a = {model.a:g}, "
                 f"Delta = {model.delta:g}); the object never sticks")
        cr = ("does not exist: v0 is on the side of the attractor v_ss (eq. (14)), so no "
              "path crosses twice")
        return {"w": stick, "u": stick, "w_cr": cr}
    before = ("not yet: t is before t_a (eq. (31)), the time the noise-free motion from v0 "
              "needs to stick, so there are no indirect paths")
    return {"w": before, "u": before,
            "w_cr": "exists only for |a| > Delta (slip regime) with v0 opposite the attractor"}


def _path_reasons() -> dict[str, str | Callable[[float], str]]:
    return {"t_cross": "this kind of path does not cross v = 0 once",
            "t_a": "this kind of path does not stick", "t_b": "this kind of path does not stick",
            "t_1": "this kind of path does not cross twice",
            "t_2": "this kind of path does not cross twice"}


def theory_table(model: Model, quantity: str, *, v: ArrayLike | None = None,
                 t: ArrayLike | None = None, v0: float | None = None, w: ArrayLike | None = None,
                 k: ArrayLike | None = None, tau: ArrayLike | None = None,
                 points: int | None = None, kind: str | None = None) -> TheoryTable:
    """Answer one query (see :data:`QUANTITIES`); ``None`` means "not given"."""
    checks.instance("model", model, Model, description="an analogue.Model")
    if quantity not in QUANTITIES:
        raise ValueError(f"quantity must be one of {', '.join(QUANTITIES)}, got {quantity!r}")
    q = QUANTITIES[quantity]
    given: dict[str, object] = {"v": v, "t": t, "v0": v0, "w": w, "k": k, "tau": tau,
                                "points": points}
    kind = _check(q, kind, given)
    start = math.nan if v0 is None else v0  # _check refused a missing v0 where it is needed

    def table(header: list[str], rows: list[list[Any]],
              reasons: dict[str, str | Callable[[float], str]] | None = None) -> TheoryTable:
        return TheoryTable(quantity, kind, header, rows, reasons or {})

    if quantity == "stationary":
        d = exact.stationary_moments(model).as_dict()
        return table(["quantity", "value"], [[key, float(val)] for key, val in d.items()])
    if quantity == "deterministic":
        times = _floats("t", t)
        vals = np.atleast_1d(model.deterministic(start, times))
        return table(["t", "v"], [[float(a), float(b)] for a, b in zip(times, vals)])
    if quantity in ("action", "path"):
        n = 50 if points is None else points
        # bounded: --points 100000000 ran past a minute (killed) instead of answering
        if quantity == "path":
            n = checks.integer("--points", n, minimum=2, maximum=100_000)
        rows = []
        for tt in _floats("t", t):
            for vv in _floats("v", v):
                p = weak_noise.optimal_path(model, vv, tt, start, n=n if quantity == "path" else 2)
                if quantity == "path":
                    rows += [[float(tt), float(vv), p.kind, float(s), float(x)]
                             for s, x in zip(p.s, p.v)]
                else:
                    rows.append([float(tt), float(vv), p.kind, float(p.action), float(p.t_cross),
                                 float(p.t_a), float(p.t_b), float(p.t_1), float(p.t_2)])
        if quantity == "path":
            return table(["t", "v", "kind", "s", "v*(s)"], rows)
        return table(["t", "v", "kind", "action", "t_cross", "t_a", "t_b", "t_1", "t_2"], rows,
                     _path_reasons())
    if quantity == "boundaries":
        rows = []
        for tt in _floats("t", t):
            b = weak_noise.boundaries(model, tt, start)
            rows.append([float(tt), float(b["w"]), float(b["u"]), float(b["w_cr"])])
        return table(["t", "w", "u", "w_cr"], rows, _boundary_reasons(model, start))
    if quantity == "propagator":
        grid = _floats("v", v)
        rows = []
        for tt in _floats("t", t):
            if kind == "weak-noise":
                f = weak_noise_density(model, grid, tt, start)
            else:
                f = exact.propagator(model, grid, tt, start)
            rows += [[float(tt), float(a), float(b)] for a, b in zip(grid, np.ravel(f))]
        return table(["t", "v", f"f_{kind}"], rows)
    if quantity in ("rate-function", "fluctuation-relation"):
        ws = _floats("w", w)
        if kind == "weak-noise":
            rate = weak_noise.rate_function
        elif kind == "limit":
            rate = _limit_rate_function
        else:
            rate = _exact_rate_function
        if quantity == "rate-function":
            vals = np.ravel(rate(model, ws))
            return table(["w", f"I_{kind}"], [[float(a), float(b)] for a, b in zip(ws, vals)],
                         {f"I_{kind}": lambda x: "infinite: this work rate cannot be reached"
                          if math.isinf(x) or kind != "exact" else "not resolved: w at or "
                          "beyond the edge of the work's support (the Legendre maximiser runs "
                          "to |k| -> inf)"})
        if kind == "weak-noise":
            vals = np.ravel(weak_noise.fluctuation_relation(model, ws))
        else:
            vals = np.ravel(np.asarray(rate(model, -ws)) - np.asarray(rate(model, ws)))
        return table(["w", f"I(-w)-I(w) [{kind}]"],
                     [[float(a), float(b)] for a, b in zip(ws, vals)])
    if quantity == "scgf":
        ks = _floats("k", k)
        vals = np.ravel(exact.scgf(model, ks))
        return table(["k", "lambda(k)"], [[float(a), float(b)] for a, b in zip(ks, vals)])
    # work-pdf
    ws = _floats("w", w)
    tau = checks.positive("--tau", tau)
    vals = np.ravel(exact.work_pdf(model, ws, tau))
    return table(["w", "P_tau(w)"], [[float(a), float(b)] for a, b in zip(ws, vals)])


def theory_rows(model: Model, quantity: str, *, v: ArrayLike | None = None,
                t: ArrayLike | None = None, v0: float | None = None, w: ArrayLike | None = None,
                k: ArrayLike | None = None, tau: ArrayLike | None = None,
                kind: str | None = None) -> tuple[list[str], list[list[Any]]]:
    """``(header, rows)`` of :func:`theory_table` (kept for callers of the first version)."""
    tab = theory_table(model, quantity, v=v, t=t, v0=v0, w=w, k=k, tau=tau, kind=kind)
    return tab.header, tab.rows
