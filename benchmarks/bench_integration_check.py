"""The integration check's estimator for indicator observables, flips against the smoothed
indicator (issue 10; :mod:`analogue.estimators.smoothed_indicator`), side by side on the same
paths (not a test).

Runs ``R`` stationary replicas of a paper experiment's circuit (``circuits/<name>.toml``) for
``T`` model time units at a nominal tolerance and again 100x tighter with a quarter of the step
on the same noise (the report's check, ``Experiment.check_spec``), then prints for each
indicator observable the per-path difference ``d`` (nominal - check) in units of the
observable's spread over paths: its mean +- SE and its spread, counting flips (h = 0) and
smoothed at the report's ``h`` and at h/2, h/4, 2h; and the check paths a report needs so that
the check's own noise (2 SE) stays below 0.05 statistical errors of a run of ``--run``
replicas (``n_c >= (2 / 0.05)^2 sd(d)^2 n_run``), with each estimator.  The CPU seconds of
both runs (ngspice children, user + sys) are printed with the load average.

    PYTHONPATH=. .venv/bin/python benchmarks/bench_integration_check.py work \\
        --replicas 32 --t-end 50 --reltol 3e-5 --seeds 7 8
"""
from __future__ import annotations

import argparse
import math
import os
import resource

import numpy as np

from analogue.circuit.experiments import load_experiment, standard_circuit
from analogue.circuit.simulate import simulate
from analogue.estimators.smoothed_indicator import kernel_width, window
from analogue.theory.exact import sample_stationary


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("experiment", nargs="?", default="work")
    ap.add_argument("--replicas", type=int, default=32)
    ap.add_argument("--t-end", type=float, default=50.0)
    ap.add_argument("--burn-in", type=float, default=2.0)
    ap.add_argument("--reltol", type=float, default=3e-5)
    ap.add_argument("--method", default="trap")
    ap.add_argument("--seeds", type=int, nargs="+", default=[7])
    ap.add_argument("--run", type=int, default=256, help="replicas of the run to size the check for")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()

    exp = load_experiment(standard_circuit(args.experiment))
    mapping = exp.mapping()
    eff = mapping.model_effective
    thr = exp.report.stick_threshold * exp.model.velocity_scale
    h = kernel_width(thr, eff.epsilon)
    nominal = exp.spec.replace(reltol=args.reltol, method=args.method, trtol=7.0)
    check = exp.check_spec(nominal)
    v0 = np.asarray(sample_stationary(eff, args.replicas, 3), dtype=float)
    kw = dict(v0=v0, t_end=args.t_end, replicas=args.replicas, replicas_per_deck=4,
              sample_dt=exp.sample_dt, store=False, workers=args.workers, progress=False)
    windows = {"stick fraction": (-thr, thr), "P(v>0)": (0.0, math.inf)}
    print(f"{args.experiment}: {args.replicas} replicas x {args.t_end:g} (burn-in "
          f"{args.burn_in:g}), nominal {args.method} reltol {args.reltol:g} against the check "
          f"(reltol {check.reltol:g} {check.method}, max step / 4); threshold {thr:.4g}, "
          f"epsilon {eff.epsilon:.4g}, h = {h:.4g}")
    for seed in args.seeds:
        load0 = os.getloadavg()[0]
        c0 = _cpu()
        nom = simulate(exp.model, seed=seed, circuit=nominal, **kw)
        c1 = _cpu()
        chk = simulate(exp.model, seed=seed, circuit=check, **kw)
        c2 = _cpu()
        i0 = int(np.searchsorted(nom.t, nom.t[0] + args.burn_in - 1e-12))
        vn, vc = nom.v[:, i0:], chk.v[:, i0:]
        print(f"\nseed {seed}: CPU nominal {c1 - c0:.1f} s, check {c2 - c1:.1f} s "
              f"(x{(c2 - c1) / max(c1 - c0, 1e-9):.1f}); load {load0:.1f}")
        print("| observable | h | mean d / s | SE / s | sd(d) / s | check paths for 2 SE < 0.05 SE_run |")
        print("|---|---|---|---|---|---|")
        for name, (lo, hi) in windows.items():
            s = float(np.std(window(vc, lo, hi).mean(axis=1)))
            for hh in (0.0, 2 * h, h, h / 2, h / 4):
                d = window(vn, lo, hi, hh).mean(axis=1) - window(vc, lo, hi, hh).mean(axis=1)
                sd = float(d.std(ddof=1)) / s
                need = math.ceil((2 / 0.05) ** 2 * sd ** 2 * args.run)
                print(f"| {name} | {hh:.4g} | {d.mean() / s:+.4f} | {sd / math.sqrt(d.size):.4f} "
                      f"| {sd:.4f} | {need} |")


if __name__ == "__main__":
    main()
