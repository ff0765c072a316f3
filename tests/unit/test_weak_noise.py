"""Weak-noise theory of the paper (sections III-IV): minimal action, optimal paths, boundaries,
saddle-point propagator.  Checked against identities (deterministic path has zero action,
indirect paths cost U(v), Delta = 0 is Ornstein-Uhlenbeck, mirror symmetry, stationarity at
long times), against the Lagrangian integrated numerically along the returned paths, and by
continuity of the minimal action across every boundary."""
import math

import numpy as np
import pytest
from scipy.integrate import trapezoid

from analogue import Model
from analogue.theory import weak_noise as wn
from conftest import SLIP_A12, STICK_FIG2


def path_integral(model, p):
    """Midpoint rule for the Lagrangian along the sampled path, and a bound for its error:
    O(h^2) on smooth stretches plus at most one segment's worth at each of the (<= 4) kinks."""
    h = np.diff(p.s)
    mid = 0.5 * (p.v[1:] + p.v[:-1])
    seg = wn.lagrangian(model, mid, np.diff(p.v) / h) * h
    return seg.sum(), 4.0 * seg.max() + 1e-12


def jump_is_continuous(f, x, scale):
    """f continuous at x: the jump over [x - d, x + d] shrinks like d (compare d and d/100)."""
    d = 1e-5 * scale
    big = abs(f(x + d) - f(x - d))
    small = abs(f(x + d / 100) - f(x - d / 100))
    return small <= big / 100 * 1.5 + 1e-12, (big, small)


# ----------------------------------------------------------------------------- identities
@pytest.mark.parametrize("model", [STICK_FIG2, SLIP_A12, STICK_FIG2.replace(a=-0.3), SLIP_A12.replace(a=-1.2),
                                   STICK_FIG2.replace(a=0.7), STICK_FIG2.replace(a=0.0)])
@pytest.mark.parametrize("v0", [1.5, -1.5, 0.4])
def test_deterministic_path_has_zero_action(model, v0):
    ts = np.array([0.2, 0.7, 1.5, 3.0, 6.0])
    v_det = model.deterministic(v0, ts)
    acts = [wn.action(model, v, t, v0) for v, t in zip(v_det, ts)]
    assert np.allclose(acts, 0.0, atol=1e-10)
    # and anything else costs something
    assert all(wn.action(model, v + 0.3, t, v0) > 1e-3 for v, t in zip(v_det, ts))


@pytest.mark.parametrize("a", [0.3, -0.3, 0.0, 0.7])
@pytest.mark.parametrize("v0", [1.5, -1.5, 0.0])
def test_indirect_region_costs_the_potential(a, v0):
    """eqs. (33)/(34): between u and w (t >= t_a) the action is U(v) with U(0) = 0."""
    model = STICK_FIG2.replace(a=a)
    t = 4.0
    b = wn.boundaries(model, t, v0)
    if math.isinf(model.stick_time(v0)):  # a = Delta, v0 > 0: v = 0 is never reached
        assert math.isnan(b["w"]) and math.isnan(b["u"])
        assert wn.optimal_path(model, 0.2, t, v0).kind == "direct"
        return
    lo, hi = sorted([b["w"], b["u"]])
    v = np.linspace(lo, hi, 41)[1:-1]
    assert np.allclose(wn.action(model, v, t, v0), model.potential(v), rtol=1e-12, atol=1e-12)
    kinds = {wn.optimal_path(model, x, t, v0).kind for x in v[::5]}
    assert kinds <= {"indirect", "indirect-crossing"}


@pytest.mark.parametrize("a", [0.0, 0.4, -0.9])
@pytest.mark.parametrize("v0", [1.2, -0.8, 0.0])
@pytest.mark.parametrize("t", [0.3, 1.0, 4.0])
def test_delta_zero_is_ornstein_uhlenbeck(a, v0, t):
    model = Model(tau_m=1.3, delta=0.0, a=a, gamma=5.0)
    v = np.linspace(-3.0, 3.0, 61)
    tau = model.tau_m
    y, y0 = v - a * tau, v0 - a * tau
    ou = (y - y0 * math.exp(-t / tau)) ** 2 / (2 * tau * (1 - math.exp(-2 * t / tau)))
    assert np.allclose(wn.action(model, v, t, v0), ou, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("model", [STICK_FIG2, SLIP_A12, STICK_FIG2.replace(a=0.7), STICK_FIG2.replace(delta=0.0)])
@pytest.mark.parametrize("v0", [1.5, -1.0, 0.0])
def test_mirror_symmetry(model, v0):
    """f(v,t|v0;a) = f(-v,t|-v0;-a) (section II).  For a = 0 this is a genuine check of the
    v0 < 0 cases (no mirroring is done internally then)."""
    v = np.linspace(-3.0, 3.0, 121)
    mirror = model.replace(a=-model.a)
    for t in (0.4, 1.7, 5.0):
        assert np.allclose(wn.action(model, v, t, v0), wn.action(mirror, -v, t, -v0),
                           rtol=1e-10, atol=1e-12)
        f = wn.propagator(model, v, t, v0)
        assert np.allclose(f, wn.propagator(mirror, -v[::-1], t, -v0)[::-1], rtol=1e-8)
    zero = model.replace(a=0.0)
    for t in (0.4, 1.7, 5.0):
        assert np.allclose(wn.action(zero, v, t, v0), wn.action(zero, -v, t, -v0),
                           rtol=1e-10, atol=1e-12)


def test_lambda_is_eq_lambda():
    """Lambda in the paper's unscaled form of eq. (20) (moderate times: no overflow)."""
    m = STICK_FIG2
    t0, t, v0 = 0.3, 1.4, -0.8
    v = np.array([-1.0, 0.2, 0.9])
    for sign in (1, -1):
        k = (m.delta - sign * m.a) * m.tau_m
        num = (np.exp(t / m.tau_m) * (k + abs(v)) - np.exp(t0 / m.tau_m) * (k + abs(v0))) ** 2
        den = 2 * m.tau_m * (np.exp(2 * t / m.tau_m) - np.exp(2 * t0 / m.tau_m))
        assert np.allclose(wn.Lambda(sign, v, t, v0, t0, m), num / den, rtol=1e-12)


# ----------------------------------------------------------------------------- optimal paths
FIVE_KINDS = [
    (STICK_FIG2, 1.5, 1.0, 0.5, "direct"),
    (STICK_FIG2, 1.5, -0.5, 0.5, "direct-crossing"),
    (STICK_FIG2, 1.5, 0.3, 3.0, "indirect"),
    (STICK_FIG2, 1.5, -0.3, 3.0, "indirect-crossing"),
    (SLIP_A12, -1.5, -0.3, 2.0, "twice-crossing"),
    (SLIP_A12.replace(a=-1.2), 1.5, 0.3, 2.0, "twice-crossing"),
    (STICK_FIG2.replace(a=-0.3), -1.5, 0.3, 3.0, "indirect-crossing"),
    (SLIP_A12, -1.0, 0.5, 2.0, "direct-crossing"),
    (SLIP_A12, -1.5, -0.5, 0.5, "direct"),
]


@pytest.mark.parametrize("model,v0,v,t,kind", FIVE_KINDS)
def test_optimal_path_kind_and_lagrangian_integral(model, v0, v, t, kind):
    t0 = 0.25
    p = wn.optimal_path(model, v, t + t0, v0, t0=t0, n=20000)
    assert p.kind == kind
    assert p.s[0] == t0 and p.s[-1] == pytest.approx(t + t0) and len(p.s) == 20001
    assert p.v[0] == v0 and p.v[-1] == v
    # continuous: the largest step between samples halves when the sampling is doubled
    # (a jump would not shrink)
    h = p.s[1] - p.s[0]
    finer = wn.optimal_path(model, v, t + t0, v0, t0=t0, n=40000)
    assert np.max(np.abs(np.diff(finer.v))) < 0.55 * np.max(np.abs(np.diff(p.v)))
    assert p.action == pytest.approx(wn.action(model, v, t + t0, v0, t0=t0), rel=1e-13, abs=1e-14)
    integral, err = path_integral(model, p)
    assert abs(integral - p.action) <= err
    # switching times are where they should be
    times = {"direct": [], "direct-crossing": ["t_cross"], "indirect": ["t_a", "t_b"],
             "indirect-crossing": ["t_a", "t_b"], "twice-crossing": ["t_1", "t_2"]}[kind]
    for name in ("t_cross", "t_a", "t_b", "t_1", "t_2"):
        x = getattr(p, name)
        if name in times:
            assert t0 < x < t + t0 or (name in ("t_a", "t_b") and t0 <= x <= t + t0)
            i = int(round((x - t0) / h))
            assert abs(p.v[i]) < 1e-3  # the path is on v = 0 there
        else:
            assert math.isnan(x)


@pytest.mark.parametrize("model,v0,v,t,kind", FIVE_KINDS[:6])
def test_optimal_path_is_locally_optimal(model, v0, v, t, kind):
    """Smooth perturbations vanishing at the ends never lower the integrated action."""
    p = wn.optimal_path(model, v, t, v0, n=8000)
    base, err = path_integral(model, p)
    x = (p.s - p.s[0]) / t
    for k in (1, 2, 3):
        for eps in (0.05, -0.05, 0.01, -0.01):
            q = wn.OptimalPath(kind=p.kind, s=p.s, v=p.v + eps * np.sin(k * np.pi * x), action=0.0)
            assert path_integral(model, q)[0] >= base - 2 * err


def test_crossing_time_matches_path():
    p = wn.optimal_path(STICK_FIG2, -0.5, 0.5, 1.5)
    assert wn.crossing_time(STICK_FIG2, -0.5, 0.5, 1.5) == pytest.approx(p.t_cross, rel=1e-12)
    tx = wn.crossing_time(STICK_FIG2, np.array([-0.5, 0.5]), 0.5, 1.5)
    assert math.isnan(tx[1]) and tx[0] == pytest.approx(p.t_cross)


# ----------------------------------------------------------------------------- boundaries
@pytest.mark.parametrize("model,v0", [(STICK_FIG2, 1.5), (STICK_FIG2, -1.5), (STICK_FIG2.replace(a=-0.3), 1.5),
                                      (STICK_FIG2.replace(a=-0.3), -1.5), (STICK_FIG2, 0.0),
                                      (STICK_FIG2.replace(a=0.0), 2.0)])
def test_w_and_u_are_where_the_action_switches_continuously(model, v0):
    t_a = model.stick_time(v0)
    for t in (t_a + 0.3, t_a + 1.5, t_a + 3.0):
        b = wn.boundaries(model, t, v0)
        for key in ("w", "u"):
            x = b[key]
            assert math.isfinite(x)
            ok, info = jump_is_continuous(lambda y: wn.action(model, y, t, v0), x, 1 + abs(x))
            assert ok, (key, x, info)
            # the kind of path changes there (unless the side is v = 0 limit)
            if v0 != 0:
                before = wn.optimal_path(model, x * (1 - 1e-6), t, v0).kind
                after = wn.optimal_path(model, x * (1 + 1e-6), t, v0).kind
                assert before.startswith("indirect") and after.startswith("direct")
        # eq. (38): at w the direct action Lambda equals U(w); eq. (42): at u the direct
        # crossing action (with its own t_x) equals the indirect-crossing action U(u)
        side = 1 if b["w"] > 0 else -1
        assert wn.Lambda(side, b["w"], t, v0, 0.0, model) == pytest.approx(
            float(model.potential(b["w"])), rel=1e-9, abs=1e-12)
        if v0 != 0:
            tx = wn.crossing_time(model, b["u"], t, v0)
            crossing = (wn.Lambda(int(np.sign(v0)), 0.0, tx, v0, 0.0, model)
                        + wn.Lambda(-int(np.sign(v0)), b["u"], t, 0.0, tx, model))
            assert crossing == pytest.approx(float(model.potential(b["u"])), rel=1e-9)
        # w on v0's side, u on the other
        if v0 != 0:
            assert np.sign(b["w"]) == np.sign(v0) and np.sign(b["u"]) == -np.sign(v0)


def test_w_matches_paper_eq_dpm_and_u_eq_vc_b():
    """My numerically stable form against eq. (41) / eq. (45) as printed (v0 > 0 upper sign)."""
    m, v0, t0 = STICK_FIG2, 1.5, 0.2
    for t in (2.0, 3.0, 5.0):
        k, E = (m.delta - m.a) * m.tau_m, math.exp((t - t0) / m.tau_m)
        w_paper = -(k - E * (k + v0) + math.sqrt((v0**2 + 2 * k * v0) * (E * E - 1)))
        u_paper = -(m.delta + m.a) * m.tau_m * (k / (k + v0) * E - 1)
        b = wn.boundaries(m, t, v0, t0=t0)
        assert b["w"] == pytest.approx(w_paper, rel=1e-11)
        assert b["u"] == pytest.approx(u_paper, rel=1e-11)


@pytest.mark.parametrize("model,v0", [(SLIP_A12, -1.0), (SLIP_A12.replace(a=-1.2), 1.0), (SLIP_A12, -0.2),
                                      (Model(1.0, 0.2, 0.5, 1.0), -2.0)])
def test_w_cr_is_where_the_action_switches_continuously(model, v0):
    for t in (1.5, 3.0):
        x = wn.boundaries(model, t, v0)["w_cr"]
        assert math.isfinite(x) and np.sign(x) == np.sign(v0)
        ok, info = jump_is_continuous(lambda y: wn.action(model, y, t, v0), x, 1 + abs(x))
        assert ok, (x, info)
        assert wn.optimal_path(model, x * (1 - 1e-6), t, v0).kind == "twice-crossing"
        assert wn.optimal_path(model, x * (1 + 1e-6), t, v0).kind == "direct"
        # eq. (49): the two competing actions agree at w_cr
        direct = wn.Lambda(int(np.sign(v0)), x, t, v0, 0.0, model)
        assert direct == pytest.approx(wn.action(model, x, t, v0), rel=1e-9)


def test_boundaries_apply_only_where_they_should():
    # too short for a twice-crossing path from v0 = -2 (deterministic arrival at 0 takes 1.35)
    m = Model(1.0, 0.2, 0.5, 1.0)
    assert math.isnan(wn.boundaries(m, 0.6, -2.0)["w_cr"])
    assert wn.optimal_path(m, -1e-9, 0.6, -2.0).kind == "direct"
    b = wn.boundaries(STICK_FIG2, np.array([0.5, 1.0, 3.0]), 1.5)  # t_a = ln(4.75) = 1.56
    assert np.isnan(b["w"][:2]).all() and np.isnan(b["u"][:2]).all()
    assert np.isfinite(b["w"][2]) and np.isnan(b["w_cr"]).all()
    assert wn.boundaries(STICK_FIG2, STICK_FIG2.stick_time(1.5), 1.5)["w"] == pytest.approx(0.0, abs=1e-12)
    s = wn.boundaries(SLIP_A12, np.array([1.0, 2.0]), 1.0)  # v0 on the attractor side
    assert all(np.isnan(s[k]).all() for k in s)
    s = wn.boundaries(SLIP_A12, np.array([1.0, 2.0]), -1.0)
    assert np.isnan(s["w"]).all() and np.isnan(s["u"]).all() and np.isfinite(s["w_cr"]).all()
    assert (np.diff(s["w_cr"]) < 0).all()  # the twice-crossing region grows with t


def test_action_is_continuous_in_time_at_t_a():
    for model, v0 in [(STICK_FIG2, 1.5), (STICK_FIG2, -1.5), (STICK_FIG2.replace(a=-0.3), 0.9)]:
        t_a = model.stick_time(v0)
        for v in (-0.6, -0.05, 0.05, 0.6):
            ok, info = jump_is_continuous(lambda t: wn.action(model, v, t, v0), t_a, 1.0)
            assert ok, (v0, v, info)


# ----------------------------------------------------------------------------- edge cases
@pytest.mark.parametrize("name,value", [("a", 0.7), ("a", -0.7), ("a", 0.0), ("delta", 0.0)])
def test_edge_parameters_are_the_limit(name, value):
    """a = +-Delta, a = 0, Delta = 0: the action is the limit of nearby parameters."""
    v = np.linspace(-2.0, 2.0, 81)
    exact = STICK_FIG2.replace(**{name: value})
    for d in (1e-7, -1e-7):
        if name == "delta" and d < 0:
            continue
        near = STICK_FIG2.replace(**{name: value + d})
        for v0 in (1.0, -1.0, 0.0):
            for t in (0.5, 2.5):
                assert np.allclose(wn.action(exact, v, t, v0), wn.action(near, v, t, v0),
                                   atol=1e-5)


@pytest.mark.parametrize("model", [STICK_FIG2, SLIP_A12, STICK_FIG2.replace(a=0.7), STICK_FIG2.replace(delta=0.0)])
def test_v0_zero_and_v_zero_are_the_limit(model):
    v = np.linspace(-2.0, 2.0, 81)
    for t in (0.5, 2.5):
        a0 = wn.action(model, v, t, 0.0)
        for d in (1e-8, -1e-8):
            assert np.allclose(a0, wn.action(model, v, t, d), atol=1e-6)
        for v0 in (1.0, -1.0, 0.0):
            z = wn.action(model, 0.0, t, v0)
            assert isinstance(z, float)
            assert z == pytest.approx(wn.action(model, 1e-9, t, v0), abs=1e-6)
            assert z == pytest.approx(wn.action(model, -1e-9, t, v0), abs=1e-6)


def test_long_times_do_not_overflow():
    for model, v0 in [(STICK_FIG2, 1.0), (SLIP_A12, -1.0), (SLIP_A12, 1.0)]:
        v = np.linspace(-3, 3, 31)
        A = wn.action(model, v, 800.0, v0)
        assert np.all(np.isfinite(A))
        assert np.allclose(A, model.potential(v) - model.potential(model.attractor), atol=1e-9)
        b = wn.boundaries(model, 800.0, v0)
        key = "w" if model is STICK_FIG2 else "w_cr"
        if model is STICK_FIG2 or v0 < 0:
            assert abs(b[key]) > 1e100  # the boundaries run off to infinity like e^{t/tau}
    w_cr = wn.boundaries(SLIP_A12, np.array([10.0, 20.0, 40.0]), -1.0)["w_cr"]
    assert np.all(np.diff(np.log(-w_cr)) > 0.9 * 10.0)  # ~ e^{t/tau}: no saturation by rounding


# ----------------------------------------------------------------------------- propagator
@pytest.mark.parametrize("model,v0", [(STICK_FIG2, 2.0), (STICK_FIG2, -2.0), (SLIP_A12, -1.0), (SLIP_A12, 1.0),
                                      (SLIP_A12.replace(a=-1.2), 1.0)])
def test_propagator_tends_to_stationary_law(model, v0):
    v = np.linspace(-4.0, 4.0, 1601)  # h = 0.005; 0 on the grid
    ps = model.stationary_pdf(v)
    late = wn.propagator(model, v, 40.0, v0)
    assert trapezoid(late, v) == pytest.approx(1.0, rel=1e-12)
    # Euler-Maclaurin: the trapezoid rule errs by -h^2/12 [p'(0-) - p'(0+)] = -h^2/12 2 gamma
    # Delta p(0) at the kink (the ends contribute nothing); the numerical normalisation carries
    # that relative error into every point.
    h = v[1] - v[0]
    eps = h * h / 12 * 2 * model.gamma * model.delta * model.stationary_pdf(0.0)
    assert np.max(np.abs(late - ps)) <= 1.05 * eps * ps.max() + 1e-9
    early = wn.propagator(model, v, 0.5, v0)
    assert np.max(np.abs(early - ps)) > 0.1 * ps.max()


def test_propagator_piecewise_form_sol2():
    """eq. (47) (a < Delta, v0 > 0, t > t_a): exp(-gamma*Lambda_-(..., t_x)) below u, exp(-gamma U)
    between u and w, exp(-gamma*Lambda_+) above w -- up to one normalisation."""
    m, v0, t = STICK_FIG2, 2.0, 2.5
    v = np.linspace(-3.0, 6.0, 901)
    f = wn.propagator(m, v, t, v0)
    b = wn.boundaries(m, t, v0)
    mid = (v > b["u"]) & (v < b["w"])
    ratio = f[mid] / np.exp(-m.gamma * m.potential(v[mid]))
    assert np.allclose(ratio, ratio[0], rtol=1e-10)
    top = v > b["w"]
    ratio_top = f[top] / np.exp(-m.gamma * wn.Lambda(1, v[top], t, v0, 0.0, m))
    assert np.allclose(ratio_top, ratio[0], rtol=1e-10)
    low = v < b["u"]
    tx = wn.crossing_time(m, v[low], t, v0)
    assert np.all((tx > 0) & (tx < t))
    acts = np.array([wn.Lambda(1, 0.0, x, v0, 0.0, m) + wn.Lambda(-1, y, t, 0.0, x, m)
                     for x, y in zip(tx, v[low])])
    assert np.allclose(f[low] / np.exp(-m.gamma * acts), ratio[0], rtol=1e-9)


# ----------------------------------------------------------------------------- bad input
def test_bad_input_raises_value_error_naming_parameter():
    with pytest.raises(ValueError, match="t must be > t0"):
        wn.action(STICK_FIG2, 0.1, 1.0, 0.5, t0=1.0)
    with pytest.raises(ValueError, match="t must be > t0"):
        wn.optimal_path(STICK_FIG2, 0.1, 0.5, 0.5, t0=1.0)
    with pytest.raises(ValueError, match="v0 must be finite"):
        wn.action(STICK_FIG2, 0.1, 1.0, float("nan"))
    with pytest.raises(ValueError, match="v0 must be finite"):
        wn.propagator(STICK_FIG2, np.linspace(-1, 1, 5), 1.0, float("inf"))
    with pytest.raises(ValueError, match="n must be an integer >= 2"):
        wn.optimal_path(STICK_FIG2, 0.1, 1.0, 0.5, n=1)
    with pytest.raises(ValueError, match="v must be finite"):
        wn.action(STICK_FIG2, np.array([0.0, np.nan]), 1.0, 0.5)
    with pytest.raises(ValueError, match="v must be a 1-D strictly increasing grid"):
        wn.propagator(STICK_FIG2, np.array([0.0, -1.0]), 1.0, 0.5)
    with pytest.raises(ValueError, match="t must be > t0"):
        wn.boundaries(STICK_FIG2, np.array([1.0, -1.0]), 0.5)
    with pytest.raises(ValueError, match="sign must be"):
        wn.Lambda(0, 0.1, 1.0, 0.5, 0.0, STICK_FIG2)


def test_propagator_piecewise_form_sol3_and_stationary_switching_times():
    """eq. (51) (a > Delta, v0 < 0): Lambda_- below w_cr, the three-piece eq. (36) between w_cr
    and 0, the direct crossing eq. (24) above 0.  The switching times from optimal_path make
    eqs. (36) / (24) stationary (finite differences), independently of how they were found."""
    m, v0, t = SLIP_A12, -1.0, 2.0
    v = np.linspace(-3.0, 3.0, 241)
    f = wn.propagator(m, v, t, v0)
    x = wn.boundaries(m, t, v0)["w_cr"]
    L = wn.Lambda

    def adc(y, t1, t2):
        return L(-1, 0.0, t1, v0, 0.0, m) + L(1, 0.0, t2, 0.0, t1, m) + L(-1, y, t, 0.0, t2, m)

    def adirx(y, tx):
        return L(-1, 0.0, tx, v0, 0.0, m) + L(1, y, t, 0.0, tx, m)

    def stationary(g, d):
        # at a stationary point the central difference (O(d^2)) is much smaller than the
        # one-sided one (O(d)); elsewhere both are the derivative
        central = (g(d) - g(-d)) / (2 * d)
        one_sided = (g(d) - g(0.0)) / d
        return abs(central) <= 0.01 * abs(one_sided) + 1e-12

    acts = np.empty_like(v)
    for i, y in enumerate(v):
        if y <= x:
            acts[i] = L(-1, y, t, v0, 0.0, m)
        elif y < 0:
            p = wn.optimal_path(m, y, t, v0, n=2)
            assert p.kind == "twice-crossing" and 0 < p.t_1 < p.t_2 < t
            acts[i] = adc(y, p.t_1, p.t_2)
            d = 1e-3 * min(p.t_1, p.t_2 - p.t_1, t - p.t_2)
            assert stationary(lambda e: adc(y, p.t_1 + e, p.t_2), d)
            assert stationary(lambda e: adc(y, p.t_1, p.t_2 + e), d)
            assert not stationary(lambda e: adc(y, 0.9 * p.t_1 + e, p.t_2), d)  # the test bites
        else:
            tx = wn.crossing_time(m, y, t, v0) if y > 0 else wn.optimal_path(m, y, t, v0).t_cross
            if math.isnan(tx):  # y = 0: the lower piece has zero length
                acts[i] = wn.action(m, y, t, v0)
                continue
            acts[i] = adirx(y, tx)
            assert stationary(lambda e: adirx(y, tx + e), 1e-3 * min(tx, t - tx))
    ref = np.exp(-m.gamma * (acts - acts.min()))
    assert np.allclose(f, ref / trapezoid(ref, v), rtol=1e-8, atol=1e-300)
