"""Timings of the family's exact numerics (analogue.theory.family) and Monte Carlo.

For the committed extension experiments (circuits/cubic.toml, shot.toml, stribeck.toml) at
epsilon = 0 and at the circuits' smoothing epsilon = 0.01: stationary moments, the propagator
at three times on 601 points, the rate function at two w, and the Monte Carlo replica rate.

    PYTHONPATH=. .venv/bin/python benchmarks/bench_family_theory.py
"""
import math
import time

import numpy as np

from analogue import Model, ShotNoise
from analogue.montecarlo import simulate_sde
from analogue.theory import exact

MODELS = {
    "cubic": Model(1.0, 0.5, 1.5, 10.0, cubic=1.0),
    "shot": Model(1.0, 0.5, 0.2, math.inf, shot=ShotNoise(1.0, 0.5)),
    "stribeck": Model(2.0, 0.3, 0.7, 10.0, stribeck=(1.0, 0.2)),
    "stribeck eps=0.01": Model(2.0, 0.3, 0.7, 10.0, stribeck=(1.0, 0.2), epsilon=0.01),
    "shot eps=0.01": Model(1.0, 0.5, 0.2, math.inf, shot=ShotNoise(1.0, 0.5), epsilon=0.01),
}


def main():
    print("| member | moments [s] | propagator [s] | rate function [s] | MC replica-time/s |")
    print("|---|---|---|---|---|")
    for name, m in MODELS.items():
        t0 = time.perf_counter()
        s = exact.stationary_moments(m)
        t1 = time.perf_counter()
        exact.propagator(m, np.linspace(-2, 4, 601), [0.5, 1.0, 3.0], 0.5)
        t2 = time.perf_counter()
        mw = m.force * s.mean
        exact.rate_function(m, [0.5 * mw, 1.5 * mw])
        t3 = time.perf_counter()
        simulate_sde(m, v0=0.0, t_end=10.0, replicas=100, seed=1, sample_dt=0.5)
        t4 = time.perf_counter()
        print(f"| {name} | {t1 - t0:.2f} | {t2 - t1:.2f} | {t3 - t2:.2f} | {1000.0 / (t4 - t3):.0f} |")


if __name__ == "__main__":
    main()
