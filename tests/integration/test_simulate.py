"""analogue.simulate: reproducibility, independence, noise-free motion, delivered noise,
stationary statistics against the exact law, Dask path, bad input.

Statistical checks use fixed seeds; standard errors come from the spread of per-replica time
averages (replicas are independent by construction, which is itself tested here), and every
tolerance is 4 standard errors plus the documented bias of the circuit (held noise:
noise_dt/(3 tau_m) of the variance; smoothing: the circuit is compared with the model it
implements, ``model_effective``, whose epsilon is stated).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

import analogue
from analogue import Model
from analogue.circuit import ngspice as ng
from analogue.circuit.simulate import deck_seeds, initial_velocities, time_grid
from conftest import SLIP_A12, STICK_A02

pytestmark = pytest.mark.requires_ngspice


def documented_bias(e, name="noise") -> float:
    """The relative bias the circuit mapping states for itself (meta["circuit"] table row
    ``bias_<name>``); held noise: the drop of the stationary variance from the noise hold."""
    rows = {row[0]: row[1] for row in e.meta["circuit"]}
    value = float(rows[f"bias_{name}"])
    assert 0 <= value < 0.05  # a correction, not a licence to pass anything
    return value


def run(model, **kw):
    kw.setdefault("store", False)
    kw.setdefault("progress", False)
    return analogue.simulate(model, **kw)


# -------------------------------------------------------------- exact values, by quadrature
def exact_moments(model: Model) -> dict:
    """Mean, variance and P(v > 0) of p_s = exp(-gamma U)/Z (eq. (6)) by adaptive
    quadrature on each half line (the density has a kink at 0 for epsilon = 0)."""
    w = 40 * model.velocity_scale
    c = model.potential_minimum()
    lo, hi = min(c - w, -w), max(c + w, w)
    log_z = model.log_normaliser()  # once: stationary_pdf would recompute it at every node
    def pdf(v):
        return math.exp(-model.gamma * float(model.potential(v)) - log_z)
    def q(f, a, b):
        return integrate.quad(lambda v: f(v) * pdf(v), a, b,
                              limit=400, epsabs=0, epsrel=1e-11)[0]
    def both(f):
        return q(f, lo, 0.0) + q(f, 0.0, hi)
    mean = both(lambda v: v)
    return {"norm": both(lambda v: 1.0), "mean": mean, "var": both(lambda v: (v - mean) ** 2),
            "m4": both(lambda v: (v - mean) ** 4), "p_pos": q(lambda v: 1.0, 0.0, hi)}


def check_iid_sample(v0, ex):
    """Mean, variance and P(v>0) of n iid draws against exact values, within 4 SE
    (SE of the sample variance from the exact fourth central moment)."""
    n = v0.size
    assert abs(v0.mean() - ex["mean"]) < 4 * math.sqrt(ex["var"] / n)
    assert abs(v0.var() - ex["var"]) < 4 * math.sqrt((ex["m4"] - ex["var"] ** 2) / n)
    assert abs((v0 > 0).mean() - ex["p_pos"]) < 4 * math.sqrt(ex["p_pos"] * (1 - ex["p_pos"]) / n)


def replica_estimates(v: np.ndarray) -> dict:
    """Pooled stationary mean, variance, P(v>0) with standard errors from independent
    replicas (mean and P: spread of per-replica averages; variance: jackknife over replicas)."""
    R = v.shape[0]
    m1, m2, pp = v.mean(1), (v ** 2).mean(1), (v > 0).mean(1)
    var = m2.mean() - m1.mean() ** 2
    loo_var = (m2.sum() - m2) / (R - 1) - ((m1.sum() - m1) / (R - 1)) ** 2
    se_var = math.sqrt((R - 1) / R * np.sum((loo_var - loo_var.mean()) ** 2))
    return {"mean": (m1.mean(), m1.std(ddof=1) / math.sqrt(R)), "var": (var, se_var),
            "p_pos": (pp.mean(), pp.std(ddof=1) / math.sqrt(R))}


# ------------------------------------------------------------------------ reproducibility
def test_same_seed_identical_different_seed_differs():
    kw = dict(v0=0.3, t_end=2.0, replicas=6, replicas_per_deck=4)
    a = run(STICK_A02, seed=3, **kw)
    b = run(STICK_A02, seed=3, workers=1, **kw)  # other scheduling, same numbers
    c = run(STICK_A02, seed=4, **kw)
    np.testing.assert_array_equal(a.v, b.v)
    np.testing.assert_array_equal(a.x, b.x)
    assert not np.allclose(a.v[:, 1:], c.v[:, 1:])
    assert a.meta["deck_seeds"] == deck_seeds(3, 2) and a.meta["deck_seeds"] != c.meta["deck_seeds"]
    assert a.meta["deck_replicas"] == [3, 3]
    # grid, units, initial values and position origin
    np.testing.assert_allclose(a.t, np.arange(201) * 0.01, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(a.v[:, 0], 0.3)
    np.testing.assert_array_equal(a.x[:, 0], 0.0)
    for key in ("model", "model_effective", "circuit", "seed", "deck_seeds", "ngspice_version",
                "deck_sha256", "wall_time", "store_keys"):
        assert key in a.meta
    assert a.meta["ngspice_version"] == ng.ngspice_version()
    assert len(set(a.meta["deck_sha256"])) == 2


def test_ensemble_meta_is_json_and_saves(tmp_path):
    import json
    e = run(STICK_A02, v0=0.1, t_end=0.5, replicas=2, seed=1)
    json.dumps(e.meta)
    e.save(tmp_path / "e.npz")
    back = analogue.Ensemble.load(tmp_path / "e.npz")
    np.testing.assert_array_equal(back.v, e.v)
    assert back.meta["deck_seeds"] == e.meta["deck_seeds"]
    assert back.meta["circuit_spec"]["coulomb"] == "diode-bridge"


def test_positions_integrate_velocities():
    e = run(SLIP_A12, v0=-0.5, t_end=3.0, replicas=3, seed=8, sample_dt=0.005)
    x_trap = np.concatenate([np.zeros((3, 1)),
                             np.cumsum(0.5 * (e.v[:, 1:] + e.v[:, :-1]) * e.dt, axis=1)], axis=1)
    # trapezoid on the output grid vs the circuit's integrator node: differences come from the
    # noise between samples, of order sqrt(dt/gamma) * sqrt(n) * dt
    assert np.max(np.abs(e.x - x_trap)) < 0.02
    assert np.max(np.abs(e.x[:, -1])) > 0.5  # not trivially zero


def test_stationary_initial_values_follow_p_s():
    """The v0="stationary" draw (before any circuit) has the exact stationary mean/variance."""
    m = STICK_A02.replace(epsilon=0.006)
    v0 = initial_velocities(m, "stationary", 20000, seed=1)
    check_iid_sample(v0, exact_moments(m))
    np.testing.assert_array_equal(v0, initial_velocities(m, "stationary", 20000, seed=1))


@pytest.mark.parametrize("epsilon", [0.0, 0.006])
def test_stationary_sampler_slip(epsilon):
    """The exact sampler behind v0="stationary" in the slip regime (kinked and smooth law)."""
    from analogue.circuit.simulate import _sample_stationary
    m = SLIP_A12.replace(epsilon=epsilon)
    v0 = _sample_stationary(m, 20000, np.random.default_rng(4))
    check_iid_sample(v0, exact_moments(m))


# ------------------------------------------------------------------- the recorded noise
def test_recorded_noise_drove_the_circuit():
    """ensemble.noise holds the standard normals of each hold; an independent integrator of
    dv = -U'(v) dt + sqrt(2 h/gamma) z_k (per hold h, held constant, 20 Euler substeps) driven by
    them retraces the circuit's paths; shifting the noise by one hold does not."""
    R, T = 4, 5.0
    e = run(STICK_A02, v0=0.5, t_end=T, replicas=R, seed=2)
    z = e.noise
    assert z is not None
    with pytest.warns(DeprecationWarning, match="ensemble.noise"):
        e_old, z_old = run(STICK_A02, v0=0.5, t_end=T, replicas=R, seed=2, return_noise=True)
    np.testing.assert_array_equal(z_old, z)  # the deprecated form still gives the same numbers
    np.testing.assert_array_equal(e_old.v, e.v)
    h = e.meta["noise_dt"]
    assert z.shape == (R, round(T / h))
    n = z.size
    assert abs(z.mean()) < 4 / math.sqrt(n) and abs(z.std() - 1) < 4 / math.sqrt(2 * n)
    eff = Model(**e.meta["model_effective"])
    every = round(h / e.dt)
    assert every * e.dt == pytest.approx(h)

    def integrate_held(zz):
        v, path = np.full(R, 0.5), [np.full(R, 0.5)]
        for k in range(zz.shape[1]):
            xi = math.sqrt(2 / (STICK_A02.gamma * h)) * zz[:, k]
            for _ in range(20):
                v = v + (eff.drift(v) + xi) * h / 20
            path.append(v)
        return np.array(path).T

    err = np.max(np.abs(integrate_held(z) - e.v[:, ::every]))
    assert err < 0.01 * STICK_A02.velocity_scale  # Euler O(h/20) and the solver's reltol
    shifted = np.max(np.abs(integrate_held(np.roll(z, 1, axis=1)) - e.v[:, ::every]))
    assert shifted > 10 * err


# --------------------------------------------------------------------------- noise-free
@pytest.mark.parametrize("model,v0", [(STICK_A02, 1.0), (SLIP_A12, -1.0)])
def test_noise_free_circuit_follows_deterministic_motion(model, v0):
    """gamma = 1e8 makes the noise negligible (deviation <= sqrt(2 t/gamma) ~ 2.4e-4); the
    circuit then follows the noise-free ODE of the model it implements, and the sgn-law
    facts (stick time t_a of eq. (31), slip velocity v_ss of eq. (14)) up to the smoothing."""
    m = model.replace(gamma=1e8)
    T, dt = 3.0, 0.001
    e = run(m, v0=v0, t_end=T, replicas=2, seed=1, sample_dt=dt,
            circuit={"smoothing": 0.5, "allow_bias": True})
    eff = Model(**e.meta["model_effective"])
    assert 0 < eff.epsilon <= 0.5 * m.velocity_scale * (1 + 1e-9)
    noise = 6 * math.sqrt(2 * T / m.gamma)  # 6 sigma of the pure-diffusion bound
    solver = 1e-3  # reltol 1e-4 over a few tau_m, interpolated at dt = 1e-3
    det = eff.deterministic(v0, e.t)
    assert np.max(np.abs(e.v - det)) < noise + solver
    if model.regime == "stick":
        b = (m.delta - m.a) * m.tau_m
        thr = 1e-3  # >> epsilon = 5e-5, where tanh(v/eps) = 1: the sgn law applies above it
        first = e.t[np.argmax(e.v < thr, axis=1)]
        t_thr = m.tau_m * math.log((v0 + b) / (thr + b))  # sgn law reaching thr
        slope = m.delta - m.a  # |dv/dt| near the stick
        tol = 2 * dt + noise / slope
        assert np.all(np.abs(first - t_thr) < tol)
        assert np.all(np.abs(first - m.stick_time(v0)) < tol + (m.stick_time(v0) - t_thr))
        assert np.max(np.abs(e.v[:, e.t > m.stick_time(v0) + 0.5])) < 20 * eff.epsilon + noise
    else:
        v_ss = m.attractor
        assert np.all(np.abs(e.v[:, -1] - det[-1]) < noise + solver)
        # the sgn-law path (epsilon = 0) differs from the smoothed one by O(epsilon) at the kink
        np.testing.assert_allclose(e.v, np.broadcast_to(m.deterministic(v0, e.t), e.v.shape),
                                   rtol=0, atol=noise + solver + 10 * eff.epsilon)
        assert abs(det[-1] - v_ss) < 0.06  # e^{-3}-close to v_ss = (a - Delta) tau_m


# ------------------------------------------------------------- Delta = 0 through simulate
def test_zero_delta_runs_as_ou_with_default_circuit():
    """Delta = 0 with the default circuit spec (diode bridge) used to fail in build_deck; the
    circuit is now the RC (Ornstein-Uhlenbeck) circuit without a Coulomb element.  From a fixed
    v0 the ensemble mean follows the exact OU mean a tau + (v0 - a tau) e^{-t/tau} (held noise
    has zero mean, so no bias) within 4 SE at each of six times, and the final variance the
    exact (tau/gamma)(1 - e^{-2t/tau}) within 4 SE of the sample variance plus the documented
    held-noise bias."""
    m = Model(tau_m=1.0, delta=0.0, a=0.5, gamma=10.0)
    R, T, v0 = 64, 3.0, 2.0
    e = run(m, v0=v0, t_end=T, replicas=R, seed=5)
    rows = {row[0]: row[1] for row in e.meta["circuit"]}
    assert rows["coulomb_elements"] == 0.0 and rows["epsilon"] == 0.0
    assert Model(**e.meta["model_effective"]) == m
    tau, var0 = m.tau_m, m.tau_m / m.gamma
    for t in (0.5, 1.0, 1.5, 2.0, 2.5, 3.0):
        k = int(round(t / e.dt))
        mean = m.a * tau + (v0 - m.a * tau) * math.exp(-t / tau)
        se = e.v[:, k].std(ddof=1) / math.sqrt(R)
        assert abs(e.v[:, k].mean() - mean) < 4 * se, (t, e.v[:, k].mean(), mean, se)
        np.testing.assert_allclose(mean, m.deterministic(v0, t), rtol=1e-12)
    var_t = var0 * (1 - math.exp(-2 * T / tau))
    est = e.v[:, -1].var(ddof=1)
    se = var_t * math.sqrt(2.0 / (R - 1))  # Gaussian sample variance
    assert abs(est - var_t) < 4 * se + var_t * documented_bias(e), (est, var_t, se)
    # the test can tell friction apart: with Delta = 0.7 the noise-free motion from v0 = 2
    # has stuck at 0 by t = 3, more than 10 SE of the mean away from what the circuit does
    se_mean = e.v[:, -1].std(ddof=1) / math.sqrt(R)
    assert abs(e.v[:, -1].mean() - Model(1.0, 0.7, 0.5, 10.0).deterministic(v0, T)) > 10 * se_mean


# --------------------------------------------------------------------- delivered noise (OU)
@pytest.mark.slow
def test_delivered_noise_intensity_delta_zero():
    """Delta = a = 0: the circuit is an OU process.  Stationary variance tau_m/gamma (minus
    the documented held-noise bias noise_dt/(3 tau_m)) and the increment variance over a short
    lag s, 2 (tau_m/gamma)(1 - e^{-s/tau_m}) ~ 2 D s with D = 1/gamma."""
    m = Model(tau_m=1.0, delta=0.0, a=0.0, gamma=10.0)
    R, T = 24, 50.0
    # (default circuit spec: with Delta = 0 the mapping omits the Coulomb element)
    e = run(m, v0="stationary", t_end=T, replicas=R, seed=21, replicas_per_deck=12)
    var0 = m.tau_m / m.gamma
    # held noise, OU: the variance dips within each hold by 2 s/tau_m - 2 s^2/(h tau_m)
    # (s the time since the hold began), i.e. by h/(3 tau_m) on average: 1/300 by default
    assert documented_bias(e) == pytest.approx(0.01 / 3, rel=1e-6)
    bias = var0 * documented_bias(e)
    m2 = (e.v ** 2).mean(1)
    est, se = m2.mean(), m2.std(ddof=1) / math.sqrt(R)
    assert abs(est - var0) < 4 * se + bias, (est, var0, se)
    assert se < 0.06 * var0
    lag = 10
    s = lag * e.dt
    inc = ((e.v[:, lag:] - e.v[:, :-lag]) ** 2).mean(1)
    expect = 2 * var0 * (1 - math.exp(-s / m.tau_m))
    est, se = inc.mean(), inc.std(ddof=1) / math.sqrt(R)
    assert abs(est - expect) < 4 * se + 2 * bias, (est, expect, se)
    assert se < 0.03 * expect
    # position: Var x(t) of the OU integral, exact for stationary start:
    # 2 var0 tau (t - tau (1 - e^{-t/tau}))
    t = e.t[-1]
    var_x = 2 * var0 * m.tau_m * (t - m.tau_m * (1 - math.exp(-t / m.tau_m)))
    vx = e.x[:, -1].var(ddof=1)
    assert abs(vx - var_x) < 4 * var_x * math.sqrt(2 / (R - 1))


# ------------------------------------------------------------- stationary statistics
@pytest.fixture(scope="module")
def slip_run():
    return run(SLIP_A12, v0="stationary", t_end=80.0, replicas=16, seed=7, replicas_per_deck=4)


@pytest.fixture(scope="module")
def stick_run():
    return run(STICK_A02, v0="stationary", t_end=40.0, replicas=24, seed=9, replicas_per_deck=12)


def _check_moments(e, model):
    eff = Model(**e.meta["model_effective"])
    assert eff.replace(epsilon=0) == model and eff.epsilon > 0
    ex = exact_moments(eff)
    assert abs(ex["norm"] - 1) < 1e-8
    est = replica_estimates(e.v)
    var_bias = ex["var"] * documented_bias(e)  # held noise (mapping's stated estimate)
    for key, bias in (("mean", 0.0), ("var", var_bias), ("p_pos", 0.0)):
        value, se = est[key]
        assert abs(value - ex[key]) < 4 * se + bias, (key, value, ex[key], se)
    # The circuit's epsilon shifts the exact values only slightly from the sgn law's:
    ex0 = exact_moments(model)
    return ex, ex0, est


@pytest.mark.slow
@pytest.mark.xdist_group("circuit-slip-run")  # share the module fixture under -n 2
def test_stationary_moments_slip(slip_run):
    ex, ex0, est = _check_moments(slip_run, SLIP_A12)
    assert est["mean"][1] < 0.02 * ex["mean"]  # the test has power
    assert abs(ex["mean"] - ex0["mean"]) < 0.01 * ex0["mean"]


@pytest.mark.slow
def test_stationary_moments_stick(stick_run):
    ex, ex0, est = _check_moments(stick_run, STICK_A02)
    assert est["var"][1] < 0.06 * ex["var"]
    assert abs(ex["p_pos"] - ex0["p_pos"]) < 0.01


@pytest.mark.slow
@pytest.mark.xdist_group("circuit-slip-run")
def test_replicas_are_independent(slip_run):
    """Cross-correlations of the stationary velocity series of different replicas (same and
    different decks) vanish within 4 standard errors; Bartlett: Var r_ij = (1/N) sum_k rho(k)^2
    with rho the (pooled) autocorrelation."""
    v = slip_run.v
    R, N = v.shape
    u = (v - v.mean(1, keepdims=True)) / v.std(1, keepdims=True)
    corr = u @ u.T / N
    f = np.fft.rfft(u, n=2 * N, axis=1)
    acf = np.fft.irfft(np.abs(f) ** 2, axis=1)[:, :N].mean(0) / np.arange(N, 0, -1)
    L = int(10 * SLIP_A12.tau_m / slip_run.dt)
    se = math.sqrt((1 + 2 * np.sum(acf[1:L] ** 2)) / N)
    off = corr[np.triu_indices(R, k=1)]
    assert se < 0.15  # about 100 effective samples: a correlation above 0.6 could not hide
    assert np.max(np.abs(off)) < 4 * se, (np.max(np.abs(off)), se)
    # Under independence r_ij and r_ik are uncorrelated, so mean z^2 over the pairs is 1 within
    # sqrt(2/n_pairs): checks the Bartlett error itself and catches a weak common correlation.
    z2 = np.mean((off / se) ** 2)
    assert abs(z2 - 1) < 4 * math.sqrt(2 / off.size), z2
    np.testing.assert_allclose(np.diag(corr), 1.0)


# -------------------------------------------------------------------------------- Dask
@pytest.mark.slow
def test_dask_local_cluster_matches_local():
    distributed = pytest.importorskip("distributed")
    kw = dict(v0=0.5, t_end=1.0, replicas=5, seed=12, replicas_per_deck=2)
    local = run(STICK_A02, **kw)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, host="127.0.0.1",
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        remote = run(STICK_A02, scheduler=client, **kw)
        by_address = run(STICK_A02, scheduler=cluster.scheduler_address, **kw)
    for other in (remote, by_address):
        np.testing.assert_array_equal(local.v, other.v)
        np.testing.assert_array_equal(local.x, other.x)
        assert other.meta["executor"] == "dask"


def test_injected_executor_matches_local():
    """executor= (any concurrent.futures.Executor the caller owns) gives the same arrays as
    the default pool, and is left open."""
    import concurrent.futures as cf
    kw = dict(v0=0.5, t_end=0.5, replicas=3, seed=12, replicas_per_deck=2)
    local = run(STICK_A02, **kw)
    with cf.ThreadPoolExecutor(2) as pool:
        injected = run(STICK_A02, executor=pool, **kw)
        assert pool.submit(int, 7).result() == 7
    np.testing.assert_array_equal(local.v, injected.v)
    np.testing.assert_array_equal(local.x, injected.x)
    assert injected.meta["executor"] == "ThreadPoolExecutor"


# ---------------------------------------------------------------------------- bad input
BASE = dict(v0=0.0, t_end=1.0, replicas=2, seed=0)


@pytest.mark.parametrize("change,name", [
    ({"replicas": 0}, "replicas"), ({"replicas": 2.5}, "replicas"), ({"seed": -1}, "seed"),
    ({"seed": "x"}, "seed"), ({"t_end": 0.0}, "t_end"), ({"t_end": float("nan")}, "t_end"),
    ({"sample_dt": -0.1}, "sample_dt"), ({"sample_dt": 2.0}, "sample_dt"),
    ({"sample_dt": 0.3}, "sample_dt"), ({"v0": "hot"}, "v0"), ({"v0": [1.0, 2.0, 3.0]}, "v0"),
    ({"v0": [0.0, np.inf]}, "v0"), ({"workers": 0}, "workers"), ({"circuit": 3}, "circuit"),
    ({"circuit": {"nonsense": 1}}, "circuit"), ({"replicas_per_deck": 0}, "replicas_per_deck"),
    ({"timeout": -1}, "timeout"), ({"store": 3.5}, "store"), ({"progress": "yes"}, "progress"),
    ({"scheduler": "localhost"}, "scheduler"),
    ({"return_noise": 1}, "return_noise"),
])
def test_bad_input_names_parameter(change, name):
    kw = {**BASE, **change}
    with pytest.raises(ValueError, match=name):
        analogue.simulate(STICK_A02, store=False, progress=False, **kw) if "store" not in change \
            and "progress" not in change else analogue.simulate(STICK_A02, **kw)


def test_unknown_keyword_is_a_type_error():
    # the signature is explicit (no **kwargs): Python names the unknown keyword itself
    with pytest.raises(TypeError, match="colour"):
        analogue.simulate(STICK_A02, store=False, progress=False, colour="red", **BASE)


def test_bad_model_and_grid():
    with pytest.raises(ValueError, match="model"):
        analogue.simulate({"tau_m": 1}, **BASE)
    with pytest.raises(ValueError, match="t_end"):
        time_grid(1.0, 0.3)
    np.testing.assert_allclose(time_grid(1.0, 0.25), [0, 0.25, 0.5, 0.75, 1.0])


def test_missing_ngspice_through_simulate(monkeypatch, tmp_path):
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(ng.NgspiceNotFoundError, match="apt-get install ngspice"):
        analogue.simulate(STICK_A02, store=False, progress=False, **BASE)


def test_records_are_attached_to_the_ensemble():
    """ensemble.records carries the spring readback (x_spring, same grid as v); the deprecated
    return_records=True still returns the same dict beside the ensemble."""
    from analogue.circuit import CircuitSpec
    model = Model(tau_m=3.0, delta=0.0, a=0.3, gamma=1e12, spring=1.0, x0=1.0)
    kw = dict(v0=0.0, t_end=2.0, replicas=2, seed=3, sample_dt=0.05, workers=1,
              circuit=CircuitSpec(allow_bias=True))
    ens = run(model, **kw)
    assert ens.records is not None and ens.records["x_spring"].shape == ens.v.shape
    np.testing.assert_allclose(ens.records["x_spring"][:, 0], 1.0, atol=1e-6)  # x(0) = x0
    with pytest.warns(DeprecationWarning, match="ensemble.records"):
        old, rec = run(model, return_records=True, **kw)
    np.testing.assert_array_equal(rec["x_spring"], ens.records["x_spring"])
    assert run(STICK_A02, v0=0.0, t_end=0.5, replicas=2, seed=1).records is None
