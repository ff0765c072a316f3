"""Work large deviations of the paper (section V): rate function (eq. (64)), fluctuation relation
(eq. (67)) and work-optimal paths (eqs. (57), (58), (60)).  Brute-force cross-checks of the
paths are in test_weak_noise_bruteforce.py."""
import math

import numpy as np
import pytest

from analogue import Model
from analogue.theory.weak_noise_work import (fluctuation_relation, rate_function,
                                             work_optimal_path)

FIG8 = Model(tau_m=1.0, delta=1.0, a=0.5, gamma=10.0)  # the paper's Figs. 7-9 (m = 1)


# ------------------------------------------------------------------------ rate function

def test_rate_function_values_by_hand():
    # tau_m = m = Delta = 1, a = 0.5: v_w = w/(m a) = 2 w
    assert rate_function(FIG8, 2.0) == pytest.approx((4.0 + 1.0 - 0.5) ** 2 / 4)
    assert rate_function(FIG8, -1.0) == pytest.approx((-2.0 - 1.0 - 0.5) ** 2 / 4)
    heavy = Model(tau_m=2.0, delta=0.3, a=0.4, gamma=1.0, mass=3.0)  # F = 1.2
    w = 0.9
    assert rate_function(heavy, w) == pytest.approx((w / (3.0 * 0.4 * 2.0) + 0.3 - 0.4) ** 2 / 4)


def test_rate_function_is_vectorised_and_returns_float_for_scalars():
    w = np.linspace(-3, 3, 13).reshape(13, 1)
    out = rate_function(FIG8, w)
    assert out.shape == (13, 1)
    assert np.allclose(out[:, 0], [rate_function(FIG8, x) for x in w[:, 0]])
    assert isinstance(rate_function(FIG8, 1.0), float)


@pytest.mark.parametrize("a", [0.3, 0.5, 1.5, -0.5, -1.5])
def test_jump_at_zero_is_a_delta_and_value_at_zero_is_lower_semicontinuous(a):
    m = FIG8.replace(a=a)
    h = 1e-12
    right, left, at0 = rate_function(m, h * m.force), rate_function(m, -h * m.force), rate_function(m, 0.0)
    # eq. (64): one-sided limits (Delta -+ a)^2/4 on the sides v -> 0+- ; the jump is |a| Delta
    assert right == pytest.approx((m.delta - a) ** 2 / 4, abs=1e-9)
    assert left == pytest.approx((m.delta + a) ** 2 / 4, abs=1e-9)
    assert abs(right - left) == pytest.approx(abs(a) * m.delta, abs=1e-9)
    # Filippov value: the cheapest way of holding v = 0; never above either side (l.s.c.)
    assert at0 == pytest.approx(max(abs(a) - m.delta, 0.0) ** 2 / 4)
    assert at0 <= min(left, right) + 1e-9


def test_rate_function_vanishes_only_at_the_deterministic_work_rate():
    slip = FIG8.replace(a=1.5)  # v_ss = (a - Delta) tau_m = 0.5
    w_ss = slip.force * slip.attractor
    assert rate_function(slip, w_ss) == pytest.approx(0.0, abs=1e-15)
    w = np.linspace(-3, 3, 601)
    assert np.all(rate_function(slip, w[np.abs(w - w_ss) > 1e-9]) > 0)
    # stick: the object is at rest, zero work, zero cost only there
    assert rate_function(FIG8, 0.0) == 0.0
    assert np.all(rate_function(FIG8, w[w != 0]) > 0)


def test_delta_zero_is_the_gaussian_ou_rate_function():
    """Delta = 0: v is an OU process with mean a tau_m and, for noise intensity 1/gamma, the
    time average over tau has variance 2 tau_m^2/(gamma tau) (textbook); so
    P_tau(w) ~ exp(-tau gamma (w/F - a tau_m)^2 / (4 tau_m^2))."""
    m = Model(tau_m=1.7, delta=0.0, a=0.6, gamma=3.0, mass=1.3)
    w = np.linspace(-4, 4, 17)
    expected = (w / m.force - m.a * m.tau_m) ** 2 / (4 * m.tau_m ** 2)
    assert np.allclose(rate_function(m, w), expected, rtol=1e-13, atol=1e-15)


def test_rate_function_is_invariant_under_reversing_the_force():
    # a -> -a, v -> -v leaves the model's law invariant and W = F int v unchanged
    w = np.linspace(-3, 3, 25)
    for a in (0.5, 1.5):
        assert np.allclose(rate_function(FIG8.replace(a=a), w), rate_function(FIG8.replace(a=-a), w))


# ----------------------------------------------------------------- fluctuation relation

@pytest.mark.parametrize("mass", [1.0, 2.5])
def test_fluctuation_relation_is_eq_ftexp(mass):
    m = FIG8.replace(mass=mass)
    w = np.linspace(0.01, 5, 50)
    assert np.allclose(fluctuation_relation(m, w), w / (mass * m.tau_m) + m.a * m.delta)
    # odd in w, zero at w = 0, jump 2 a Delta there (Fig. 9)
    assert np.allclose(fluctuation_relation(m, -w), -fluctuation_relation(m, w))
    assert fluctuation_relation(m, 0.0) == 0.0
    jump = fluctuation_relation(m, 1e-12) - fluctuation_relation(m, -1e-12)
    assert jump == pytest.approx(2 * m.a * m.delta, abs=1e-9)


def test_fluctuation_relation_for_negative_force_and_without_dry_friction():
    w = np.linspace(0.05, 4, 20)
    m = FIG8.replace(a=-0.7)
    assert np.allclose(fluctuation_relation(m, w), w / m.tau_m + 0.7 * m.delta)
    ou = FIG8.replace(delta=0.0)  # Delta = 0: the conventional SSFT slope 1/(m tau_m)
    assert np.allclose(fluctuation_relation(ou, w), w / ou.tau_m)


def test_zero_force_and_bad_input_raise_value_error():
    with pytest.raises(ValueError, match="a must be nonzero"):
        rate_function(FIG8.replace(a=0.0), 1.0)
    with pytest.raises(ValueError, match="a must be nonzero"):
        fluctuation_relation(FIG8.replace(a=0.0), 1.0)
    with pytest.raises(ValueError, match="a must be nonzero"):
        work_optimal_path(FIG8.replace(a=0.0), 1.0, 10.0, 1.0, 1.0)
    with pytest.raises(ValueError, match="w must be finite"):
        rate_function(FIG8, [1.0, np.nan])
    with pytest.raises(ValueError, match="tau must be > 0"):
        work_optimal_path(FIG8, 1.0, 0.0, 1.0, 1.0)
    with pytest.raises(ValueError, match="n must be an integer >= 2"):
        work_optimal_path(FIG8, 1.0, 10.0, 1.0, 1.0, n=1)
    with pytest.raises(ValueError, match="v0 must be finite"):
        work_optimal_path(FIG8, 1.0, 10.0, math.inf, 1.0)


# ------------------------------------------------------------------ work-optimal paths

def _numerical_action(model, s, v):
    vd = np.diff(v) / np.diff(s)
    vm = 0.5 * (v[1:] + v[:-1])
    up = vm / model.tau_m + model.delta * np.sign(vm) - model.a
    return float(np.sum(0.25 * (vd + up) ** 2 * np.diff(s)))


FIG7 = [(w, tau, v0, v) for w in (2.0, 4.0) for tau in (10.0, 30.0)
        for v0, v in ((2.0, 1.0), (0.5, 6.0), (10.0, 3.0), (-2.0, 3.0))]


@pytest.mark.parametrize("w,tau,v0,v", FIG7)
def test_fig7_paths_hit_the_endpoints_do_the_work_and_carry_their_action(w, tau, v0, v):
    p = work_optimal_path(FIG8, w, tau, v0, v, n=4000)
    assert p.s[0] == 0 and p.s[-1] == pytest.approx(tau) and len(p.s) == len(p.v) == 4001
    assert p.v[0] == v0 and p.v[-1] == v
    assert p.v_w == pytest.approx(w / (FIG8.mass * FIG8.a))
    assert p.work == pytest.approx(w * tau, rel=1e-12)
    assert FIG8.force * np.trapezoid(p.v, p.s) == pytest.approx(w * tau, rel=1e-5)
    assert _numerical_action(FIG8, p.s, p.v) == pytest.approx(p.action, rel=1e-4)
    assert p.kind == ("+" if v0 > 0 else "-+")


@pytest.mark.parametrize("v0,v", [(2.0, 1.0), (0.5, 6.0), (10.0, 3.0)])
def test_long_paths_sit_on_the_attractor_in_the_middle(v0, v):
    """tau = 30 (Fig. 7b,d): the middle is the E-L fixed point v_p.  Work balance with the two
    boundary layers of width tau_m (z'' = z/tau_m^2) gives, up to e^{-tau/(2 tau_m)},
    v_p (tau - 2 tau_m) + tau_m (v0 + v) = v_w tau, i.e. v_p -> v_w = w/(m a) as 1/tau."""
    w, tau = 2.0, 30.0
    p = work_optimal_path(FIG8, w, tau, v0, v, n=600)
    tm = FIG8.tau_m
    mid = p.v[300]
    assert mid == pytest.approx((p.v_w * tau - tm * (v0 + v)) / (tau - 2 * tm), abs=1e-5)
    assert abs(mid - p.v_w) < 0.25 * abs(p.v_w - 0.5 * (v0 + v)) + 0.03 * p.v_w
    # the E-L fixed point v'' = 0: U'(v_p) U''(v_p) = 2 beta m a
    up = mid / tm + FIG8.delta - FIG8.a
    assert p.beta == pytest.approx(up / tm / (2 * FIG8.mass * FIG8.a), rel=1e-6)


@pytest.mark.parametrize("w", [2.0, 4.0])
def test_action_per_time_tends_to_the_rate_function(w):
    """A(tau) = tau I(w) + C + O(1/tau) for paths that stay on one half plane (eq. (56))."""
    taus = np.array([20.0, 40.0, 80.0])
    A = np.array([work_optimal_path(FIG8, w, t, 2.0, 1.0, n=50).action for t in taus])
    slopes = np.diff(A) / np.diff(taus)
    I = rate_function(FIG8, w)
    err = np.abs(slopes - I)
    assert err[1] < err[0]  # converging
    assert err[1] < 2e-3 * I
    assert abs(A[-1] / taus[-1] - I) < abs(A[0] / taus[0] - I)


@pytest.mark.parametrize("w,v0,v", [(2.0, 2.0, 1.0), (4.0, -2.0, 3.0), (-0.5, 1.0, 1.0)])
def test_multiplier_is_the_derivative_of_the_minimal_action(w, v0, v):
    """Envelope theorem for K = A - beta W: d A_min / d W = beta, with W = w tau."""
    tau, h = 10.0, 1e-4
    p = work_optimal_path(FIG8, w, tau, v0, v)
    up = work_optimal_path(FIG8, w + h, tau, v0, v).action
    dn = work_optimal_path(FIG8, w - h, tau, v0, v).action
    assert (up - dn) / (2 * h * tau) == pytest.approx(p.beta, rel=1e-4)


def test_mirror_symmetry_of_work_optimal_paths():
    """(a, v0, v) -> (-a, -v0, -v) at fixed w mirrors the path (v -> -v)."""
    for w, v0, v in [(2.0, -2.0, 3.0), (-1.0, 1.0, 0.5)]:
        p = work_optimal_path(FIG8, w, 10.0, v0, v)
        q = work_optimal_path(FIG8.replace(a=-FIG8.a), w, 10.0, -v0, -v)
        assert q.action == pytest.approx(p.action, rel=1e-9)
        assert np.allclose(q.v, -p.v, atol=1e-7)
        assert q.beta == pytest.approx(p.beta, rel=1e-9)  # A and W are both unchanged


def test_twice_crossing_when_both_ends_lie_opposite_the_attractor():
    p = work_optimal_path(FIG8, 2.0, 10.0, -1.0, -1.0, n=2000)
    assert p.kind == "-+-"
    t1, t2 = p.t_nodes
    assert 0 < t1 < t2 < 10.0
    assert np.all(p.v[(p.s > t1 + 1e-9) & (p.s < t2 - 1e-9)] > 0)
    assert np.all(p.v[(p.s < t1 - 1e-9) | (p.s > t2 + 1e-9)] < 0)


@pytest.mark.parametrize("w,v0,v,kind", [(2.0, -1.0, -1.0, "-+-"), (2.0, -2.0, 3.0, "-+"),
                                         (0.1, 1.0, 1.0, "+0+"), (-0.5, 1.0, 1.0, "+-+")])
def test_first_integral_is_constant_along_the_whole_path(w, v0, v, kind):
    """K has no explicit time dependence, so H = (v'^2 - U'^2)/4 + beta m a v is conserved on
    every piece (E-L, eq. (60)) and continuous across the kinks at v = 0 (Weierstrass-Erdmann
    corner condition for free crossing times: v'^2 jumps by (Delta - a)^2 - (Delta + a)^2).
    A stuck piece has H = -U'_Filippov^2/4 = 0, so time-sharing paths must have H = 0."""
    p = work_optimal_path(FIG8, w, 10.0, v0, v, n=20000)
    assert p.kind == kind
    s, x = p.s, p.v
    ds = s[1] - s[0]
    vd = (x[2:] - x[:-2]) / (2 * ds)
    vc, sc = x[1:-1], s[1:-1]
    up = vc / FIG8.tau_m + FIG8.delta * np.sign(vc) - FIG8.a
    H = (vd ** 2 - up ** 2) / 4 + p.beta * FIG8.force * vc
    keep = vc != 0
    for t in p.t_nodes:
        keep &= np.abs(sc - t) > 3 * ds
    scale = np.max(vd[keep] ** 2) / 4 + abs(p.beta * FIG8.force) * np.max(np.abs(vc))
    assert np.ptp(H[keep]) < 1e-5 * scale
    if "0" in kind:
        assert abs(np.mean(H[keep])) < 1e-5 * scale


def test_small_work_rates_share_time_between_sticking_and_sliding():
    """Not in the paper: for |a| < Delta and small w the optimum sticks on v = 0 (free) and
    slides at v* = (Delta - a) tau_m for the rest, so A/tau -> v_w (Delta - a)/tau_m, below the
    paper's I(w) (the convex envelope of eq. (64); cf. work_statistics)."""
    w = 0.1  # v_w = 0.2 < v* = 0.5
    A = [work_optimal_path(FIG8, w, t, 1.0, 1.0).action for t in (30.0, 60.0)]
    p = work_optimal_path(FIG8, w, 60.0, 1.0, 1.0)
    assert "0" in p.kind
    slope = (A[1] - A[0]) / 30.0
    envelope = (w / FIG8.force) * (FIG8.delta - FIG8.a) / FIG8.tau_m
    assert slope == pytest.approx(envelope, rel=1e-3)
    assert slope < rate_function(FIG8, w)


@pytest.mark.parametrize("params,w", [
    (dict(tau_m=1.0, delta=1.0, a=0.5), -0.5),   # stick, time-sharing with v = 0 (free)
    (dict(tau_m=1.0, delta=0.5, a=1.0), -0.5),   # slip, time-sharing with a held v = 0
    (dict(tau_m=1.0, delta=1.0, a=0.5), 2.0),    # one half plane, eq. (64) itself
])
def test_long_time_limit_agrees_with_the_convex_envelope_of_work_statistics(params, w):
    """Independent route (another module, derived from the envelope of the holding cost):
    fit A(tau) = I tau + C + D/tau at tau = 20, 40, 80 and compare I."""
    from analogue.theory.work_statistics import weak_noise_limit_rate_function

    m = Model(gamma=10.0, **params)
    taus = np.array([20.0, 40.0, 80.0])
    A = np.array([work_optimal_path(m, w, t, 1.0, 1.0, n=10).action for t in taus])
    I = np.linalg.solve(np.stack([taus, np.ones(3), 1 / taus], axis=1), A)[0]
    assert I == pytest.approx(weak_noise_limit_rate_function(m, w), rel=2e-4)
