"""Timing of the exact work statistics: scgf, a 100-point rate-function curve, and work_pdf
curves of 40 w values (the report's need: ~40 w x 4 taus x 3 models).

Run: ``.venv/bin/python benchmarks/bench_work.py [--quick]``.  work_pdf limits BLAS to one
thread itself (threadpoolctl): its many 48 x 48 dense eigen-problems are 5-30x slower under
OpenBLAS threading on a loaded machine.  The last column of the work_pdf rows counts the
points that took the large-deviation fallback (far tails the mode basis cannot resolve);
the OU error column is over the other (contour) points.

Measured on the shared 2-core machine under load (other helpers' tests running), gamma = 10,
tau_m = 1, 40 w in [-1.5, 2.5]: OU tau = 1 / 2 / 5 / 10: 63 / 43 / 18 / 12 s (17 / 12 / 3 / 1
fallbacks, all at exact densities below 5.5e-7 / 2.2e-18 / 6e-91 / 3e-200); Fig. 8 tau = 2:
33 s.  Before (threaded BLAS, the old code): 50 w at tau = 4 took ~130 s and raised
RuntimeError at w = 1.4 (tau = 2).
"""
from __future__ import annotations

import sys
import time

import numpy as np

from analogue import Model
from analogue.theory import ornstein_uhlenbeck as ou
from analogue.theory import work_statistics as ws


def _timed(f, *args, **kw):
    t = time.perf_counter()
    out = f(*args, **kw)
    return out, time.perf_counter() - t


def main(quick=False):
    rows = []
    for g in (10.0,) if quick else (10.0, 100.0):
        for delta in (0.0, 1.0):
            m = Model(tau_m=1.0, delta=delta, a=0.5, gamma=g)
            k = np.linspace(-2, 2, 21) * g
            lam, t_scgf = _timed(ws.scgf, m, k)
            w = np.linspace(-1.0, 1.2, 100)
            I, t_rate = _timed(ws.rate_function, m, w)
            err = np.max(np.abs(I - ou.rate_function(m, w))) if delta == 0 else float("nan")
            rows.append((g, delta, "scgf (21 k)", t_scgf, float("nan"), ""))
            rows.append((g, delta, "rate_function (100 w)", t_rate, err, ""))
    models = [("OU a=0.5", Model(1.0, 0.0, 0.5, 10.0)), ("Fig8 a=0.5", Model(1.0, 1.0, 0.5, 10.0)),
              ("stick a=0.2", Model(1.0, 0.7, 0.2, 10.0)), ("slip a=1.2", Model(1.0, 0.7, 1.2, 10.0))]
    taus = (2.0,) if quick else (1.0, 2.0, 5.0, 10.0)
    for name, m in models[: 2 if quick else 4]:
        for tau in taus:
            wp = np.linspace(-1.5, 2.5, 40)
            with ws.recorded_fallbacks() as fallbacks:
                p, t_pdf = _timed(ws.work_pdf, m, wp, tau)
            ok = ~np.isin(wp, [x[0] for x in fallbacks])     # contour points only
            errp = (np.max(np.abs(p[ok] / ou.work_pdf(m, wp[ok], tau) - 1))
                    if m.delta == 0 and ok.any() else float("nan"))
            rows.append((m.gamma, m.delta, f"work_pdf {name} tau={tau:g} (40 w)", t_pdf, errp,
                         str(len(fallbacks))))
    print(f"{'gamma':>7} {'Delta':>5}  {'call':<36} {'seconds':>8}  {'max err vs OU':>13}  fallbacks")
    for g, d, name, t, e, fb in rows:
        print(f"{g:7g} {d:5g}  {name:<36} {t:8.2f}  {e:13.2e}  {fb}")


if __name__ == "__main__":
    main(quick="--quick" in sys.argv)
