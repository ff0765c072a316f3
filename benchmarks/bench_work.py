"""Timing of the exact work statistics: scgf, a 100-point rate-function curve, 50 work_pdf points.

Run: ``.venv/bin/python benchmarks/bench_work.py`` (set OPENBLAS_NUM_THREADS=1 on a shared
machine: the small dense eigen-problems of work_pdf are slower with threaded BLAS under load).
"""
from __future__ import annotations

import time

import numpy as np

from analogue import Model
from analogue.theory import ornstein_uhlenbeck as ou
from analogue.theory import work_statistics as ws


def _timed(f, *args, **kw):
    t = time.perf_counter()
    out = f(*args, **kw)
    return out, time.perf_counter() - t


def main(gammas=(10.0, 100.0)):
    rows = []
    for g in gammas:
        for delta in (0.0, 1.0):
            m = Model(tau_m=1.0, delta=delta, a=0.5, gamma=g)
            k = np.linspace(-2, 2, 21) * g
            lam, t_scgf = _timed(ws.scgf, m, k)
            w = np.linspace(-1.0, 1.2, 100)
            I, t_rate = _timed(ws.rate_function, m, w)
            err = np.max(np.abs(I - ou.rate_function(m, w))) if delta == 0 else float("nan")
            rows.append((g, delta, "scgf (21 k)", t_scgf, float("nan")))
            rows.append((g, delta, "rate_function (100 w)", t_rate, err))
            if g <= 10:
                mean = ws.work_rate_mean(m)
                wp = np.linspace(mean - 0.6, mean + 0.9, 50)
                p, t_pdf = _timed(ws.work_pdf, m, wp, 4.0)
                errp = np.max(np.abs(p / ou.work_pdf(m, wp, 4.0) - 1)) if delta == 0 else float("nan")
                rows.append((g, delta, "work_pdf (50 w, tau=4)", t_pdf, errp))
    print(f"{'gamma':>7} {'Delta':>5}  {'call':<24} {'seconds':>8}  {'max err vs OU':>13}")
    for g, d, name, t, e in rows:
        print(f"{g:7g} {d:5g}  {name:<24} {t:8.2f}  {e:13.2e}")


if __name__ == "__main__":
    main()
