"""Theory values as table rows, for the ``analogue theory`` command (and notebooks)."""
from __future__ import annotations

import numpy as np

from ..model import Model

__all__ = ["theory_rows"]


def _need(name, value):
    if value is None:
        raise ValueError(f"quantity needs --{name.replace('_', '-')}")
    return value


def theory_rows(model: Model, quantity: str, *, v=None, t=None, v0=None, w=None, k=None,
                tau=None, kind="exact"):
    """Return ``(header, rows)`` for one theory quantity (see ``analogue theory --help``)."""
    if quantity == "stationary":
        from . import exact
        s = exact.stationary_moments(model)
        d = s.as_dict()
        return ["quantity", "value"], [[key, float(val)] for key, val in d.items()]
    if quantity == "deterministic":
        times = np.asarray(_need("t", t))
        vals = model.deterministic(_need("v0", v0), times)
        return ["t", "v"], [[float(a), float(b)] for a, b in zip(times, vals)]
    if quantity in ("action", "path"):
        from . import weak_noise
        rows = []
        for tt in _need("t", t):
            for vv in _need("v", v):
                p = weak_noise.optimal_path(model, vv, tt, _need("v0", v0))
                rows.append([tt, vv, p.kind, float(p.action), float(p.t_cross), float(p.t_a),
                             float(p.t_b), float(p.t_1), float(p.t_2)])
        return ["t", "v", "kind", "action", "t_cross", "t_a", "t_b", "t_1", "t_2"], rows
    if quantity == "boundaries":
        from . import weak_noise
        rows = []
        for tt in _need("t", t):
            b = weak_noise.boundaries(model, tt, _need("v0", v0))
            rows.append([tt, float(b["w"]), float(b["u"]), float(b["w_cr"])])
        return ["t", "w", "u", "w_cr"], rows
    if quantity == "propagator":
        grid = np.asarray(_need("v", v))
        rows = []
        for tt in _need("t", t):
            if kind == "weak-noise":
                from . import weak_noise
                f = weak_noise.propagator(model, grid, tt, _need("v0", v0))
            else:
                from . import exact
                f = exact.propagator(model, grid, tt, _need("v0", v0))
            rows += [[tt, float(a), float(b)] for a, b in zip(grid, np.ravel(f))]
        return ["t", "v", f"f_{kind}"], rows
    if quantity == "rate-function":
        ws = np.asarray(_need("w", w))
        if kind == "weak-noise":
            from . import weak_noise
            vals = weak_noise.rate_function(model, ws)
        elif kind == "limit":
            from .work_statistics import weak_noise_limit_rate_function
            vals = weak_noise_limit_rate_function(model, ws)
        else:
            from . import exact
            vals = exact.rate_function(model, ws)
        return ["w", f"I_{kind}"], [[float(a), float(b)] for a, b in zip(ws, np.ravel(vals))]
    if quantity == "fluctuation-relation":
        ws = np.asarray(_need("w", w))
        if kind == "weak-noise":
            from . import weak_noise
            vals = weak_noise.fluctuation_relation(model, ws)
        else:
            if kind == "limit":
                from .work_statistics import weak_noise_limit_rate_function as rate
            else:
                from .exact import rate_function as rate
            vals = np.asarray(rate(model, -ws)) - np.asarray(rate(model, ws))
        return ["w", f"I(-w)-I(w) [{kind}]"], [[float(a), float(b)] for a, b in zip(ws, np.ravel(vals))]
    if quantity == "scgf":
        from . import exact
        ks = np.asarray(_need("k", k))
        vals = exact.scgf(model, ks)
        return ["k", "lambda(k)"], [[float(a), float(b)] for a, b in zip(ks, np.ravel(vals))]
    if quantity == "work-pdf":
        from . import exact
        ws = np.asarray(_need("w", w))
        vals = exact.work_pdf(model, ws, _need("tau", tau))
        return ["w", "P_tau(w)"], [[float(a), float(b)] for a, b in zip(ws, np.ravel(vals))]
    raise ValueError(f"unknown quantity {quantity!r}")
