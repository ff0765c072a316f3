"""The noise-bandwidth frontier of the paper's experiments: bias (in statistical errors)
against ngspice CPU, for several stationary noise holds and smoothing widths (not a test).

For each experiment (stick, slip, work), each smoothing width and each stationary hold
divisor ``k`` (the stationary runs hold the noise for ``noise_dt / k``,
``[report] stationary_hold_divisor``; the transition runs keep ``noise_dt``) it prints

- the budget's bandwidth term of every comparison (``|d| + 2 SE(d)`` from the held/white
  Monte Carlo pair on the report's seeds, :func:`analogue.study.budget.held_noise_pair`),
  in units of the circuit's statistical error at full size.  That error is estimated from
  the white Monte Carlo run of the same pair (delete-a-group jackknife over replicas),
  scaled by ``sqrt(n_mc / n_circuit)`` to the report's replica count: the circuit is that
  process up to the budget's other terms.  Columns: the largest stationary term (and the
  stick fraction's), the largest transition term;
- the ngspice CPU (children user + sys) of one stationary deck (``--replicas`` replicas from
  the stationary law over ``--t-end``, fixed tolerances trap 1e-4 trtol 7, no store)
  relative to ``k = 1`` (the hold before the stationary holds were refined), and the cost of
  the full report's runs relative to ``k = 1``: each run kind weighted by its replica-time
  in the full report (checks at 5x the nominal cost per unit time, as in
  :mod:`analogue.study.runs`) times its measured CPU per replica-time.

The last lines sum the report cost over the experiments (the paper: the goal is at most 1.25x).

Usage:  PYTHONPATH=. .venv/bin/python benchmarks/bench_bandwidth_frontier.py
        [--experiments stick,slip,work] [--divisors 1,2,4] [--smoothing 0.02]
        [--replicas 32] [--t-end 10] [--no-ngspice]
"""
from __future__ import annotations

import argparse
import math
import resource
import time

import numpy as np

from analogue import simulate
from analogue.circuit.experiments import load_experiment, standard_circuit
from analogue.circuit.mapping import map_model
from analogue.estimators.resampling import jackknife, jackknife_difference
from analogue.study.budget import SE_MULTIPLIER, held_noise_pair
from analogue.study.comparisons import MC_REPLICAS, MC_STATIONARY_REPLICAS
from analogue.study.theory_curves import stationary_taus
from analogue.study.catalogue import StationaryValues, transition_values
from analogue.study.seeds import SeedPlan
from analogue.theory.exact import sample_stationary


def children_cpu() -> float:
    c = resource.getrusage(resource.RUSAGE_CHILDREN)
    return c.ru_utime + c.ru_stime


def _in_se(diff: dict, white: dict, scale: float) -> dict:
    """{label: budget term / circuit SE}: the term |d| + 2 se, the SE the white run's
    jackknife scaled to the circuit's replica count."""
    out = {}
    for k, (d, se) in diff.items():
        s = white[k][1] * scale
        out[k] = (abs(d) + SE_MULTIPLIER * se) / s if s > 0 else math.nan
    return out


def bias_in_se(exp, spec, noise_dt: dict) -> dict:
    """{"stationary": {label: term/SE}, "transition": {label: term/SE}} at full size with
    ``noise_dt = {"stationary": dt, "transition": dt}``."""
    model = exp.model
    m_eff = map_model(model, spec).model_effective
    settings = exp.report
    seeds = SeedPlan(exp.seed)
    out: dict = {"stationary": {}, "transition": {}}
    thr = settings.stick_threshold * model.velocity_scale
    taus = stationary_taus(exp, settings)
    fn = StationaryValues(burn_in=settings.stationary_burn_in, threshold=thr,
                          force=model.force, taus=tuple(taus))
    v0_mc = sample_stationary(m_eff, MC_STATIONARY_REPLICAS, seeds.mc_stationary_v0)
    held, white = held_noise_pair(m_eff, v0=v0_mc, t_end=settings.stationary_t_end,
                                  replicas=v0_mc.size, seed=seeds.mc_stationary,
                                  noise_dt=noise_dt["stationary"], sample_dt=exp.sample_dt)
    scale = math.sqrt(v0_mc.size / settings.stationary_replicas)
    out["stationary"] = _in_se(jackknife_difference(fn, held, white), jackknife(fn, white), scale)
    times = list(exp.histogram_times)
    for i, v0 in enumerate(exp.v0):
        held, white = held_noise_pair(m_eff, v0=v0, t_end=max(times), replicas=MC_REPLICAS,
                                      seed=seeds.mc_transition(i),
                                      noise_dt=noise_dt["transition"], sample_dt=exp.sample_dt)
        def tf(e, v0=v0):
            return transition_values(e, v0, times)
        terms = _in_se(jackknife_difference(tf, held, white), jackknife(tf, white),
                       math.sqrt(MC_REPLICAS / exp.replicas))
        out["transition"].update({f"v0={v0:g} {k}": x for k, x in terms.items()})
    return out


def ngspice_cpu(exp, spec, noise_dt: float, *, v0, replicas: int, t_end: float) -> float:
    spec = spec.replace(reltol=1e-4, trtol=7.0, method="trap", noise_dt=noise_dt)
    c0 = children_cpu()
    simulate(exp.model, v0=v0, t_end=t_end, replicas=replicas, seed=8101, sample_dt=exp.sample_dt,
             circuit=spec, replicas_per_deck=replicas, store=False, workers=1, progress=False)
    return children_cpu() - c0


def _worst(terms: dict) -> tuple[str, float]:
    k = max(terms, key=lambda k: terms[k] if math.isfinite(terms[k]) else -1.0)
    return k, terms[k]


CHECK_COST = 5.0  # a check's ngspice cost per unit replica-time against its nominal run's


def replica_time(exp) -> dict:
    """Replica-time of each run kind of the full report (checks weighted by CHECK_COST)."""
    st = exp.report
    return {"stationary": st.stationary_replicas * st.stationary_t_end
            + CHECK_COST * st.check_replicas * st.stationary_t_end,
            "transition": len(exp.v0) * exp.replicas * exp.t_end
            + CHECK_COST * st.check_replicas * exp.t_end}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--experiments", default="stick,slip,work")
    ap.add_argument("--divisors", default="1,2,4")
    ap.add_argument("--smoothing", default="")
    ap.add_argument("--replicas", type=int, default=32)
    ap.add_argument("--t-end", type=float, default=10.0)
    ap.add_argument("--no-ngspice", action="store_true")
    args = ap.parse_args(argv)
    divisors = [int(x) for x in args.divisors.split(",")]
    print("experiment  divisor  smoothing  hold(stat/trans)  stationary: worst term/SE "
          "(stick fraction)  transition: worst term/SE   ngspice CPU stationary deck, report")
    paper: dict = {}   # (smoothing index, divisor) -> [cost, cost at divisor 1]
    for name in args.experiments.split(","):
        exp = load_experiment(standard_circuit(name))
        mapping = map_model(exp.model, exp.spec)
        hold = mapping.noise_dt
        v0s = np.asarray(sample_stationary(mapping.model_effective, args.replicas, 3), dtype=float)
        smooths = ([float(s) for s in args.smoothing.split(",")] if args.smoothing
                   else [mapping.smoothing])
        rt = replica_time(exp)
        base = None
        if not args.no_ngspice:
            # today's transition deck and stationary deck (divisor 1, the shipped smoothing)
            per = args.replicas * args.t_end
            base = {"transition": ngspice_cpu(exp, exp.spec, hold, v0=exp.v0[0],
                                              replicas=args.replicas, t_end=args.t_end) / per,
                    "stationary": ngspice_cpu(exp, exp.spec, hold, v0=v0s,
                                              replicas=args.replicas, t_end=args.t_end) / per}
        for si, s in enumerate(smooths):
            spec = exp.spec.replace(smoothing=s, allow_bias=True)
            for k in divisors:
                dts = {"stationary": hold / k, "transition": hold}
                t0 = time.process_time()
                terms = bias_in_se(exp, spec, dts)
                mc = time.process_time() - t0
                ks, xs = _worst(terms["stationary"])
                kt, xt = _worst(terms["transition"])
                stick = terms["stationary"].get("stick fraction", math.nan)
                cost = ""
                if base is not None:
                    cs = ngspice_cpu(exp, spec, dts["stationary"], v0=v0s,
                                     replicas=args.replicas, t_end=args.t_end)
                    ct = (ngspice_cpu(exp, spec, hold, v0=exp.v0[0], replicas=args.replicas,
                                      t_end=args.t_end) / (args.replicas * args.t_end)
                          if s != mapping.smoothing else base["transition"])
                    now = (rt["stationary"] * cs / (args.replicas * args.t_end)
                           + rt["transition"] * ct)

                    before = rt["stationary"] * base["stationary"] + rt["transition"] * base["transition"]
                    acc = paper.setdefault((si, k), [0.0, 0.0])
                    acc[0] += now
                    acc[1] += before
                    cost = (f"{cs:6.2f} s ({cs / (base['stationary'] * args.replicas * args.t_end):.2f}x)"
                            f", report {now / before:.2f}x")
                print(f"{name:6s}  {k:3d}  {s:6.3g}  {dts['stationary']:.4g}/{dts['transition']:.4g}"
                      f"  {xs:6.2f} ({ks}; stick {stick:.2f})  {xt:6.2f} ({kt})  {cost}"
                      f"  [MC {mc:.0f} s]", flush=True)
    for (si, k), (now, before) in sorted(paper.items()):
        print(f"all experiments: smoothing #{si}, divisor {k}: ngspice CPU of the full reports "
              f"{now / before:.2f}x that at divisor 1 (shipped smoothing)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
