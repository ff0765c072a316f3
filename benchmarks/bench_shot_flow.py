"""Event-driven pure-shot Monte Carlo between kicks: RK4 substeps against the tabulated flow
(analogue.theory.flow_table), side by side with the same kicks (the kick stream does not
depend on the flow), for the committed Stribeck and cubic members with shot noise.

Prints CPU seconds (user + sys of this process), wall seconds, the load average, and the
largest difference of the two routes' velocities and positions.

    PYTHONPATH=. .venv/bin/python benchmarks/bench_shot_flow.py [replicas ...]
"""
import math
import os
import resource
import sys
import time

import numpy as np

from analogue import Model, ShotNoise
from analogue.montecarlo import _event_driven, default_dt

MODELS = {
    "stribeck+shot": Model(2.0, 0.3, 0.7, math.inf, stribeck=(1.0, 0.2), shot=ShotNoise(1.0, 0.5)),
    "cubic+shot": Model(1.0, 0.5, 1.5, math.inf, cubic=1.0, shot=ShotNoise(1.0, 0.5)),
}


def _cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def main(replica_counts=(200, 2000)):
    print("| member | replicas | RK4 cpu [s] | table cpu [s] | RK4 wall | table wall | load | "
          "max dv | max dx |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, m in MODELS.items():
        dt = default_dt(m)
        t_end = 10.0 * m.tau_m
        n_out = 1001
        for reps in replica_counts:
            res, cpu, wall = {}, {}, {}
            for tab in (False, True):
                rng = np.random.default_rng(5)
                c0, w0 = _cpu(), time.perf_counter()
                res[tab] = _event_driven(m, np.zeros(reps), n_out, t_end / (n_out - 1), dt, rng,
                                         tabulate=tab)
                cpu[tab], wall[tab] = _cpu() - c0, time.perf_counter() - w0
            dv = np.max(np.abs(res[True][0] - res[False][0]))
            dx = np.max(np.abs(res[True][1] - res[False][1]))
            print(f"| {name} | {reps} | {cpu[False]:.2f} | {cpu[True]:.2f} | {wall[False]:.2f} | "
                  f"{wall[True]:.2f} | {os.getloadavg()[0]:.1f} | {dv:.1e} | {dx:.1e} |")


if __name__ == "__main__":
    main(tuple(int(a) for a in sys.argv[1:]) or (200, 2000))
