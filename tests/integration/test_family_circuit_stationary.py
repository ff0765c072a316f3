"""Issue 9: circuit statistics of each extension against independent references at small
sizes (the committed circuits/*.toml parameters).

References written here: the stationary law p_s ~ exp(-gamma U) by quadrature with
U = v^2/(2 tau_m) + cubic v^4/4 + Delta |v| + (delta_s - Delta) v_s (1 - e^{-|v|/v_s}) - a v
(exact for the 1-D Gaussian members), and for the spring an Euler-Maruyama integration of
dv = (-v/tau_m - Delta sgn v - spring x + a) dt + sqrt(2/gamma) dW, dx = v dt from the same
initial state (window averages, so stationarity is not assumed).  Standard errors from the
spread of per-replica averages (replicas are independent); the allowed difference is
4 SE plus the mapping's budget terms for the quantity.
"""
import math

import numpy as np
import pytest

from analogue import simulate
from analogue.circuit.experiments import load_experiment

pytestmark = pytest.mark.slow


def exact_moments(model, thr=None):
    tau, d, a, g = model.tau_m, model.delta, model.a, model.gamma
    v = np.linspace(-6.0, 6.0, 600001)
    u = v * v / (2 * tau) + model.cubic * v**4 / 4 + d * np.abs(v) - a * v
    if model.stribeck is not None:
        ds, vs = model.stribeck
        u += (ds - d) * vs * (1 - np.exp(-np.abs(v) / vs))
    p = np.exp(-g * (u - u.min()))
    p /= np.trapezoid(p, v)
    mean = np.trapezoid(v * p, v)
    out = {"mean": mean, "var": np.trapezoid((v - mean) ** 2 * p, v)}
    if thr is not None:
        out["low"] = np.trapezoid(p * (v < thr), v)
    return out


def circuit_run(name, **changes):
    exp = load_experiment(name)
    spec = exp.spec.replace(**changes) if changes else exp.spec
    v0 = exp.initial_velocities()
    ens = simulate(exp.model, v0=v0, t_end=exp.t_end, replicas=v0.size, seed=exp.seed,
                   sample_dt=exp.sample_dt, circuit=spec, workers=1, store=False)
    return exp, ens


def compare(label, per_replica: dict, exact: dict, budget: dict):
    for key, vals in per_replica.items():
        se = vals.std(ddof=1) / math.sqrt(vals.size)
        diff = vals.mean() - exact[key]
        allowed = 4 * se + budget.get(key, 0.0) * abs(exact[key])
        print(f"{label} {key}: circuit {vals.mean():.4f} +- {se:.4f}, reference {exact[key]:.4f}, "
              f"z = {diff / se:.2f}")
        assert abs(diff) < allowed, (label, key)


@pytest.mark.parametrize("element", ["diode-network", "behavioural"])
def test_cubic_stationary(element):
    exp, ens = circuit_run("cubic", cubic_element=element)
    v = ens.v[:, ens.t >= exp.burn_in]
    per = {"mean": v.mean(axis=1), "var": ((v - v.mean()) ** 2).mean(axis=1)}
    bias = exp.mapping().bias if element == "diode-network" else {}
    budget = {"var": bias.get("cubic_variance", 0.0) + exp.mapping().bias["noise"]}
    compare(f"cubic[{element}]", per, exact_moments(exp.model), budget)


def test_stribeck_stationary_bimodal():
    """The velocity-weakening law's two modes: the fraction of time below v = 0.3 (the stuck
    mode) as well as mean and variance."""
    exp, ens = circuit_run("stribeck")
    v = ens.v[:, ens.t >= exp.burn_in]
    per = {"mean": v.mean(axis=1), "var": ((v - v.mean()) ** 2).mean(axis=1),
           "low": (v < 0.3).mean(axis=1)}
    ref = exact_moments(exp.model, thr=0.3)
    assert 0.2 < ref["low"] < 0.8  # genuinely bimodal at these parameters
    b = exp.mapping().bias
    compare("stribeck", per, ref, {"var": b["noise"], "low": b["smoothing"]})


def euler_spring(model, v0, t_end, burn_in, dt, replicas, seed):
    rng = np.random.default_rng(seed)
    v = np.full(replicas, v0, dtype=float)
    x = np.full(replicas, model.x0, dtype=float)
    n = round(t_end / dt)
    n0 = round(burn_in / dt)
    acc = {k: np.zeros(replicas) for k in ("v", "v2", "x", "x2", "stuck")}
    amp = math.sqrt(2 * dt / model.gamma)
    for i in range(n):
        f = -v / model.tau_m - model.delta * np.sign(v) - model.spring * x + model.a
        x = x + v * dt
        v = v + f * dt + amp * rng.standard_normal(replicas)
        if i + 1 >= n0:
            acc["v"] += v
            acc["v2"] += v * v
            acc["x"] += x
            acc["x2"] += x * x
            acc["stuck"] += np.abs(v) < 0.05
    k = n - n0 + 1
    return {key: val / k for key, val in acc.items()}


def test_spring_window_moments_vs_euler():
    exp, ens = circuit_run("spring")
    model = exp.model
    sel = ens.t >= exp.burn_in
    v = ens.v[:, sel]
    x = model.x0 + ens.x[:, sel]
    per = {"v": v.mean(axis=1), "v2": (v * v).mean(axis=1), "x": x.mean(axis=1),
           "x2": (x * x).mean(axis=1), "stuck": (np.abs(v) < 0.05).mean(axis=1)}
    ref_runs = euler_spring(model, exp.v0[0], exp.t_end, exp.burn_in, 1e-3, 2000, 7)
    ref = {k: float(np.mean(val)) for k, val in ref_runs.items()}
    # the reference's own SE adds in quadrature: fold it into the budget as 4 SE_ref/|ref|
    b = exp.mapping().bias
    budget = {k: 4 * float(np.std(val) / math.sqrt(val.size)) / max(abs(ref[k]), 1e-12)
              for k, val in ref_runs.items()}
    budget["v2"] += b["spring_leak_var_v"] + b["noise"]
    budget["x2"] += b["spring_leak_var_x"]
    budget["stuck"] += b["smoothing"]
    compare("spring", per, ref, budget)
    # the inductor readback is the same position up to the leak (tau_L = 300)
    assert exp.mapping().spring_leak_time == pytest.approx(300.0)


@pytest.mark.parametrize("name", ["cubic", "stribeck"])
def test_quadrature_matches_exact_theory(name):
    """This file's quadrature reference agrees with analogue.theory.exact, so the circuit's
    z-scores hold against either."""
    from analogue.theory import exact
    model = load_experiment(name).model
    mine, theirs = exact_moments(model), exact.stationary_moments(model)
    assert mine["mean"] == pytest.approx(theirs.mean, rel=1e-6)
    assert mine["var"] == pytest.approx(theirs.variance, rel=1e-6)


def test_spring_window_moments_vs_package_monte_carlo():
    """The same comparison against analogue.montecarlo.simulate_sde (the project's Monte
    Carlo for the family): window averages from the same initial state."""
    from analogue.montecarlo import simulate_sde
    exp, ens = circuit_run("spring")
    model = exp.model
    mc = simulate_sde(model, v0=exp.v0[0], t_end=exp.t_end, replicas=1000, seed=3,
                      sample_dt=exp.sample_dt)
    b = exp.mapping().bias
    out = {}
    for label, e in (("circuit", ens), ("mc", mc)):
        sel = e.t >= exp.burn_in
        v, x = e.v[:, sel], model.x0 + e.x[:, sel]
        out[label] = {"v2": (v * v).mean(axis=1), "x2": (x * x).mean(axis=1),
                      "stuck": (np.abs(v) < 0.05).mean(axis=1)}
    budget = {"v2": b["spring_leak_var_v"] + b["noise"], "x2": b["spring_leak_var_x"],
              "stuck": b["smoothing"]}
    for key in out["circuit"]:
        c, r = out["circuit"][key], out["mc"][key]
        se = math.hypot(c.std(ddof=1) / math.sqrt(c.size), r.std(ddof=1) / math.sqrt(r.size))
        diff = c.mean() - r.mean()
        print(f"spring vs montecarlo {key}: circuit {c.mean():.4f}, MC {r.mean():.4f}, z = {diff / se:.2f}")
        assert abs(diff) < 4 * se + budget[key] * abs(r.mean())
