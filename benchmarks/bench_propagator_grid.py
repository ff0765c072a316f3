"""Benchmark of the propagator's grid choice (issue 18 item 2; not a test).

For each regime, one ``exact.propagator`` call at one time on 2001 points, on

* **before**: the previous default grid (:func:`analogue.theory.exact_grid.resolved_grid` with
  the start and ``t_min``: width/40, kink length/2, diffusion length/10, Gaussian reach of the
  start), passed as ``grid=`` so that both sides use the same normalisation and route choice;
* **after**: the default grid (:func:`analogue.theory.exact_grid.propagator_grid`).

Prints nodes, CPU time (best of ``--repeat``) and the ratio after/before, and the error of each
against an independent reference (max |f - ref| / peak): the Delta = 0 Gaussian, the pure
dry-friction closed form at tau_m = 1e5, a = 0, else the default spacing / 8.  The last line
is the total CPU ratio over all rows; "report" rows are the four report-style times at once.

Usage:  .venv/bin/python benchmarks/bench_propagator_grid.py [--repeat 7]
"""
from __future__ import annotations

import argparse
import math
import time

import numpy as np
from scipy import special

from analogue import Model
from analogue.theory import exact
from analogue.theory.exact_grid import propagator_grid, resolved_grid


def ou(m, v, t, v0):
    mu = v0 * math.exp(-t / m.tau_m) + m.a * m.tau_m * (1 - math.exp(-t / m.tau_m))
    var = m.tau_m / m.gamma * (1 - math.exp(-2 * t / m.tau_m))
    return np.exp(-(v - mu) ** 2 / (2 * var)) / math.sqrt(2 * math.pi * var)


def dry(m, v, t, v0):
    d, dl = 1.0 / m.gamma, m.delta
    s = 4 * d * t
    z = (np.abs(v) + abs(v0) - dl * t) / math.sqrt(s)
    tail = np.where(z > 0, special.erfcx(np.maximum(z, 0)) * np.exp(-dl * np.abs(v) / d - z * z),
                    np.exp(-dl * np.abs(v) / d) * special.erfc(np.minimum(z, 0)))
    return (np.exp(-dl * (np.abs(v) - abs(v0)) / (2 * d) - dl * dl * t / (4 * d) - (v - v0) ** 2 / s)
            / math.sqrt(math.pi * s) + dl / (4 * d) * tail)


CASES = [  # label, model, v0, time, reference
    ("issue 18: g=200 a=-0.6, t=0.02 tau", Model(1.7, 1.3, -0.6, 200.0), 0.15, 0.034, None),
    ("issue 18: same, t=0.05 tau", Model(1.7, 1.3, -0.6, 200.0), 0.15, 0.085, None),
    ("dry tau=1e5 g=1 v0=1, t=0.3", Model(1e5, 1.0, 0.0, 1.0), 1.0, 0.3, dry),
    ("dry tau=1e5 g=1 v0=1, t=3", Model(1e5, 1.0, 0.0, 1.0), 1.0, 3.0, dry),
    ("dry tau=1e5 g=10 v0=0.5, t=0.03", Model(1e5, 1.0, 0.0, 10.0), 0.5, 0.03, dry),
    ("OU g=10 v0=2, t=0.03", Model(1.0, 0.0, 0.3, 10.0), 2.0, 0.03, ou),
    ("OU g=1000 v0=0.5, t=0.02", Model(1.0, 0.0, 0.3, 1000.0), 0.5, 0.02, ou),
    ("stick g=10 a=0.2 v0=1, t=0.1", Model(1.0, 0.7, 0.2, 10.0), 1.0, 0.1, None),
    ("slip g=10 a=1.2 v0=-1, t=0.03", Model(1.0, 0.7, 1.2, 10.0), -1.0, 0.03, None),
    ("a=Delta g=100 v0=0.5, t=0.01", Model(1.0, 0.7, 0.7, 100.0), 0.5, 0.01, None),
    ("stick g=1 a=0.2 v0=2, t=0.03", Model(1.0, 0.7, 0.2, 1.0), 2.0, 0.03, None),
    ("tau=100 D=0.05 g=10 v0=2, t=1", Model(100.0, 0.05, 0.02, 10.0), 2.0, 1.0, None),
    ("tanh eps=0.05 g=10 v0=1, t=0.1", Model(1.0, 0.7, 0.2, 10.0, epsilon=0.05), 1.0, 0.1, None),
    ("deep start: stick g=1000 v0=0.5, t=0.1", Model(1.0, 0.7, 0.3, 1000.0), 0.5, 0.1, None),
    ("report: stick g=10 v0=2, 4 times", Model(1.0, 0.7, 0.2, 10.0), 2.0, (0.1, 0.5, 1.6, 5.0), None),
    ("report: slip g=10 v0=-1, 4 times", Model(1.0, 0.7, 1.2, 10.0), -1.0, (0.1, 0.5, 1.6, 5.0), None),
]


def best(repeat, fn):
    out, dt = None, math.inf
    for _ in range(repeat):
        c = time.process_time()
        out = fn()
        dt = min(dt, time.process_time() - c)
    return dt, out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    print(f"{'case':<42}{'n before':>9}{'n after':>9}{'cpu before':>12}{'cpu after':>11}{'ratio':>7}"
          f"{'err before':>12}{'err after':>11}")
    totals = [0.0, 0.0]
    for label, m, v0, t, ref in CASES:
        times = np.atleast_1d(np.asarray(t, dtype=float))
        new = propagator_grid(m, v0, float(times.min()))
        try:
            old = resolved_grid(m, extra=(v0,), t_min=float(times.min()))
        except ValueError:
            old = None
        lo, hi = new.v[0], new.v[-1]
        v = np.union1d(np.linspace(lo, hi, 2001), [0.0, v0])
        t_new, f_new = best(args.repeat, lambda: exact.propagator(m, v, times, v0))
        if ref is None:
            r = exact.propagator(m, v, times, v0, h=new.h / 8)
        else:
            r = np.array([ref(m, v, tt, v0) for tt in times])
        peak = r.max(axis=-1)
        e_new = float((np.abs(f_new - r).max(axis=-1) / peak).max())
        if old is None:
            print(f"{label:<42}{'> 4e5':>9}{new.n:>9}{'no grid':>12}{t_new:>11.4f}{'':>7}{'':>12}{e_new:>11.1e}")
            continue
        t_old, f_old = best(args.repeat, lambda: exact.propagator(m, v, times, v0, grid=old))
        e_old = float((np.abs(f_old - r).max(axis=-1) / peak).max())
        totals[0] += t_old
        totals[1] += t_new
        print(f"{label:<42}{old.n:>9}{new.n:>9}{t_old:>12.4f}{t_new:>11.4f}{t_new / t_old:>7.2f}"
              f"{e_old:>12.1e}{e_new:>11.1e}")
    print(f"{'total (rows with a grid before)':<42}{'':>18}{totals[0]:>12.3f}{totals[1]:>11.3f}"
          f"{totals[1] / totals[0]:>7.2f}")


if __name__ == "__main__":
    main()
