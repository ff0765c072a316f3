"""Model-family circuits (issue 9): ngspice time per extension, and the shot-noise source
measured two ways (seeded PWL pulses, the project's route, against an ngspice-native
compound Poisson source built from trrandom types 4 (Poisson count) and 3 (exponential size)).

    .venv/bin/python benchmarks/bench_family_circuit.py [--quick]

Prints wall times (one ngspice process, workers=1, store off) and, for the shot source, the
stationary mean, variance and P(|v| < 0.05) against the exact event-driven averages.
"""
from __future__ import annotations

import argparse
import math
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from analogue import Model, ShotNoise, simulate
from analogue.circuit import build_deck, map_model
from analogue.circuit.experiments import load_experiment
from analogue.circuit.rawfile import read_raw


def time_experiments(quick: bool) -> None:
    print("experiment  replicas x t_end  wall [s]  per replica-time-unit [ms]")
    for name in ("cubic", "stribeck", "spring", "shot"):
        exp = load_experiment(name)
        v0 = exp.initial_velocities()
        if quick:
            v0 = v0[:8]
        t0 = time.perf_counter()
        simulate(exp.model, v0=v0, t_end=exp.t_end, replicas=v0.size, seed=exp.seed,
                 sample_dt=exp.sample_dt, circuit=exp.spec, workers=1, store=False)
        wall = time.perf_counter() - t0
        print(f"{name:10s}  {v0.size:4d} x {exp.t_end:5.0f}  {wall:8.1f}  "
              f"{1e3 * wall / (v0.size * exp.t_end):8.2f}")


def exact_averages(thr=0.05, n=400_000, seed=1, tau=1.0, delta=0.5, a=0.2, rate=1.0, mean=0.5):
    """Exact time averages of the one-sided shot-noise stick regime (closed-form flow)."""
    rng = np.random.default_rng(seed)
    gaps, jumps = rng.exponential(1 / rate, n), rng.exponential(mean, n)
    b = (delta - a) * tau
    s1 = s2 = tlow = 0.0
    v = 0.0
    for g, z in zip(gaps, jumps):
        v0 = v + z
        ta = tau * math.log1p(v0 / b)
        s = min(g, ta)
        c = v0 + b
        e = math.exp(-s / tau)
        s1 += c * tau * (1 - e) - b * s
        s2 += c * c * tau / 2 * (1 - e * e) - 2 * b * c * tau * (1 - e) + b * b * s
        t_thr = tau * math.log((v0 + b) / (thr + b)) if v0 > thr else 0.0
        tlow += max(0.0, s - t_thr) + (g - s)
        v = c * e - b if g < ta else 0.0
    T = gaps.sum()
    return s1 / T, s2 / T - (s1 / T) ** 2, tlow / T


def trrandom_deck(pwl_text: str, mapping, replicas: int, ts: float) -> str:
    """The PWL deck with its kick sources replaced by held trrandom sources: per hold TS a
    Poisson count N (mean rate TS) times an exponential size E (mean), delivered as the
    current C kappa N E / TS during the hold."""
    lines = pwl_text.splitlines()
    out, skip = [], False
    for ln in lines:
        if ln.startswith("Ishot"):
            skip = True
            continue
        if skip and ln.startswith("+"):
            continue
        skip = False
        out.append(ln)
    sh = mapping.model.shot
    theta = mapping.theta
    add = []
    for i in range(replicas):
        add += [f"Vcnt{i} nc{i} 0 dc 0 trrandom(4 {ts * theta:.15g} 0 {sh.rate * ts:.15g} 0)",
                f"Vsz{i} ns{i} 0 dc 0 trrandom(3 {ts * theta:.15g} 0 {sh.mean:.15g} 0)",
                f"Bshot{i} 0 v{i} i={mapping.shot_charge / (ts * theta):.15g}*V(nc{i})*V(ns{i})"]
    k = next(j for j, ln in enumerate(out) if ln.startswith(".ic"))
    return "\n".join(out[:k] + add + out[k:]) + "\n"


def run(text: str):
    with tempfile.TemporaryDirectory() as tmp:
        Path(tmp, "d.cir").write_text(text)
        t0 = time.perf_counter()
        p = subprocess.run(["ngspice", "-b", "-r", "o.raw", "d.cir"], cwd=tmp,
                           capture_output=True, text=True, timeout=3600)
        wall = time.perf_counter() - t0
        assert p.returncode == 0, p.stdout + p.stderr
        return wall, read_raw(Path(tmp, "o.raw"))[0]


def shot_sources(quick: bool) -> None:
    model = Model(tau_m=1.0, delta=0.5, a=0.2, gamma=math.inf, shot=ShotNoise(rate=1.0, mean=0.5))
    m = map_model(model)
    replicas, t_end, burn = (8, 50.0, 5.0) if quick else (32, 100.0, 5.0)
    deck = build_deck(m, replicas=replicas, v0=np.zeros(replicas), t_end=t_end, seed=7,
                      sample_dt=0.01)
    mean_ex, var_ex, low_ex = exact_averages()
    print(f"exact: mean {mean_ex:.4f} var {var_ex:.4f} P(|v|<0.05) {low_ex:.4f}")
    grid = np.arange(round(t_end / 0.01) + 1) * 0.01
    for label, text in [("pwl", deck.text)] + [
            (f"trrandom TS={ts}", trrandom_deck(deck.text, m, replicas, ts)) for ts in (0.01, 0.001)]:
        wall, plot = run(text)
        t = plot["time"] / m.theta
        v = np.array([np.interp(grid, t, plot[f"v(v{i})"]) for i in range(replicas)]) / m.kappa
        v = v[:, grid >= burn]
        per_mean, per_var = v.mean(axis=1), ((v - v.mean()) ** 2).mean(axis=1)
        low = (np.abs(v) < 0.05).mean(axis=1)
        se = lambda x: x.std(ddof=1) / math.sqrt(x.size)
        print(f"{label:18s} wall {wall:6.2f} s  points {plot.n_points:7d}  "
              f"mean {per_mean.mean():.4f} (z {(per_mean.mean() - mean_ex) / se(per_mean):+.2f})  "
              f"var {per_var.mean():.4f} (z {(per_var.mean() - var_ex) / se(per_var):+.2f})  "
              f"P0 {low.mean():.4f} (z {(low.mean() - low_ex) / se(low):+.2f})")


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    shot_sources(args.quick)
    time_experiments(args.quick)
