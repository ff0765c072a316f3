"""Benchmark of the exact finite-noise theory and the SDE reference (not a test).

Prints tables of

* ``propagator`` wall time for four times at once (full curves on 2001 points), per
  propagation route (eigen / expm_multiply / hybrid / auto) and for the default grid n versus
  the halved spacing 2n, with the max difference between routes and grids (relative to peak);
* ``stationary_moments`` and ``autocorrelation`` timings;
* the SDE integrator's throughput (replica-steps per second) and its time-step bias on the
  stationary variance, measured with common random numbers (same Wiener paths at dt, 2 dt,
  4 dt).

Usage:  .venv/bin/python benchmarks/bench_exact.py [--repeat 3] [--quick]
"""
from __future__ import annotations

import argparse
import math
import time

import numpy as np

from analogue import Model
from analogue.montecarlo import simulate_sde, standard_noise
from analogue.theory import exact
from analogue.theory.exact_grid import resolved_grid

TIMES = np.array([0.1, 0.5, 1.6, 5.0])


def best_of(repeat, fn):
    best, out = math.inf, None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def bench_propagator(repeat, cases):
    print("propagator, 4 times (0.1, 0.5, 1.6, 5.0) x 2001 points")
    print(f"{'case':<34}{'n':>6}{'route':>8}{'time [s]':>10}{'ratio':>8}{'max diff/peak':>15}")
    for label, m, v0 in cases:
        v = np.linspace(min(v0, m.attractor) - 1.0, max(v0, m.attractor) + 1.0, 2001)
        g = resolved_grid(m, extra=[v0], t_min=TIMES[0])
        ref_time, ref = best_of(repeat, lambda: exact.propagator(m, v, TIMES, v0, method="expm"))
        peak = ref.max()
        print(f"{label:<34}{g.n:>6}{'expm':>8}{ref_time:>10.3f}{1.0:>8.2f}{0.0:>15.1e}")
        for route in ("eigen", "hybrid", "auto"):
            t, f = best_of(repeat, lambda: exact.propagator(m, v, TIMES, v0, method=route))
            print(f"{'':<34}{g.n:>6}{route:>8}{t:>10.3f}{t / ref_time:>8.2f}"
                  f"{np.abs(f - ref).max() / peak:>15.1e}")
        t2, f2 = best_of(1, lambda: exact.propagator(m, v, TIMES, v0, h=g.h / 2))
        t1, f1 = best_of(repeat, lambda: exact.propagator(m, v, TIMES, v0))
        print(f"{'':<34}{2 * g.n - 1:>6}{'auto/2h':>8}{t2:>10.3f}{t2 / t1:>8.2f}"
              f"{np.abs(f2 - f1).max() / peak:>15.1e}  (ratio: 2n vs n, diff: grid change)")


def bench_stationary(repeat, models):
    print("\nstationary observables")
    print(f"{'case':<34}{'moments [s]':>12}{'autocorr 200 lags [s]':>23}")
    for label, m in models:
        tm, _ = best_of(repeat, lambda: exact.stationary_moments(m))
        ta, _ = best_of(repeat, lambda: exact.autocorrelation(m, np.linspace(0, 5, 200)))
        print(f"{label:<34}{tm:>12.4f}{ta:>23.3f}")


def bench_sde(replicas, t_end, chunk=5_000):
    """Stationary start, run to t_end; the same Wiener paths at dt0, 2 dt0, 4 dt0 (coarse
    normals are sums of fine ones), in chunks of replicas to bound memory."""
    m = Model(1.0, 0.7, 0.2, 10.0)
    s = exact.stationary_moments(m)
    dt0 = 5e-4
    steps = int(round(t_end / dt0))
    print(f"\nSDE integrator, {m}, stationary start, t_end={t_end}, {replicas} replicas")
    print(f"{'scheme':<12}{'dt':>8}{'replica-steps/s':>17}{'var-var(dt0)':>14}{'mean-mean(dt0)':>16}"
          f"{'var-exact':>11}{'SE(var)':>9}")
    for scheme in ("exponential", "euler"):
        finals = {1: [], 2: [], 4: []}
        clock = {1: 0.0, 2: 0.0, 4: 0.0}
        for c, start in enumerate(range(0, replicas, chunk)):
            n = min(chunk, replicas - start)
            noise = standard_noise(1000 + c, n, steps)
            for k in (1, 2, 4):
                nz = noise.reshape(n, steps // k, k).sum(axis=2) / math.sqrt(k)
                t = time.perf_counter()
                e = simulate_sde(m, v0="stationary", t_end=t_end, replicas=n, seed=1000 + c,
                                 dt=k * dt0, sample_dt=t_end, noise=nz, scheme=scheme)
                clock[k] += time.perf_counter() - t
                finals[k].append(e.v[:, -1])
        v = {k: np.concatenate(x) for k, x in finals.items()}
        se_var = math.sqrt(np.var((v[1] - s.mean) ** 2) / replicas)
        for k in (1, 2, 4):
            rate = replicas * (steps // k) / clock[k]
            print(f"{scheme:<12}{k * dt0:>8.4f}{rate:>17.3g}{v[k].var() - v[1].var():>14.2e}"
                  f"{v[k].mean() - v[1].mean():>16.2e}{v[k].var() - s.variance:>11.2e}{se_var:>9.1e}")
    print(f"(exact stationary variance {s.variance:.5f}; weak order 1 => the bias at dt0 is about "
          "the 2 dt0 row's difference)")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="fewer cases, fewer replicas")
    args = ap.parse_args()
    cases = [("stick a=0.2 g=10 v0=2 (tail)", Model(1.0, 0.7, 0.2, 10.0), 2.0),
             ("stick a=0.2 g=10 v0=0.5", Model(1.0, 0.7, 0.2, 10.0), 0.5),
             ("slip a=1.2 g=10 v0=-1", Model(1.0, 0.7, 1.2, 10.0), -1.0)]
    if not args.quick:
        cases += [("tanh eps=0.05 a=0.2 g=10 v0=1", Model(1.0, 0.7, 0.2, 10.0, epsilon=0.05), 1.0),
                  ("stick a=0.2 g=100 v0=1 (tail)", Model(1.0, 0.7, 0.2, 100.0), 1.0)]
    bench_propagator(args.repeat, cases)
    bench_stationary(args.repeat, [("stick a=0.2 g=10", Model(1.0, 0.7, 0.2, 10.0)),
                                   ("tanh eps=0.05 g=10", Model(1.0, 0.7, 0.2, 10.0, epsilon=0.05)),
                                   ("stick a=0.3 g=1e4", Model(1.0, 0.7, 0.3, 1e4))])
    bench_sde(5_000 if args.quick else 40_000, 1.0)


if __name__ == "__main__":
    main()
