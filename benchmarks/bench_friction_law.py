"""Benchmark of the real-diode transition element term (not a test).

``study.budget.real_diode_transition_element`` propagates two friction laws (the bridge's DC
law and tanh(v/epsilon)) on one Scharfetter-Gummel grid
(:func:`analogue.theory.friction_law.transition_moments_with_friction`).  A start deep in the
tail of the stationary law (gamma (U(v0) - U_min)/2 >= 23) cannot use the spectral sum; it
went by ``expm_multiply`` (``method="expm"``, O(n / h^2) per unit time: tens of seconds per
law to t = 8 on a 1N4148 grid) and now goes by the contour route (``method="auto"``, O(n) per
time).  Per start: CPU seconds of both laws by each route, side by side with the ratio, and the
largest difference of the element term (real minus tanh, the number the budget books) and of
either law's moments between the routes.  Starts outside the deep tail use the spectral sum
either way (same code, bit-identical): timed once, for scale.

Experiment: circuits/stick.toml with tau_m = 2, Delta = 0.5, a = 0.3, gamma = 15 and the 1N4148
bridge (grid n ~ 3300 at v0 = -3), times 0.5, 1, 1.6, 3, 8.

Usage:  .venv/bin/python benchmarks/bench_friction_law.py [--starts -2.5 -3]
"""
from __future__ import annotations

import argparse
import time
import tomllib
from pathlib import Path

import numpy as np

from analogue.circuit import map_model
from analogue.circuit.experiments import experiment_from_dict
from analogue.theory.friction_law import transition_moments_with_friction

TIMES = [0.5, 1.0, 1.6, 3.0, 8.0]


def mapping():
    data = tomllib.loads((Path(__file__).parent.parent / "circuits" / "stick.toml").read_text())
    data["model"].update(tau_m=2.0, delta=0.5, a=0.3, gamma=15.0)
    data["circuit"]["diode"] = "1N4148"
    exp = experiment_from_dict(data)
    return map_model(exp.model, exp.spec)


def both_laws(m, v0, method):
    model, eps = m.model_effective, m.epsilon
    t0 = time.process_time()
    real = transition_moments_with_friction(model, m.friction_law, eps, v0, TIMES, method=method)
    tanh = transition_moments_with_friction(model, lambda v: np.tanh(v / eps), eps, v0, TIMES,
                                            method=method)
    return time.process_time() - t0, real, tanh


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--starts", type=float, nargs="+", default=[-2.5, -3.0],
                    help="deep starts v0 (timed by both routes)")
    ap.add_argument("--shallow", type=float, nargs="*", default=[2.0, -2.0],
                    help="starts the spectral sum takes (timed once)")
    args = ap.parse_args()
    m = mapping()
    print(f"1N4148, tau_m=2, Delta=0.5, a=0.3, gamma=15: epsilon={m.epsilon:.4g}, times {TIMES}")
    print(f"{'v0':>6} {'expm [s]':>9} {'contour [s]':>12} {'ratio':>8} "
          f"{'max|d element|':>15} {'max|d law|':>11}")
    total_old = total_new = 0.0
    for v0 in args.starts:
        s_old, r_old, t_old = both_laws(m, v0, "expm")
        s_new, r_new, t_new = both_laws(m, v0, "auto")
        total_old, total_new = total_old + s_old, total_new + s_new
        d_el = max(abs((r_new[t][i] - t_new[t][i]) - (r_old[t][i] - t_old[t][i]))
                   for t in TIMES for i in range(3))
        d_law = max(abs(a[t][i] - b[t][i]) for a, b in ((r_new, r_old), (t_new, t_old))
                    for t in TIMES for i in range(3))
        print(f"{v0:6g} {s_old:9.2f} {s_new:12.3f} {s_old / s_new:8.0f} {d_el:15.1e} {d_law:11.1e}")
    if args.starts:
        print(f"{'total':>6} {total_old:9.2f} {total_new:12.3f} {total_old / total_new:8.0f}")
    for v0 in args.shallow:
        s, _, _ = both_laws(m, v0, "auto")
        print(f"{v0:6g} spectral sum (unchanged): {s:.2f} s")


if __name__ == "__main__":
    main()
