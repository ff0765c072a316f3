"""SDE Monte Carlo reference: reproducibility, given noise, OU exactness, stationary law."""
import math

import numpy as np
import pytest

from analogue import Ensemble, Model
from analogue.montecarlo import default_dt, simulate_sde, standard_noise
from analogue.theory import exact


def coarsen(noise):
    """Standard normals of the Wiener increments over pairs of steps (common random numbers)."""
    return (noise[:, 0::2] + noise[:, 1::2]) / math.sqrt(2.0)


def test_same_seed_identical_different_seed_different():
    m = Model(1.0, 0.7, 0.2, 10.0)
    kw = dict(v0=0.5, t_end=0.5, replicas=50, dt=0.005)
    e1 = simulate_sde(m, seed=7, **kw)
    e2 = simulate_sde(m, seed=7, **kw)
    e3 = simulate_sde(m, seed=8, **kw)
    assert isinstance(e1, Ensemble)
    assert np.array_equal(e1.v, e2.v) and np.array_equal(e1.x, e2.x)
    assert not np.array_equal(e1.v, e3.v)
    assert e1.meta["source"] == "sde" and e1.meta["seed"] == 7 and e1.meta["dt"] == 0.005
    assert e1.meta["scheme"] == "exponential" and e1.meta["model"] == m.as_dict()
    em = simulate_sde(m, seed=7, scheme="euler-maruyama", **kw)
    assert em.meta["scheme"] == "euler" and np.array_equal(em.v, simulate_sde(m, seed=7, scheme="euler", **kw).v)


@pytest.mark.parametrize("scheme", ["exponential", "euler"])
@pytest.mark.parametrize("v0", [0.3, "stationary"])
def test_given_noise_reproduces_seeded_run(scheme, v0):
    m = Model(1.0, 0.7, 1.1, 10.0, epsilon=0.05)
    kw = dict(v0=v0, t_end=0.4, replicas=30, dt=0.002, sample_dt=0.01, scheme=scheme)
    seeded = simulate_sde(m, seed=123, **kw)
    noise = standard_noise(123, 30, 200)
    given = simulate_sde(m, seed=123, noise=noise, **kw)
    assert np.array_equal(seeded.v, given.v) and np.array_equal(seeded.x, given.x)
    assert given.meta["noise"] == "given"
    # and the noise really drives the run
    other = simulate_sde(m, seed=123, noise=noise[::-1], **kw)
    assert not np.array_equal(other.v, given.v)


def test_euler_step_by_hand_and_trapezoid_positions():
    m = Model(0.8, 0.5, 0.3, 4.0)
    dt, n = 0.01, 5
    noise = np.array([[0.3, -1.2, 2.0, 0.1, -0.4], [1.0, 1.0, -2.5, 0.0, 0.7]])
    e = simulate_sde(m, v0=[0.05, -0.2], t_end=n * dt, replicas=2, dt=dt, sample_dt=dt,
                     noise=noise, scheme="euler")
    v = np.array([0.05, -0.2])
    vs = [v]
    for k in range(n):
        v = v + (m.a - v / m.tau_m - m.delta * np.sign(v)) * dt + math.sqrt(2 * dt / m.gamma) * noise[:, k]
        vs.append(v)
    vs = np.array(vs).T
    assert e.v == pytest.approx(vs, rel=1e-13, abs=1e-15)
    x = np.concatenate([np.zeros((2, 1)), np.cumsum(0.5 * dt * (vs[:, 1:] + vs[:, :-1]), axis=1)], axis=1)
    assert e.x == pytest.approx(x, rel=1e-12, abs=1e-15)
    assert e.t == pytest.approx(dt * np.arange(n + 1))


def test_exponential_scheme_is_exact_for_ornstein_uhlenbeck():
    """Delta = 0: the exponential step has no time-step error even for a coarse dt, so mean and
    variance at t agree with the OU closed forms within 4 standard errors."""
    tau, a, gamma, v0 = 1.0, 0.4, 5.0, 1.5
    m = Model(tau, 0.0, a, gamma)
    n = 40_000
    e = simulate_sde(m, v0=v0, t_end=1.0, replicas=n, seed=3, dt=0.1, sample_dt=0.5)
    for t in (0.5, 1.0):
        mu = v0 * math.exp(-t / tau) + a * tau * (1 - math.exp(-t / tau))
        var = tau / gamma * (1 - math.exp(-2 * t / tau))
        v = e.at(t)
        assert abs(v.mean() - mu) < 4 * math.sqrt(var / n)
        assert abs(v.var() - var) < 4 * var * math.sqrt(2.0 / n)


def _stationary_run(m, replicas, dt, t_end, seed, noise=None):
    return simulate_sde(m, v0="stationary", t_end=t_end, replicas=replicas, seed=seed, dt=dt,
                        sample_dt=t_end, noise=noise).v[:, -1]


@pytest.mark.slow
@pytest.mark.parametrize("a,eps", [(0.2, 0.0), (1.2, 0.0), (0.3, 0.05)])
def test_stationary_mc_matches_exact_moments(a, eps):
    """Started from exact stationary samples and run for 1.5 tau_m, the integrator keeps the
    law: mean, variance and P(v > 0) of the independent final values within 4 SE.

    Honesty of the comparison: the time-step bias is measured with common random numbers
    (the same Wiener paths at dt and 2 dt; weak order 1, so bias(dt) ~ est(dt) - est(2 dt))
    and must be below one standard error of the main comparison.
    """
    m = Model(1.0, 0.7, a, 10.0, epsilon=eps)
    dt, t_end, n = 1e-3, 1.5, 30_000
    s = exact.stationary_moments(m)
    v = _stationary_run(m, n, dt, t_end, seed=2024)
    se_mean = math.sqrt(s.variance / n)
    d2 = (v - s.mean) ** 2
    se_var = math.sqrt(np.var(d2) / n)
    se_p = math.sqrt(s.p_positive * s.p_negative / n)
    assert abs(v.mean() - s.mean) < 4 * se_mean
    assert abs(d2.mean() - s.variance) < 4 * se_var
    assert abs((v > 0).mean() - s.p_positive) < 4 * se_p

    n_b, steps = 4000, int(round(t_end / dt))
    noise = standard_noise(99, n_b, steps)
    fine = _stationary_run(m, n_b, dt, t_end, seed=99, noise=noise)
    coarse = _stationary_run(m, n_b, 2 * dt, t_end, seed=99, noise=coarsen(noise))
    assert abs(fine.mean() - coarse.mean()) < se_mean
    assert abs(fine.var() - coarse.var()) < se_var
    assert abs((fine > 0).mean() - (coarse > 0).mean()) < se_p


@pytest.mark.slow
def test_position_variance_grows_as_green_kubo_predicts():
    """Var x(T) = 2 int_0^T (T - s) C(s) ds with the exact autocorrelation (-> 2 D_x T)."""
    m = Model(1.0, 0.7, 0.3, 10.0)
    T, n = 4.0, 20_000
    e = simulate_sde(m, v0="stationary", t_end=T, replicas=n, seed=77, dt=2e-3, sample_dt=T)
    lags = np.linspace(0.0, T, 2001)
    c = exact.autocorrelation(m, lags)
    from scipy.integrate import simpson
    var_x = 2 * simpson((T - lags) * c, x=lags)
    x = e.x[:, -1]
    dx2 = (x - x.mean()) ** 2
    assert abs(dx2.mean() - var_x) < 4 * math.sqrt(np.var(dx2) / n)
    assert var_x < 2 * exact.stationary_moments(m).diffusion * T  # approach from below (C > 0)


def test_default_time_grid():
    m = Model(1.0, 0.7, 0.2, 10.0)
    e = simulate_sde(m, v0=0.0, t_end=3.0, replicas=2, seed=1)
    assert e.meta["dt"] <= default_dt(m) * (1 + 1e-12)
    assert e.t[-1] == pytest.approx(3.0) and e.t.size <= 1001
    k = e.meta["sample_dt"] / e.meta["dt"]
    assert k == pytest.approx(round(k))
    e = simulate_sde(m, v0=0.0, t_end=1.0, replicas=2, seed=1, sample_dt=0.25)
    assert e.t == pytest.approx([0, 0.25, 0.5, 0.75, 1.0])
    # the default step resolves the kink time 2/(gamma (Delta+|a|)^2) at large gamma
    assert default_dt(Model(1.0, 0.7, 0.2, 1000.0)) <= 2 / (1000 * 0.9 ** 2) / 50 * (1 + 1e-12)
    assert default_dt(Model(1.0, 0.7, 0.2, 10.0, epsilon=1e-3)) <= 0.1 * 1e-3 / 0.7


@pytest.mark.parametrize("kw,needle", [
    (dict(t_end=-1.0), "t_end"),
    (dict(replicas=0), "replicas"),
    (dict(replicas=2.5), "replicas"),
    (dict(dt=0.003), "t_end.*multiple of dt"),
    (dict(dt=0.01, sample_dt=0.015), "sample_dt.*multiple of dt"),
    (dict(sample_dt=0.3), "t_end.*multiple of sample_dt"),
    (dict(sample_dt=2.0), "sample_dt"),
    (dict(scheme="rk4"), "scheme"),
    (dict(v0="equilibrium"), "v0"),
    (dict(v0=[1.0, 2.0, 3.0]), "v0"),
    (dict(v0=np.nan), "v0"),
    (dict(noise=np.zeros((4, 7))), "noise must have shape"),
    (dict(seed=-1), "seed"),
    (dict(seed="abc"), "seed"),
])
def test_bad_arguments_name_the_parameter(kw, needle):
    m = Model(1.0, 0.7, 0.2, 10.0)
    args = dict(v0=0.1, t_end=1.0, replicas=4, seed=1, dt=0.01)
    args.update(kw)
    with pytest.raises(ValueError, match=needle):
        simulate_sde(m, **args)
