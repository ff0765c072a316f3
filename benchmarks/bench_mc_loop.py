"""Benchmark of the time-stepped SDE loop (``analogue.montecarlo._stepped``) where the report
spends it: the held/white noise pair of the bandwidth budget term
(:func:`analogue.study.budget.held_noise_pair` -> ``simulate_sde_held_pair``), old against new,
side by side (not a test).

"old" is ``analogue/montecarlo.py`` as of a git ref (``--old-ref``, default ``085af38``, the
last commit before the loop was rewritten); "new" is the checkout's.  Both integrate the same
noise ``z`` (drawn as ``held_noise_pair`` draws it), and their outputs are compared bit for bit.
The models are the report's effective models (``exp.mapping().model_effective``: the tanh
law at epsilon = smoothing sqrt(tau_m/gamma)) and sizes:

* stationary pair: 256 replicas (``MC_STATIONARY_REPLICAS``) x ``stationary_t_end`` (halved by
  ``--quick``), from v0 = 0 (the timing does not depend on the start);
* transition pair: 1024 replicas (``MC_REPLICAS``) x max(histogram_times), per v0 (the same
  at both sizes);

with the report's fine step (``held_noise_pair``: the circuit's noise hold split into
``ceil(noise_dt / default_dt)`` steps).  Printed per case: steps x rows, the CPU seconds
(user + sys, ``getrusage``) of drawing ``z`` and of the old and new pair, their ratio, and
whether the outputs are identical; the load average at the start and end.

Usage:  PYTHONPATH=. .venv/bin/python benchmarks/bench_mc_loop.py [stick slip work]
        [--size quick|full|both] [--old-ref 085af38] [--only new]
"""
from __future__ import annotations

import argparse
import math
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_report_runs import old_module  # noqa: E402

from analogue import montecarlo  # noqa: E402
from analogue.circuit.experiments import load_experiment  # noqa: E402
from analogue.study.comparisons import MC_REPLICAS, MC_STATIONARY_REPLICAS  # noqa: E402


def cpu_seconds() -> float:
    s = resource.getrusage(resource.RUSAGE_SELF)
    return s.ru_utime + s.ru_stime


def timed(f, *args, **kw):
    c, w = cpu_seconds(), time.perf_counter()
    out = f(*args, **kw)
    return out, cpu_seconds() - c, time.perf_counter() - w


def cases(name: str, size: str):
    """(label, model, v0, t_end, replicas, noise_dt, sample_dt) of the report's pairs."""
    exp = load_experiment(name)
    mp = exp.mapping()
    settings = exp.report
    t_stat = settings.stationary_t_end / (2 if size == "quick" else 1)
    out = [(f"stationary {size}", mp.model_effective, 0.0, t_stat, MC_STATIONARY_REPLICAS,
            mp.noise_dt, exp.sample_dt)]
    for v0 in exp.v0:
        out.append((f"transition v0={v0:g}", mp.model_effective, v0, max(exp.histogram_times),
                    MC_REPLICAS, mp.noise_dt, exp.sample_dt))
    return out


def noise(model, t_end, replicas, noise_dt, seed=1):
    """``held_noise_pair``'s fine step, hold and normals (its seed derivation)."""
    per_hold = max(1, math.ceil(noise_dt / montecarlo.default_dt(model) - 1e-9))
    n_hold = round(t_end / noise_dt)
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(7,)))
    return noise_dt / per_hold, per_hold, rng.standard_normal((replicas, n_hold * per_hold))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("models", nargs="*", default=["stick", "slip", "work"])
    ap.add_argument("--size", choices=("quick", "full", "both"), default="quick")
    ap.add_argument("--old-ref", default="085af38")
    ap.add_argument("--only", choices=("new",), default=None)
    ap.add_argument("--no-transitions", action="store_true")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        old = None if args.only else old_module(args.old_ref, Path(tmp), "analogue/montecarlo.py",
                                                "montecarlo_old", "analogue")
        # warm-up: the first call of a process pays one-time costs (~0.1 s) that would be
        # charged to whichever version runs first
        for mod in (montecarlo,) if old is None else (montecarlo, old):
            mod.simulate_sde_held_pair(montecarlo.Model(1.0, 0.7, 0.2, 10.0, epsilon=0.01),
                                       v0=0.0, t_end=1.0, replicas=64, dt=1e-3, sample_dt=1e-2,
                                       noise=np.zeros((64, 1000)), noise_hold=10)
        print(f"load average at start: {os.getloadavg()}")
        print(f"{'model':<6} {'case':<22} {'steps x rows':>16} {'z CPU s':>8} {'old CPU s':>9} "
              f"{'new CPU s':>9} {'old/new':>7} {'new wall s':>10} identical")
        tot = {"z": 0.0, "old": 0.0, "new": 0.0}
        sizes = ("quick", "full") if args.size == "both" else (args.size,)
        for name in args.models:
            seen = set()
            for size in sizes:
                for label, model, v0, t_end, reps, noise_dt, sample_dt in cases(name, size):
                    if label in seen or (args.no_transitions and label.startswith("transition")):
                        continue
                    seen.add(label)
                    (dt, hold, z), c_z, _ = timed(noise, model, t_end, reps, noise_dt)
                    kw = dict(v0=v0, t_end=t_end, replicas=reps, noise=z, noise_hold=hold, dt=dt,
                              sample_dt=noise_dt * max(1, round(sample_dt / noise_dt)))
                    new, c_new, w_new = timed(montecarlo.simulate_sde_held_pair, model, **kw)
                    c_old, same = float("nan"), "-"
                    if old is not None:
                        ref, c_old, _ = timed(old.simulate_sde_held_pair, model, **kw)
                        same = str(all(np.array_equal(getattr(a, f), getattr(b, f))
                                       for a, b in zip(new, ref) for f in ("v", "x", "t")))
                        del ref
                    tot["z"] += c_z
                    tot["old"] += c_old
                    tot["new"] += c_new
                    shape = f"{z.shape[1]} x {2 * reps}"
                    print(f"{name:<6} {label:<22} {shape:>16} {c_z:8.2f} {c_old:9.2f} {c_new:9.2f} "
                          f"{c_old / c_new:7.2f} {w_new:10.2f} {same}", flush=True)
                    del z, new
        print(f"{'total':<29} {'':>16} {tot['z']:8.2f} {tot['old']:9.2f} {tot['new']:9.2f} "
              f"{tot['old'] / tot['new']:7.2f}")
        print(f"load average at end: {os.getloadavg()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
