"""Scaling with cores (issue 22, item 5): weak and strong scaling of ``simulate`` on local
workers and on a Dask ``LocalCluster``, the main job's critical path against its wall time,
the job in deck-times, and the start-up ratios, each a ratio measured in this one run
(not a test).

    PYTHONPATH=. .venv/bin/python benchmarks/bench_scaling.py            # everything, quick job
    PYTHONPATH=. .venv/bin/python benchmarks/bench_scaling.py --full     # the full job too
    PYTHONPATH=. .venv/bin/python benchmarks/bench_scaling.py --only simulate

* **deck-time**: the wall time of one fixed deck, the machine-independent unit the issue
  counts the job in: the stick model (tau_m = 1, Delta = 0.7, a = 0.2, gamma = 10), 16
  replicas from v0 = 0.5, t_end = 20 (2000 noise holds), at the tolerances every deck had
  before issue 10 (gear, reltol 1e-4, trtol 7), one ``ngspice -b`` process (issue 10's
  "fixed ceiling" deck); the fastest of three, timed before and after the job.
* **weak scaling**: ``simulate`` with ``per_worker`` decks of 16 replicas per worker (store
  off, so every deck runs), 1 .. usable cores workers; efficiency = wall(1) / wall(n) (1 is
  perfect).  **Strong scaling**: a fixed job of ``usable cores x per_worker`` decks on 1 ..
  usable cores workers; speed-up = wall(1) / wall(n).  With ``dask.distributed`` installed
  the same on a ``LocalCluster(n_workers=n, threads_per_worker=1)`` (started and warmed up
  before timing: steady state), printed as its ratio to the local wall of the same n.
* **the main job** (``bench_paper.run_paper``: ``analogue paper --quick`` on an empty store):
  wall time, the paper's chapters, the critical path (provenance ``critical_path_s``, the job
  with unlimited cores) and its ratio to the wall time, and all three in deck-times.
* **start-up**: ``import analogue`` and ``analogue --help`` against ``import numpy``
  (``bench_startup``, interleaved, medians).

On a shared machine only the ratios taken in one run mean much: every line prints the load
average (1 min) when it was measured.
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))

from analogue import Model  # noqa: E402
from analogue.cores import usable_cpus  # noqa: E402

STICK = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)
DECK_REPLICAS = 16


def _load() -> float:
    return os.getloadavg()[0]


def deck_time(repeats: int = 3) -> float:
    """Wall seconds of the fixed reference deck (module docstring), fastest of ``repeats``."""
    from analogue.circuit import build_deck, map_model
    from analogue.circuit.mapping import CircuitSpec
    from analogue.circuit.ngspice import find_ngspice
    from analogue.circuit.tolerances import FIXED
    mapping = map_model(STICK, CircuitSpec(**FIXED.as_dict()))
    text = build_deck(mapping, replicas=DECK_REPLICAS, v0=np.full(DECK_REPLICAS, 0.5),
                      t_end=20.0, seed=1, sample_dt=mapping.noise_dt).text
    walls = []
    with tempfile.TemporaryDirectory() as tmp:
        Path(tmp, "deck.cir").write_text(text)
        for _ in range(repeats):
            t0 = time.perf_counter()
            subprocess.run([find_ngspice(), "-b", "-r", "deck.raw", "deck.cir"], cwd=tmp,
                           check=True, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL, start_new_session=True)
            walls.append(time.perf_counter() - t0)
    return min(walls)


def _simulate(decks: int, t_end: float, **kw) -> float:
    import analogue
    t0 = time.perf_counter()
    e = analogue.simulate(STICK, v0=0.5, t_end=t_end, replicas=decks * DECK_REPLICAS, seed=1,
                          store=False, progress=False, replicas_per_deck=DECK_REPLICAS, **kw)
    wall = time.perf_counter() - t0
    assert e.v.shape[0] == decks * DECK_REPLICAS
    return wall


def simulate_scaling(counts: list[int], per_worker: int, t_end: float, dask: bool) -> None:
    """Weak and strong scaling tables (module docstring)."""
    from analogue.circuit.mapping import CircuitSpec
    from analogue.circuit.tolerances import FIXED
    spec = CircuitSpec(**FIXED.as_dict())   # fixed tolerances: no calibration in the timing
    n_max = max(counts)
    clusters: dict = {}
    if dask:
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            print("dask.distributed is not installed: local workers only")
            dask = False
    rows = []
    try:
        for n in counts:
            client = None
            if dask:
                cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                       dashboard_address=None)
                client = Client(cluster)
                clusters[n] = (cluster, client)
                _simulate(n, 0.1, circuit=spec, scheduler=client)       # warm-up, excluded
            weak = _simulate(n * per_worker, t_end, circuit=spec, workers=n)
            weak_load = _load()
            strong = _simulate(n_max * per_worker, t_end, circuit=spec, workers=n)
            strong_load = _load()
            dweak = dstrong = None
            if client is not None:
                dweak = _simulate(n * per_worker, t_end, circuit=spec, scheduler=client)
                dstrong = _simulate(n_max * per_worker, t_end, circuit=spec, scheduler=client)
                cluster, client = clusters.pop(n)
                client.close()
                cluster.close()
            rows.append((n, weak, weak_load, strong, strong_load, dweak, dstrong, _load()))
            # each row as it is measured (a run cut short by a time limit keeps them)
            print(f"  {n} workers: weak {weak:.2f} s, strong {strong:.2f} s"
                  + (f", Dask weak {dweak:.2f} s, strong {dstrong:.2f} s"
                     if dweak is not None else "") + f" (load {_load():.2f})", flush=True)
    finally:
        for cluster, client in clusters.values():
            client.close()
            cluster.close()
    w1, s1 = rows[0][1], rows[0][3]
    print(f"\nsimulate, stick, {DECK_REPLICAS}-replica decks x t_end {t_end:g}, fixed tolerances "
          f"(gear 1e-4), store off; weak: {per_worker} decks per worker, strong: "
          f"{n_max * per_worker} decks")
    head = ("| workers | weak wall [s] | weak efficiency | strong wall [s] | strong speed-up "
            "| load |")
    sep = "|---|---|---|---|---|---|"
    if dask:
        head += " Dask weak / local | Dask strong / local (wall ratio local/Dask) |"
        sep += "---|---|"
    print(head)
    print(sep)
    for n, weak, wl, strong, sl, dweak, dstrong, _ in rows:
        line = (f"| {n} | {weak:.2f} | {w1 / weak:.2f} | {strong:.2f} | {s1 / strong:.2f} "
                f"| {wl:.1f}, {sl:.1f} |")
        if dask:
            line += f" {weak / dweak:.2f} | {strong / dstrong:.2f} |"
        print(line)


def main_job(full: bool, extra: tuple = (), save: Path | None = None) -> dict:
    """The paper job on an empty store (bench_paper), its critical path and deck-times;
    ``extra``: more arguments of ``analogue paper``; ``save``: where its metrics.json goes."""
    import bench_paper
    r = bench_paper.run_paper(ROOT, full, extra=extra, save=save)
    bench_paper._print(r)
    return r


def startup(repeats: int) -> None:
    import bench_startup
    from bench_paper import _python_path as bench_paper_path
    env = {**os.environ, "PYTHONPATH": bench_paper_path(ROOT)}
    times: dict[str, list[float]] = {k: [] for k in bench_startup.COMMANDS}
    for _ in range(repeats):
        for name, cmd in bench_startup.COMMANDS.items():
            t0 = time.perf_counter()
            subprocess.run(cmd, env=env, stdout=subprocess.DEVNULL, check=True)
            times[name].append(time.perf_counter() - t0)
    base = statistics.median(times["import numpy"])
    print(f"\nstart-up ({repeats} interleaved runs each, load {_load():.2f}): "
          + "; ".join(f"{k} {statistics.median(v):.3f} s ({statistics.median(v) / base:.2f}x "
                      "import numpy)" for k, v in times.items()))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", choices=("simulate", "job", "startup"), action="append",
                    help="run only these parts (repeatable; default: all)")
    ap.add_argument("--full", action="store_true", help="the full paper job as well")
    ap.add_argument("--quick-job", action=argparse.BooleanOptionalAction, default=True,
                    help="the quick paper job (default: yes; --no-quick-job with --full or "
                         "--sweeps to time only those)")
    ap.add_argument("--sweeps", action="store_true",
                    help="the quick paper job with --sweeps (make paper's job) as well")
    ap.add_argument("--save", type=Path, default=None,
                    help="copy each job's metrics.json into this directory")
    ap.add_argument("--workers", type=int, nargs="*", default=None,
                    help="worker counts (default 1 .. usable cores)")
    ap.add_argument("--per-worker", type=int, default=2, help="decks per worker (weak)")
    ap.add_argument("--t-end", type=float, default=20.0, help="model time of each deck")
    ap.add_argument("--no-dask", action="store_true", help="local workers only")
    ap.add_argument("--startup-repeats", type=int, default=9)
    args = ap.parse_args()
    parts = set(args.only or ("simulate", "job", "startup"))
    cores = usable_cpus()
    counts = args.workers or list(range(1, cores + 1))
    print(f"usable cores {cores} (os.cpu_count {os.cpu_count()}); load {_load():.2f}")
    d0 = deck_time()
    print(f"deck-time (reference deck, before): {d0:.3f} s (load {_load():.2f})", flush=True)
    if "simulate" in parts:
        simulate_scaling(counts, args.per_worker, args.t_end, not args.no_dask)
    jobs = []
    if "job" in parts:
        plan = [(name, full, extra) for name, full, extra, wanted in (
            ("quick", False, (), args.quick_job), ("quick --sweeps", False, ("--sweeps",),
                                                   args.sweeps),
            ("full", True, (), args.full)) if wanted]
        for name, full, extra in plan:
            save = (args.save / f"metrics-{name.replace(' --', '-')}.json"
                    if args.save is not None else None)
            jobs.append((name, main_job(full, extra, save)))
            sys.stdout.flush()
    d1 = deck_time()
    deck = 0.5 * (d0 + d1)
    print(f"\ndeck-time (reference deck, after): {d1:.3f} s (load {_load():.2f}); "
          f"mean {deck:.3f} s")
    if jobs:
        print("| job | wall [s] | paper's chapters [s] | critical path [s] | critical path / wall "
              "| wall [deck-times] | paper's chapters [deck-times] | critical path [deck-times] "
              "| load start -> end |")
        print("|---|---|---|---|---|---|---|---|---|")
        for name, r in jobs:
            cp, wall, paper = r["critical_path_s"], r["wall_s"], r["paper_wall_s"]
            print(f"| {name} | {wall:.1f} | {paper:.1f} | {cp:.1f} | {cp / wall:.2f} | "
                  f"{wall / deck:.0f} | {paper / deck:.0f} | {cp / deck:.0f} | "
                  f"{r['load_1min'][0]:.1f} -> {r['load_1min'][1]:.1f} |")
    if "startup" in parts:
        startup(args.startup_repeats)


if __name__ == "__main__":
    main()
