"""Before/after timings of the report's exact theory (issue 10, "theory computed once").

Run: ``.venv/bin/python benchmarks/bench_theory.py [--quick] [--only=15]``.  Each row prints the time of
the old algorithm (still callable: ``mesh="uniform"``, per-w Legendre roots bracketed from
k = 0, ``work_pdf(..., share=False)``), the new one, their ratio and the largest difference.

1. Rate function on the report's grids (Fig. 8 model; the open question's a = 0.5 and 1.5 at
   gamma = 10, 100, 1000): uniform grid + per-w roots -> graded mesh ("auto") + sorted sweep.
2. Cost of one Legendre point against gamma (the open question's need): nodes per mesh and
   seconds per point; uniform grows like gamma, graded stays flat.
3. work_pdf on 30 w over +-4 sd per window tau (Fig. 8 and OU, gamma = 10; the report's
   range): per-w contours -> shared contours; for OU also the error against the closed form.
4. The theory cache: cold call, warm call (read from disk).
6. The report's exact transition propagators (stick, slip, work: every start, ideal and
   smoothed model, the histogram times): the old "auto" route (eigen-decomposition, or
   expm_multiply then eigen for starts in the tail) against the contour route (Talbot
   contour, complex tridiagonal solves), CPU seconds and the largest difference relative to
   the peak (and relative, where the density exceeds 1e-6 of the peak).
7. Stationary work variances of the report (work experiment, ideal and smoothed model, its
   four windows): Simpson on 801 lags of the spectral autocorrelation (old) against the
   closed form (Poisson solve + Talbot contour, stationary.integrated_autocorrelation).
8. The quick report's theory pieces, CPU seconds on a cold cache (cache=False): experiment_theory
   of stick, slip, work; figure_curves of work (only with ``--with-runs``: it loads the quick
   work runs from the store, or runs them); the open question's curves at the
   quick gammas (10, 100) and at gamma 1000 (what the full report adds).  Run it with the old
   checkout on PYTHONPATH too for the side-by-side.
9. The rate functions' principal eigenpairs in the Legendre sweep: LAPACK bisection (forced by
   disabling ``_top_eigenpair_shifted``) against the certified shifted inverse iteration, CPU
   seconds and the largest |dI|, on the open question's curves (quick gammas 10, 100; and
   1000) and the work experiment's 61-point curve (Fig. 8 model, gamma 10).
5. work_pdf's contour generating function: eigen-decomposition (``propagator="eig"``) vs
   batched Pade matrix exponential (``"expm"``, default) on the report's range, with the
   load average printed (2 cores shared by other jobs: times are comparable only side by side).

Differences at gamma >= 100 on the negative-w side are errors of the *old* uniform grid (its
ground-state transform zone |v| <= tau_m (Delta + |a|) holds sliding states with
gamma h |U'| ~ 0.2; benchmarks/README.md gives an example); the graded values are converged
in h (h vs h/2 within 2e-5 at gamma = 1000) and equal eq. (64) where the sliding OU state
alone carries them: see tests/unit/test_theory_fast_paths.py.
"""
from __future__ import annotations

import os
import resource
import sys
import tempfile
import time
import warnings

import numpy as np

from analogue import Model
from analogue.theory import ornstein_uhlenbeck as ou
from analogue.theory import work_statistics as ws
from analogue.theory.cache import cached_call


def _timed(f, *args, **kw):
    t = time.perf_counter()
    out = f(*args, **kw)
    return out, time.perf_counter() - t


def rate_old(model, w):
    """The pre-issue-10 algorithm: uniform grid, every root bracketed from k = 0."""
    h = ws.tilted_grid_spacing(model)
    mean = float(ws._scgf_pair(model, 0.0, h, mesh="uniform")[1])
    out = []
    for wi in np.ravel(w):
        k, lam = ws._legendre_root(model, float(wi), h, mean, "uniform")
        out.append(max(k * wi - lam, 0.0) / model.gamma)
    return np.array(out)


def bench_rate(quick):
    print("\n1. rate function (old: uniform grid, per-w roots; new: auto mesh, sorted sweep)")
    print(f"{'case':<28} {'points':>6} {'old [s]':>8} {'new [s]':>8} {'old/new':>8} {'max |dI|':>9}")
    cases = [("Fig. 8, gamma 10", Model(1.0, 1.0, 0.5, 10.0), np.linspace(-2, 2, 61))]
    for a, half in ((0.5, 1.2), (1.5, 2.0)):
        for g, n in ((10.0, 41), (100.0, 21), (1000.0, 9)):
            if quick and g == 1000.0:
                continue
            cases.append((f"open q. a={a:g}, gamma {g:g}", Model(1.0, 1.0, a, g),
                          np.linspace(-half, half, n)))
    for name, m, w in cases:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            old, t_old = _timed(rate_old, m, w)
        new, t_new = _timed(ws.rate_function, m, w)
        print(f"{name:<28} {w.size:6d} {t_old:8.2f} {t_new:8.2f} {t_old / t_new:8.1f} "
              f"{np.max(np.abs(old - new)):9.1e}")


def bench_gamma(quick):
    print("\n2. one Legendre point (w = -0.3, a = 0.5) against gamma")
    print(f"{'gamma':>7} {'uniform n':>10} {'graded n':>9} {'uniform [s]':>12} {'graded [s]':>11}")
    for g in (10.0, 100.0, 1000.0) if quick else (10.0, 30.0, 100.0, 300.0, 1000.0, 3000.0):
        m = Model(1.0, 1.0, 0.5, g)
        h = ws.tilted_grid_spacing(m)
        n_u = ws._grid_for(m, 0.0, h).n
        n_g = ws._graded_nodes(m, 0.0, h).size
        t_u = float("nan")
        if n_u < 100_000:
            _, t_u = _timed(ws.rate_function, m, [-0.3], mesh="uniform")
        _, t_g = _timed(ws.rate_function, m, [-0.3], mesh="graded")
        print(f"{g:7g} {n_u:10d} {n_g:9d} {t_u:12.2f} {t_g:11.2f}")


def bench_pdf(quick):
    print("\n3. work_pdf, 30 w over +-4 sd per tau (old: one contour per w; new: shared contours)")
    print(f"{'case':<18} {'old [s]':>8} {'new [s]':>8} {'old/new':>8} {'max rel diff':>12} "
          f"{'err vs OU old/new':>18}")
    taus = (2.0,) if quick else (1.0, 2.0, 5.0, 10.0)
    for name, m in (("Fig. 8", Model(1.0, 1.0, 0.5, 10.0)), ("OU", Model(1.0, 0.0, 0.5, 10.0))):
        centre = float(ws.scgf_derivative(m, 0.0))
        for tau in taus:
            # the report's range: bins where the circuit has data, about +-4 sd of w
            sd = float(np.sqrt(ws.work_variance(m, [tau])[0]))
            w = np.linspace(centre - 4 * sd, centre + 4 * sd, 30)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                with ws.recorded_fallbacks() as fallbacks:
                    old, t_old = _timed(ws.work_pdf, m, w, tau, share=False)
                fb = {x[0] for x in fallbacks}
                new, t_new = _timed(ws.work_pdf, m, w, tau)
            ok = ~np.isin(w, list(fb))      # compare contour points (fallbacks are O(1) in ln p)
            diff = np.max(np.abs(new[ok] / old[ok] - 1))
            err = ""
            if m.delta == 0:
                ex = ou.work_pdf(m, w[ok], tau)
                err = f"{np.max(np.abs(old[ok] / ex - 1)):.1e}/{np.max(np.abs(new[ok] / ex - 1)):.1e}"
            print(f"{name + f' tau={tau:g}':<18} {t_old:8.1f} {t_new:8.1f} {t_old / t_new:8.1f} "
                  f"{diff:12.1e} {err:>18}")


def bench_cache():
    print("\n4. theory cache (open question curve a = 0.5, gamma = 100, 21 points)")
    m = Model(1.0, 1.0, 0.5, 100.0)
    w = np.linspace(-1.2, 1.2, 21)
    with tempfile.TemporaryDirectory() as d:
        _, cold = _timed(cached_call, ws.rate_function_curve, m, w, cache=d)
        _, warm = _timed(cached_call, ws.rate_function_curve, m, w, cache=d)
    print(f"cold {cold:.2f} s, warm {warm * 1e3:.1f} ms")


def bench_propagator(quick):
    print("\n5. work_pdf, 30 w over +-4 sd: contour G by eig + solve vs batched expm")
    print(f"{'case':<18} {'eig [s]':>8} {'expm [s]':>8} {'eig/expm':>8} {'max rel diff':>12} "
          f"{'err vs OU eig/expm':>18} {'load':>5}")
    taus = (1.0,) if quick else (1.0, 2.0, 5.0, 10.0)
    for name, m in (("Fig. 8", Model(1.0, 1.0, 0.5, 10.0)), ("OU", Model(1.0, 0.0, 0.5, 10.0))):
        centre = float(ws.scgf_derivative(m, 0.0))
        for tau in taus:
            sd = float(np.sqrt(ws.work_variance(m, [tau])[0]))
            w = np.linspace(centre - 4 * sd, centre + 4 * sd, 30)
            load = os.getloadavg()[0]
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                old, t_old = _timed(ws.work_pdf, m, w, tau, propagator="eig")
                new, t_new = _timed(ws.work_pdf, m, w, tau)
            err = ""
            if m.delta == 0:
                ex = ou.work_pdf(m, w, tau)
                err = f"{np.max(np.abs(old / ex - 1)):.1e}/{np.max(np.abs(new / ex - 1)):.1e}"
            print(f"{name + f' tau={tau:g}':<18} {t_old:8.1f} {t_new:8.1f} {t_old / t_new:8.1f} "
                  f"{np.max(np.abs(new / old - 1)):12.1e} {err:>18} {load:5.1f}")


def bench_transition(quick):
    from analogue.circuit.experiments import load_experiment
    from analogue.theory.exact_grid import resolved_grid
    from analogue.theory.fokker_planck import symmetric_generator
    from analogue.theory.propagation import (EIGEN_MAX_HALF_LOG_RANGE, amplification,
                                             contour_nodes, initial_delta, propagate)
    print("\n6. transition propagators of the report (old: eigen / hybrid; new: contour), CPU s")
    print(f"{'case':<30} {'n':>5} {'amp':>5} {'N':>3} {'old [s]':>8} {'new [s]':>8} "
          f"{'max|d|/peak':>11} {'rel >1e-6':>9} {'load':>5}")
    tot_old = tot_new = 0.0
    for name in ("stick", "slip", "work"):
        exp = load_experiment(name)
        eff = exp.mapping().model_effective
        h = eff.epsilon / 2 if eff.epsilon > 0 else None
        times = np.asarray(exp.histogram_times, dtype=float)
        for model in (exp.model, eff):
            for v0 in exp.v0:
                grid = resolved_grid(model, extra=(v0,), h=h, t_min=float(times.min()))
                p0 = initial_delta(grid, v0)
                amp = amplification(symmetric_generator(model, grid)[2], p0)
                old_method = "eigen" if amp <= EIGEN_MAX_HALF_LOG_RANGE else "hybrid"
                c0 = time.process_time()
                old = propagate(model, grid, p0, times, method=old_method)
                c1 = time.process_time()
                new = propagate(model, grid, p0, times)
                c2 = time.process_time()
                tot_old += c1 - c0
                tot_new += c2 - c1
                peak = old.max(axis=1, keepdims=True)
                big = old > 1e-6 * peak
                print(f"{name + f' eps={model.epsilon:.3g} v0={v0:g}':<30} {grid.n:5d} {amp:5.1f} "
                      f"{contour_nodes(amp):3d} {c1 - c0:8.2f} {c2 - c1:8.3f} "
                      f"{np.max(np.abs(new - old) / peak):11.1e} "
                      f"{np.max(np.abs(new[big] / old[big] - 1)):9.1e} {os.getloadavg()[0]:5.1f}")
    print(f"{'total':<30} {'':>5} {'':>5} {'':>3} {tot_old:8.2f} {tot_new:8.3f}")


def bench_work_variance(quick):
    from analogue.circuit.experiments import load_experiment
    print("\n7. work_variance of the work experiment (old: Simpson, 801 lags; new: closed form)")
    print(f"{'model':<22} {'old [s]':>8} {'new [s]':>8} {'max rel diff':>12} {'old n=12801 vs new':>18}")
    exp = load_experiment("work")
    taus = np.asarray(exp.work_taus, dtype=float)
    eff = exp.mapping().model_effective
    h = eff.epsilon / 2 if eff.epsilon > 0 else None      # the report's common spacing
    for model in (exp.model, eff):
        c0 = time.process_time()
        old = ws.work_variance(model, taus, n=801, h=h)
        c1 = time.process_time()
        new = ws.work_variance(model, taus, h=h)
        c2 = time.process_time()
        fine = ("" if quick else
                f"{np.max(np.abs(ws.work_variance(model, taus, n=12801, h=h) / new - 1)):.1e}")
        print(f"{f'epsilon={model.epsilon:.3g}':<22} {c1 - c0:8.2f} {c2 - c1:8.3f} "
              f"{np.max(np.abs(new / old - 1)):12.1e} {fine:>18}")


def cpu() -> float:
    """CPU seconds of this process (user + sys)."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def bench_report_pieces(quick):
    from analogue.circuit.experiments import load_experiment
    from analogue.plots.open_question import CASES, open_question_data
    from analogue.report.plan import RunOptions
    from analogue.study.runs import run_experiment_runs
    from analogue.study.theory_curves import experiment_theory, figure_curves

    print("\n8. the quick report's theory pieces, CPU s, cold cache")
    opts = RunOptions(quick=True, workers=1, progress=False)
    res = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name in ("stick", "slip", "work"):
            exp = load_experiment(name)
            c = cpu()
            experiment_theory(exp, exp.report.for_options(opts), cache=False)
            res[f"exact theory {name}"] = cpu() - c
        if "--with-runs" in sys.argv:     # loads (or runs, ~5 min) the quick work runs
            runs = run_experiment_runs(load_experiment("work"), opts)
            c = cpu()
            figure_curves(runs, cache=False)
            res["theory curves work"] = cpu() - c
        for gammas, label in (((10.0, 100.0), "open question quick"),
                              ((1000.0,), "open question gamma 1000 (full adds)")):
            c = cpu()
            for a, half in CASES:
                open_question_data(a, half, gammas=gammas, cache=False)
            res[label] = cpu() - c
    for k, v in res.items():
        print(f"{k:<40} {v:7.2f}")
    print(f"{'total (quick)':<40} {sum(v for k, v in res.items() if 'full' not in k):7.2f}"
          f"  load {os.getloadavg()[0]:.1f}")


def bench_eigenpairs(quick):
    from unittest import mock
    from analogue.plots.open_question import CASES, open_question_data

    def curves(gammas):
        out = {}
        for a, half in CASES:
            for g, (_, rate) in open_question_data(a, half, gammas=gammas, cache=False).items():
                out[(a, g)] = rate
        return out

    print("\n9. principal eigenpairs of the sweeps: LAPACK vs shifted inverse iteration, CPU s")
    print(f"{'case':<36} {'LAPACK [s]':>10} {'shifted [s]':>11} {'ratio':>6} {'max |dI|':>9} {'load':>5}")
    fig8 = Model(1.0, 1.0, 0.5, 10.0)
    cases = [("open question, gamma 10 and 100", lambda: curves((10.0, 100.0))),
             ("Fig. 8 curve, 61 points, gamma 10",
              lambda: {0: ws.rate_function_curve(fig8, np.linspace(-2, 2, 61))[1]})]
    if not quick:
        cases.append(("open question, gamma 1000", lambda: curves((1000.0,))))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name, run in cases:
            c = cpu()
            with mock.patch.object(ws, "_top_eigenpair_shifted", lambda d, e, g: None):
                old = run()
            c1 = cpu()
            new = run()
            c2 = cpu()
            diff = max(float(np.max(np.abs(old[k] - new[k]))) for k in old)
            print(f"{name:<36} {c1 - c:10.2f} {c2 - c1:11.2f} {(c1 - c) / (c2 - c1):6.1f} "
                  f"{diff:9.1e} {os.getloadavg()[0]:5.1f}")


def main(quick=False, only=None):
    sections = {"1": bench_rate, "2": bench_gamma, "3": bench_pdf, "4": lambda q: bench_cache(),
                "5": bench_propagator, "6": bench_transition, "7": bench_work_variance,
                "8": bench_report_pieces, "9": bench_eigenpairs}
    for key, run in sections.items():
        if only is None or key in only:
            run(quick)


if __name__ == "__main__":
    # --only=5 (or --only=35, ...) runs the listed sections
    only = next((a.split("=", 1)[1] for a in sys.argv if a.startswith("--only=")), None)
    main(quick="--quick" in sys.argv, only=only)
