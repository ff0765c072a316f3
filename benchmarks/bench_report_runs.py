"""Benchmark of the report's circuit runs (issue 10): ``run_experiment_runs`` for the paper's
experiments at the ``--quick`` size, old against new, side by side (not a test).

"old" is ``analogue/study/runs.py`` and ``analogue/circuit/deck_size.py`` as of a git ref
(``--old-ref``, default ``main``; before issue 10's run scheduling: one ``simulate`` call after
another, the stationary check over the whole run, the deck-size cost model of one-replica
decks); "new" is the checkout's.  Each runs on its own empty run store (calibrations included), so
every deck really runs.  Printed per experiment and version: CPU seconds of this process and
its ngspice children (user + sys), wall seconds, the load average, and the report's
integration term in units of the statistical standard error (the largest over the stationary
observables and over the transition observables of the first v0): ``(|mean d| + 2 SE(d)) /
SE``, ``d`` the paired check-minus-nominal difference, ``SE`` the circuit estimate's jackknife
error (as in analogue.study.comparisons).

Usage:  PYTHONPATH=. .venv/bin/python benchmarks/bench_report_runs.py [stick slip work]
        [--old-ref main] [--only new|old] [--workers 2]
"""
from __future__ import annotations

import argparse
import importlib.util
import os
import resource
import subprocess
import sys
import tempfile
import time
from contextlib import contextmanager, nullcontext
from pathlib import Path

import numpy as np

from analogue.circuit.experiments import load_experiment, standard_circuit
from analogue.estimators.resampling import jackknife, jackknife_difference, subset
from analogue.study.budget import SE_MULTIPLIER
from analogue.report.plan import RunOptions
from analogue.study.theory_curves import stationary_taus
from analogue.study.catalogue import stationary_values, transition_values

ROOT = Path(__file__).resolve().parents[1]


def cpu_seconds() -> float:
    s = resource.getrusage(resource.RUSAGE_SELF)
    c = resource.getrusage(resource.RUSAGE_CHILDREN)
    return s.ru_utime + s.ru_stime + c.ru_utime + c.ru_stime


def old_module(ref: str, tmp: Path, path: str, name: str, package: str):
    """The file ``path`` at git ``ref``, imported as ``package.name`` (relative imports work)."""
    src = subprocess.run(["git", "-C", str(ROOT), "show", f"{ref}:{path}"],
                         check=True, capture_output=True, text=True).stdout
    file = tmp / f"{name}.py"
    file.write_text(src)
    spec = importlib.util.spec_from_file_location(f"{package}.{name}", file)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    mod.__package__ = package
    sys.modules[spec.name] = mod          # dataclasses look their module up there
    spec.loader.exec_module(mod)
    return mod


@contextmanager
def old_deck_size(mod):
    """The deck-size chooser of the old ref while the old runs are made (runs.py imports
    ``choose_deck_size`` from analogue.circuit.deck_size at call time)."""
    from analogue.circuit import deck_size
    saved = deck_size.choose_deck_size
    deck_size.choose_deck_size = mod.choose_deck_size
    try:
        yield
    finally:
        deck_size.choose_deck_size = saved


def pairs(runs):
    """(check, nominal) pairs on matched rows and times, for either version."""
    if hasattr(runs, "check_pair"):
        return runs.check_pair("transition"), runs.check_pair("stationary")
    rows = lambda c: np.arange(c.replicas)
    t0 = runs.transition[runs.exp.v0[0]]
    return ((runs.check_transition, subset(t0, rows(runs.check_transition))),
            (runs.check_stationary, subset(runs.stationary, rows(runs.check_stationary))))


def worst_term(fn, ens, chk, nom) -> tuple[str, float]:
    circ = jackknife(fn, ens)
    integ = jackknife_difference(fn, chk, nom)
    r = {k: (abs(integ[k][0]) + SE_MULTIPLIER * integ[k][1]) / se
         for k, (_, se) in circ.items() if se > 0}
    k = max(r, key=lambda name: r[name])
    return k, r[k]


def terms(runs) -> dict:
    exp, st = runs.exp, runs.settings
    model = exp.model
    thr = st.stick_threshold * model.velocity_scale
    taus = list(stationary_taus(exp, st))
    sfn = lambda e: stationary_values(e, burn_in=st.stationary_burn_in, threshold=thr,
                                      force=model.force, taus=taus)
    v0 = exp.v0[0]
    tfn = lambda e: transition_values(e, v0, list(exp.histogram_times))
    (tc, tn), (sc, sn) = pairs(runs)
    return {"stationary": worst_term(sfn, runs.stationary, sc, sn),
            "transition": worst_term(tfn, runs.transition[v0], tc, tn),
            "check_t_end": float(sc.t[-1]), "check_replicas": sc.replicas}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("experiments", nargs="*", default=["stick", "slip", "work"])
    ap.add_argument("--old-ref", default="main")
    ap.add_argument("--only", choices=("old", "new"))
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args(argv)
    from analogue.report import runs as new
    with tempfile.TemporaryDirectory(prefix="bench-report-runs-") as tmp:
        old = old_module(args.old_ref, Path(tmp), "analogue/study/runs.py", "_runs_old",
                         "analogue.report")
        old_ds = old_module(args.old_ref, Path(tmp), "analogue/circuit/deck_size.py",
                            "_deck_size_old", "analogue.circuit")
        versions = {"old": old, "new": new}
        if args.only:
            versions = {args.only: versions[args.only]}
        print(f"{'experiment':10s} {'version':7s} {'CPU s':>7s} {'wall s':>7s} {'load':>5s}  "
              f"integration term / SE (worst stationary; worst transition)  check")
        for name in args.experiments:
            exp = load_experiment(standard_circuit(name))
            for label, mod in versions.items():
                store = Path(tmp) / f"store-{label}-{name}"
                opts = RunOptions(quick=True, progress=False, store=store, workers=args.workers)
                c0, w0 = cpu_seconds(), time.perf_counter()
                with old_deck_size(old_ds) if label == "old" else nullcontext():
                    runs = mod.run_experiment_runs(exp, opts)
                cpu, wall = cpu_seconds() - c0, time.perf_counter() - w0
                t = terms(runs)
                (sk, sv), (tk, tv) = t["stationary"], t["transition"]
                print(f"{name:10s} {label:7s} {cpu:7.1f} {wall:7.1f} {os.getloadavg()[0]:5.1f}  "
                      f"{sv:.3f} ({sk}); {tv:.3f} ({tk})  {t['check_replicas']} x "
                      f"{t['check_t_end']:g}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
