"""The report's stationary jackknives, per-replica route against the direct one (issue 10):
``analyse`` of stored quick runs with ``StationaryValues.leave_group_out`` (new) and with the
observables recomputed on each subset copy (old), alternating old/new twice in one process;
prints CPU and wall seconds and the largest relative difference of every comparison number.

Run (reads a complete ``--quick`` store, runs nothing new; point the env at copies):
``ANALOGUE_STORE=... ANALOGUE_THEORY_CACHE=... .venv/bin/python benchmarks/bench_jackknife.py
work stick slip``.  Results: benchmarks/README.md.
"""
import math
import os
import resource
import sys
import time
from dataclasses import asdict
from pathlib import Path
from analogue.study.runs import run_experiment_runs
from analogue.report.plan import RunOptions
from analogue.study.comparisons import analyse
from analogue.study.theory_curves import experiment_theory
from analogue.circuit.experiments import load_experiment, standard_circuit
from analogue.estimators import resampling as R

def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime

def flat(d, pre=""):
    for k, v in d.items():
        if isinstance(v, dict):
            yield from flat(v, pre + k + ".")
        elif isinstance(v, float):
            yield pre + k, v

fast = R._left_out
def direct(fn, ens, labels, g):
    # the old route: the observables on each subset copy
    return [fn(R.subset(ens, labels != j)) for j in range(g)]

for name in sys.argv[1:]:
    exp = load_experiment(standard_circuit(name))
    runs = run_experiment_runs(exp, RunOptions(quick=True, progress=False,
                                               store=Path(os.environ["ANALOGUE_STORE"])))
    theory = experiment_theory(exp, runs.settings)
    out = {}
    for label, route in (("old", direct), ("new", fast), ("old", direct), ("new", fast)):
        R._left_out = route
        c0, w0 = cpu(), time.perf_counter()
        res = analyse(runs, theory=theory)
        out.setdefault(label, []).append((cpu() - c0, time.perf_counter() - w0, res))
    R._left_out = fast
    worst, n = (0.0, ""), 0
    per = {}
    for a, b in zip(out["old"][0][2].comparisons, out["new"][0][2].comparisons):
        assert a.observable == b.observable
        for (k, x), (k2, y) in zip(flat(asdict(a)), flat(asdict(b))):
            assert k == k2
            n += 1
            if x == y or (math.isnan(x) and math.isnan(y)):
                continue
            rel = abs(x - y) / max(abs(x), abs(y))
            scale = abs(x - y) / max(abs(a.circuit), abs(a.theory), 1e-300)
            f = per.setdefault(k, [0.0, 0.0])
            f[0], f[1] = max(f[0], rel), max(f[1], scale)
            if rel > worst[0]:
                worst = (rel, f"{a.observable} {k}: {x!r} vs {y!r}")
    print(f"{name}: {len(out['old'][0][2].comparisons)} comparisons, {n} numbers, "
          f"max rel diff {worst[0]:.3g} ({worst[1]})")
    for k, (r1, r2) in per.items():
        print(f"    {k}: max rel {r1:.3g}, rel to |circuit| {r2:.3g}")
    for label in ("old", "new"):
        print(f"  {label}: CPU " + ", ".join(f"{c:.2f}" for c, _, _ in out[label])
              + " s; wall " + ", ".join(f"{w:.2f}" for _, w, _ in out[label]) + " s")
    print("  load", os.getloadavg())
