"""Benchmark of the circuit runner: replica-steps per second (not a test).

A replica-step is one replica advanced by one noise hold time (``noise_dt``, tau_m/100 by
default): ngspice's cost scales with the number of held-noise breakpoints.  Configurations:

* ``pyspice-loop``  - the naive baseline: one trajectory per run of PySpice's shared-library
  simulator (NgSpiceShared: load the one-replica deck, ``run``, fetch vectors, interpolate).
* ``ngspice -b``    - the raw subprocess on one single-replica deck, nothing else (the ceiling
  for a one-replica deck: process start, parse, transient, raw write).
* ``simulate ...``  - :func:`analogue.simulate` with 1 or many replicas per deck, on one ngspice
  process or on all cores (no store, so every deck really runs).

Usage:  .venv/bin/python benchmarks/bench_circuit.py [--replicas 32] [--t-end 40] [--repeat 3]
        [--quick]
        .venv/bin/python benchmarks/bench_circuit.py --ceiling [--replicas 64] [--t-end 20]
        [--dask] [--model stick|slip]

``--ceiling`` (issue 10) runs the same job, side by side, as
* the fixed ceiling: two ``ngspice -b`` processes at once on 16-replica decks at the
  tolerances every deck had before issue 10 (reltol 1e-4, trtol 7, gear), nothing else;
* ``simulate`` at those tolerances (16/deck, 2 workers): the runner's own overhead;
* ``simulate`` with the tolerances and deck size chosen by measurement (the calibration
  timed separately: it is paid once per model and kept in the run store), and the chosen
  tolerances' measured integration error in statistical errors;
* with ``--dask``: the chosen configuration on a ``distributed.LocalCluster`` of 2 single-
  threaded worker processes against 2 local workers (cluster start-up and a warm-up task
  excluded: steady state).
Every line prints its throughput as a ratio to the ceiling, with the load average.
Set NGSPICE_LIBRARY_PATH if libngspice is not found (default tried:
/usr/lib/x86_64-linux-gnu/libngspice.so.0).
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import analogue
from analogue import Model
from analogue.circuit import map_model, build_deck
from analogue.circuit.ngspice import find_ngspice
from analogue.circuit.simulate import DEFAULT_REPLICAS_PER_DECK

LIB_CANDIDATES = ("/usr/lib/x86_64-linux-gnu/libngspice.so.0", "/usr/lib/libngspice.so.0",
                  "/usr/local/lib/libngspice.so")


def bench_simulate(model, *, replicas, t_end, per_deck, workers):
    t0 = time.perf_counter()
    e = analogue.simulate(model, v0=0.5, t_end=t_end, replicas=replicas, seed=1, store=False,
                          progress=False, replicas_per_deck=per_deck, workers=workers)
    wall = time.perf_counter() - t0
    assert e.v.shape[0] == replicas
    return wall, -(-replicas // per_deck)


def bench_raw(deck_text, repeats):
    exe = find_ngspice()
    with tempfile.TemporaryDirectory() as tmp:
        Path(tmp, "deck.cir").write_text(deck_text)
        t0 = time.perf_counter()
        for _ in range(repeats):
            subprocess.run([exe, "-b", "-r", "out.raw", "deck.cir"], cwd=tmp, check=True,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        return time.perf_counter() - t0


def bench_pyspice(mapping, *, trajectories, t_end, sample_dt):
    """One trajectory per shared-library run, as a first PySpice script would do it."""
    if "NGSPICE_LIBRARY_PATH" not in os.environ:
        for cand in LIB_CANDIDATES:
            if Path(cand).exists():
                os.environ["NGSPICE_LIBRARY_PATH"] = cand
                break
    import logging
    logging.getLogger("PySpice").setLevel(logging.ERROR)  # "Unsupported Ngspice version 39"
    from PySpice.Spice.NgSpice.Shared import NgSpiceShared
    ns = NgSpiceShared.new_instance()
    grid = np.arange(round(t_end / sample_dt) + 1) * sample_dt * mapping.theta
    t0 = time.perf_counter()
    for k in range(trajectories):
        deck = build_deck(mapping, replicas=1, v0=np.array([0.5]), t_end=t_end, seed=k + 1,
                          sample_dt=sample_dt)
        ns.load_circuit(deck.text)
        ns.run()
        plot = ns.plot(None, ns.last_plot)  # vectors keyed by node name ("v0", "time")
        t = np.real(np.asarray(plot["time"]._data))
        v = np.real(np.asarray(plot["v0"]._data))
        if t[-1] < grid[-1] * (1 - 1e-9):
            raise RuntimeError(f"shared-library run {k} stopped at {t[-1]:g} s")
        np.interp(grid, t, v)
        ns.destroy()
        ns.remove_circuit()
    return time.perf_counter() - t0


def _load() -> str:
    return "load %.1f" % os.getloadavg()[0]


def _raw_pair(texts) -> float:
    """Wall time of running ``texts`` (deck texts) as ``ngspice -b`` processes, two at a
    time (the fixed ceiling of issue 10): nothing but ngspice, output to files.  Each in its
    own session, like simulate's processes: with the kernel's autogroup scheduling a session
    gets a fair share of a loaded machine, so without it the ceiling ran 1.5x slower than
    simulate's identical decks under load 10 (12 s vs 7.5 s for 4 decks of 16)."""
    import concurrent.futures as cf
    exe = find_ngspice()
    with tempfile.TemporaryDirectory() as tmp:
        for i, t in enumerate(texts):
            Path(tmp, f"d{i}.cir").write_text(t)

        def one(i):
            with open(Path(tmp, f"d{i}.out"), "wb") as out:
                subprocess.run([exe, "-b", "-r", f"d{i}.raw", f"d{i}.cir"], cwd=tmp, check=True,
                               stdin=subprocess.DEVNULL, stdout=out, stderr=out,
                               start_new_session=True)
        t0 = time.perf_counter()
        with cf.ThreadPoolExecutor(2) as ex:
            list(ex.map(one, range(len(texts))))
        return time.perf_counter() - t0


def ceiling(argv=None):
    from analogue.circuit.deck_size import choose_deck_size
    from analogue.circuit.mapping import CircuitSpec
    from analogue.circuit.simulate import deck_seeds
    from analogue.circuit.tolerances import FIXED, choose_tolerances
    ap = argparse.ArgumentParser()
    ap.add_argument("--ceiling", action="store_true")
    ap.add_argument("--replicas", type=int, default=64)
    ap.add_argument("--t-end", type=float, default=20.0)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--dask", action="store_true")
    ap.add_argument("--model", choices=("stick", "slip"), default="stick")
    ap.add_argument("--store", default=os.environ.get("ANALOGUE_STORE", "/tmp/bench-circuit-store"))
    args = ap.parse_args(argv)
    R, T, rep = args.replicas, args.t_end, max(1, args.repeat)
    a = 0.2 if args.model == "stick" else 1.2
    model = Model(tau_m=1.0, delta=0.7, a=a, gamma=10.0)
    fixed = CircuitSpec(**FIXED.as_dict())
    mapping = map_model(model, fixed)
    holds = R * T / mapping.noise_dt
    print(f"{args.model}: {model.as_dict()}, {R} replicas x t_end {T:g} = {holds:.0f} "
          f"replica-holds; ngspice {analogue.circuit.ngspice.ngspice_version()}; {_load()}")

    # 1. the ceiling: 16-replica decks of the same job, two ngspice -b at a time
    n_dec = -(-R // 16)
    seeds = deck_seeds(1, n_dec)
    texts = [build_deck(mapping, replicas=16, v0=np.full(16, 0.5), t_end=T, seed=seeds[b],
                        sample_dt=mapping.noise_dt).text for b in range(n_dec)]
    rows = []

    def sim(spec, per_deck, **kw):
        t0 = time.perf_counter()
        e = analogue.simulate(model, v0=0.5, t_end=T, replicas=R, seed=1, store=False,
                              progress=False, circuit=spec, replicas_per_deck=per_deck, **kw)
        return time.perf_counter() - t0, e

    # 2. the calibration (once per model; kept in the store)
    t0 = time.perf_counter()
    cal = analogue.Runner(store=args.store, workers=2)
    tol = choose_tolerances(model, CircuitSpec(), replicas=R, t_end=T, runner=cal)
    chosen = CircuitSpec(**tol.tolerances.as_dict())
    deck = choose_deck_size(model, chosen, replicas=R, t_end=T, workers=2, runner=cal)
    t_cal = time.perf_counter() - t0
    print(f"chosen: {tol.tolerances.label()} (criterion met: {tol.criterion_met}, worst "
          f"{tol.worst_observable} at {tol.worst_ratio:.3f} statistical errors), "
          f"{deck.replicas_per_deck} replicas/deck; calibration {t_cal:.1f} s "
          f"(0 s once stored); {_load()}")
    if deck.predicted_s:
        print("deck-size cost model, predicted job s by replicas/deck: "
              + ", ".join(f"{r}: {t:.2f}" for r, t in deck.predicted_s.items())
              + "; points per hold measured: "
              + ", ".join(f"{r}: {p:.1f}" for r, p in deck.points_per_hold.items()))
    for k in range(rep):
        rows.append(("ceiling: 2 x ngspice -b, 16/deck, reltol 1e-4 gear", _raw_pair(texts),
                     _load()))
        rows.append(("simulate, 16/deck, reltol 1e-4 gear, 2 workers",
                     sim(fixed, 16, workers=2)[0], _load()))
        rows.append((f"simulate, chosen ({tol.tolerances.label()}, {deck.replicas_per_deck}/deck),"
                     " 2 workers", sim(chosen, deck.replicas_per_deck, workers=2)[0], _load()))
    if args.dask:
        from distributed import Client, LocalCluster
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                          dashboard_address=None) as cluster, Client(cluster) as client:
            # warm-up: imports and ngspice's first start on each worker, excluded
            analogue.simulate(model, v0=0.5, t_end=0.1, replicas=2, seed=99, store=False,
                              progress=False, circuit=chosen, replicas_per_deck=1,
                              scheduler=client)
            for k in range(rep):
                rows.append((f"simulate, chosen, {deck.replicas_per_deck}/deck, 2 local workers",
                             sim(chosen, deck.replicas_per_deck, workers=2)[0], _load()))
                rows.append((f"simulate, chosen, {deck.replicas_per_deck}/deck, Dask LocalCluster"
                             " 2x1", sim(chosen, deck.replicas_per_deck, scheduler=client)[0],
                             _load()))
    best = {}
    for label, wall, load in rows:
        best.setdefault(label, []).append((wall, load))
    ceil = min(w for w, _ in best[rows[0][0]])
    print(f"\n{'configuration':72s} {'wall s (each run, load)':>34s} {'us/rep-hold':>11s} "
          f"{'x ceiling':>9s}")
    for label, runs in best.items():
        w = min(x for x, _ in runs)
        each = ", ".join(f"{x:.2f} ({ld})" for x, ld in runs)
        print(f"{label:72s} {each:>34s} {1e6 * w / holds:11.1f} {ceil / w:9.2f}")
    if args.dask:
        lw = min(x for x, _ in best[next(k for k in best if "local workers" in k)])
        dw = min(x for x, _ in best[next(k for k in best if "Dask" in k)])
        print(f"Dask efficiency (local / Dask wall, fastest of {rep}): {lw / dw:.2f}")


def main(argv=None):
    if "--ceiling" in (argv if argv is not None else sys.argv[1:]):
        return ceiling(argv)
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--replicas", type=int, default=32)
    ap.add_argument("--t-end", type=float, default=40.0, help="model time units (tau_m = 1)")
    ap.add_argument("--repeat", type=int, default=1,
                    help="run each configuration this often and keep the fastest (busy machines)")
    ap.add_argument("--pyspice-trajectories", type=int, default=8)
    ap.add_argument("--quick", action="store_true", help="a quarter of the work")
    args = ap.parse_args(argv)
    R, T = args.replicas, args.t_end
    if args.quick:
        R, T = max(4, R // 2), T / 2
    cores = os.cpu_count() or 1
    model = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)  # stick regime (the costlier one)
    mapping = map_model(model)
    steps = T / mapping.noise_dt  # noise hold times per replica
    sample_dt = mapping.noise_dt
    print(f"model {model.as_dict()}; default circuit (ideal diode bridge, noise_dt = "
          f"{mapping.noise_dt:g}); t_end = {T:g} -> {steps:.0f} replica-steps per replica; "
          f"{cores} cores; ngspice {analogue.circuit.ngspice.ngspice_version()}")

    rows = []  # (label, replicas, decks, processes, wall)
    global _REPEAT
    _REPEAT = max(1, args.repeat)
    n_py = args.pyspice_trajectories
    try:
        rows.append(("pyspice-loop (1 traj/run)", n_py, n_py, 1, min(
            bench_pyspice(mapping, trajectories=n_py, t_end=T, sample_dt=sample_dt)
            for _ in range(_REPEAT))))
    except Exception as exc:  # noqa: BLE001 - report and go on: the others still mean something
        print(f"PySpice shared-library run failed: {exc!r}", file=sys.stderr)
    one = build_deck(mapping, replicas=1, v0=np.array([0.5]), t_end=T, seed=1,
                     sample_dt=sample_dt)
    reps = max(3, n_py)
    rows.append(("ngspice -b, 1-replica deck", reps, reps, 1,
                 min(bench_raw(one.text, reps) for _ in range(_REPEAT))))
    rows.append(("simulate, 1 replica/deck, 1 proc", R, *_sim(model, R, T, 1, 1)))
    rows.append(("simulate, 1 replica/deck, all cores", R, *_sim(model, R, T, 1, cores)))
    rows.append((f"simulate, {R} replicas/deck, 1 proc", R, *_sim(model, R, T, R, 1)))
    rows.append((f"simulate, {-(-R // cores)} replicas/deck, all cores", R,
                 *_sim(model, R, T, -(-R // cores), cores)))
    d = DEFAULT_REPLICAS_PER_DECK
    rows.append((f"simulate, {d} replicas/deck (default), 1 proc", R, *_sim(model, R, T, d, 1)))
    rows.append((f"simulate, {d} replicas/deck (default), all cores", R,
                 *_sim(model, R, T, d, cores)))

    base = rows[0][1] * steps / rows[0][4]
    print(f"\n{'configuration':50s} {'replicas':>8s} {'decks':>6s} {'procs':>5s} {'wall s':>8s} "
          f"{'replica-steps/s':>16s} {'us/rep-step':>11s} {'x baseline':>10s}")
    for label, n, decks, procs, wall in rows:
        rate = n * steps / wall
        print(f"{label:50s} {n:8d} {decks:6d} {procs:5d} {wall:8.2f} {rate:16.0f} "
              f"{1e6 / rate:11.1f} {rate / base:10.2f}")
    print(f"\nbaseline: {rows[0][0]}; fastest of {_REPEAT} run(s) per configuration")


_REPEAT = 1


def _sim(model, R, T, per_deck, workers):
    runs = [bench_simulate(model, replicas=R, t_end=T, per_deck=per_deck, workers=workers)
            for _ in range(_REPEAT)]
    wall = min(r[0] for r in runs)
    return runs[0][1], workers, wall


if __name__ == "__main__":
    main()
