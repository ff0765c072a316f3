"""Benchmark of drawing the paper chapters' figures (issue 10), old against new, side by side
(not a test).

The report draws each experiment's figures in its main thread (the ``figures`` phase), while
ngspice keeps both cores busy; this times only the drawing.  The analyses are built once from
the run store (``run_experiment_runs`` reuses stored runs: fill the store first, e.g.
``analogue report stick --quick``) and pickled; then one child process per version unpickles
them and draws every figure of :func:`analogue.report.pipeline._figures_for` plus Fig. 1
(``fig_deterministic``).  "old" is ``analogue/`` as of a git ref (``--old-ref``, default
``main``) extracted with ``git archive``; "new" is this checkout.  Each child draws every figure
once (the first pass, as a report does: fonts, caches, imports; its total is printed too),
then ``--repeat`` times, and reports the median CPU seconds of the process (user + sys) per
figure.  Old and new write their PNGs to separate directories;
the benchmark then checks that each pair has the same pixel size and prints the share of
pixels that differ (look at the pairs: ``--keep DIR`` keeps them).

Usage:  PYTHONPATH=. .venv/bin/python benchmarks/bench_figures.py [stick slip work]
        [--old-ref main] [--repeat 3] [--rounds 2] [--full] [--keep DIR]
        [--analyses FILE.pickle]
"""
from __future__ import annotations

import argparse
import json
import os
import pickle
import resource
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def cpu_seconds() -> float:
    s = resource.getrusage(resource.RUSAGE_SELF)
    return s.ru_utime + s.ru_stime


# ------------------------------------------------------------------------- the analyses
def build_analyses(names, quick: bool, store: Path | None) -> list:
    """(runs, analysis) per experiment, as the report builds them (runs from the store)."""
    from analogue.circuit.experiments import load_experiment, standard_circuit
    from analogue.study.comparisons import analyse
    from analogue.report.plan import RunOptions
    from analogue.study.runs import run_experiment_runs
    from analogue.study.theory_curves import experiment_theory, figure_curves

    opts = RunOptions(quick=quick, progress=False, store=store)
    out = []
    for name in names:
        exp = load_experiment(standard_circuit(name))
        t0 = time.perf_counter()
        runs = run_experiment_runs(exp, opts)
        theory = experiment_theory(exp, exp.report.for_options(opts))
        analysis = analyse(runs, theory=theory)
        analysis.curves = figure_curves(runs)
        print(f"{name}: analysis built in {time.perf_counter() - t0:.1f} s (wall)", flush=True)
        out.append(analysis)
    return out


# ----------------------------------------------------------------------- the child side
def figure_calls(analysis, out: Path):
    """(label, call) for every figure the report draws for this experiment."""
    from analogue.circuit.experiments import PAPER_FIGURE_TAGS
    from analogue.report import figures

    a, runs = analysis, analysis.runs
    name = runs.exp.name
    tag = PAPER_FIGURE_TAGS.get(name, "paths")
    calls = [(f"{name}: fig1 deterministic", lambda: figures.fig_deterministic([runs], out)),
             (f"{name}: prehistory", lambda: figures.fig_prehistory(a, out, tag)),
             (f"{name}: boundaries", lambda: figures.fig_boundaries(runs, out)),
             (f"{name}: propagator v0[0]", lambda: figures.fig_propagator(a, out))]
    if len(runs.exp.v0) > 1:
        calls.append((f"{name}: propagator v0[-1]",
                      lambda: figures.fig_propagator(a, out, runs.exp.v0[-1])))
    calls += [(f"{name}: stationary law", lambda: figures.fig_stationary(a, out)),
              (f"{name}: work paths", lambda: figures.fig_work_paths(a, out)),
              (f"{name}: rate function", lambda: figures.fig_rate_function(a, out)),
              (f"{name}: error budget", lambda: figures.fig_budget(a, out))]
    return calls


def draw(pickled: Path, out: Path, repeat: int) -> dict:
    """Median CPU seconds per figure (after one untimed pass), and the files written."""
    with open(pickled, "rb") as fh:
        analyses = pickle.load(fh)
    calls = [c for a in analyses for c in figure_calls(a, out)]
    files: dict = {}
    first: dict = {}
    for label, call in calls:          # the first pass, as in a report: fonts, caches, imports
        c0 = cpu_seconds()
        r = call()
        first[label] = cpu_seconds() - c0
        if r is not None:
            files[label] = Path(r[0]).name
    times: dict = {label: [] for label, _ in calls}
    for _ in range(repeat):
        for label, call in calls:
            c0 = cpu_seconds()
            call()
            times[label].append(cpu_seconds() - c0)
    return {"seconds": {k: statistics.median(v) for k, v in times.items() if k in files},
            "first": sum(first[k] for k in files), "files": files}


# ---------------------------------------------------------------------- the parent side
def old_tree(ref: str, tmp: Path) -> Path:
    """``analogue/`` as of git ``ref``, extracted into ``tmp`` (importable from there)."""
    archive = tmp / "old.tar"
    subprocess.run(["git", "-C", str(ROOT), "archive", "--format=tar", "-o", str(archive), ref,
                    "analogue"], check=True)
    with tarfile.open(archive) as tar:
        tar.extractall(tmp / "old", filter="data")
    return tmp / "old"


def run_child(tree: Path, pickled: Path, out: Path, repeat: int) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree), MPLBACKEND="Agg")
    out.mkdir(parents=True, exist_ok=True)
    res = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--child",
                          str(pickled), str(out), str(repeat)],
                         env=env, check=True, capture_output=True, text=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


def compare_png(a: Path, b: Path) -> str:
    from matplotlib.image import imread
    import numpy as np
    x, y = imread(a), imread(b)
    if x.shape != y.shape:
        return f"SIZE DIFFERS {x.shape[1]}x{x.shape[0]} vs {y.shape[1]}x{y.shape[0]}"
    diff = np.any(np.abs(x - y) > 1 / 255, axis=-1)
    return f"{x.shape[1]}x{x.shape[0]}, {100 * diff.mean():.2f} % px differ"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("experiments", nargs="*", default=["stick", "slip", "work"])
    ap.add_argument("--old-ref", default="main")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--full", action="store_true", help="full-size runs (default: --quick)")
    ap.add_argument("--store", type=Path, default=None)
    ap.add_argument("--keep", type=Path, default=None, help="keep the PNGs in this directory")
    ap.add_argument("--rounds", type=int, default=2,
                    help="child processes per version, old and new alternating (the machine's "
                         "load drifts: a version drawn later is not slower for it)")
    ap.add_argument("--analyses", type=Path, default=None,
                    help="pickle of the analyses: read if it exists, else built and written")
    args = ap.parse_args(argv)
    store = args.store or (Path(os.environ["ANALOGUE_STORE"]) if "ANALOGUE_STORE" in os.environ
                           else None)
    with tempfile.TemporaryDirectory(prefix="bench-figures-") as tmp_:
        tmp = Path(tmp_)
        keep = args.keep or tmp
        pickled = args.analyses or tmp / "analyses.pickle"
        if not pickled.exists():
            with open(pickled, "wb") as fh:
                pickle.dump(build_analyses(args.experiments, not args.full, store), fh)
        old = old_tree(args.old_ref, tmp)
        load0 = os.getloadavg()[0]
        trees = {"old": old, "new": ROOT}
        runs: dict = {"old": [], "new": []}
        for r in range(args.rounds):
            for version in (("old", "new") if r % 2 == 0 else ("new", "old")):
                w0 = time.perf_counter()
                runs[version].append(run_child(trees[version], pickled, keep / version,
                                               args.repeat))
                print(f"round {r + 1}, {version}: {time.perf_counter() - w0:.1f} s wall for "
                      f"{args.repeat + 1} passes", flush=True)
        res = {v: {"files": rs[0]["files"],
                   "first": statistics.median(x["first"] for x in rs),
                   "seconds": {k: statistics.median(x["seconds"][k] for x in rs)
                               for k in rs[0]["seconds"]}} for v, rs in runs.items()}
        print(f"\nCPU seconds per figure (median over {args.rounds} processes of the median of "
              f"{args.repeat} passes; load average {load0:.2f} -> {os.getloadavg()[0]:.2f}); "
              f"old = {args.old_ref}, new = this checkout")
        print(f"{'figure':36s} {'old':>7s} {'new':>7s} {'ratio':>6s}  png (old vs new)")
        tot_o = tot_n = 0.0
        for label, so in res["old"]["seconds"].items():
            sn = res["new"]["seconds"].get(label, float("nan"))
            tot_o, tot_n = tot_o + so, tot_n + sn
            f_o, f_n = res["old"]["files"][label], res["new"]["files"].get(label)
            cmp = (compare_png(keep / "old" / f_o, keep / "new" / f_n) if f_n == f_o
                   else f"files differ: {f_o} vs {f_n}")
            print(f"{label:36s} {so:7.3f} {sn:7.3f} {so / sn:6.2f}  {cmp}")
        print(f"{'total':36s} {tot_o:7.3f} {tot_n:7.3f} {tot_o / tot_n:6.2f}")
        fo, fn = res["old"]["first"], res["new"]["first"]
        print(f"{'total, first pass of a process':36s} {fo:7.3f} {fn:7.3f} {fo / fn:6.2f}  "
              "(what a report pays: it draws each figure once)")
    return 0


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        print(json.dumps(draw(Path(sys.argv[2]), Path(sys.argv[3]), int(sys.argv[4]))))
    else:
        sys.exit(main())
