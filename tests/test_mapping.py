"""Model <-> circuit mapping: independent routes, not the mapping's own formulas."""
import math

import numpy as np
import pytest
from scipy import integrate

from analogue import Model
from analogue.circuit import CircuitSpec, map_model
from analogue.circuit.parts import PARTS, thermal_voltage, bridge_current, ideal_diode

STICK = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)
SLIP = Model(tau_m=1.0, delta=0.7, a=1.2, gamma=10.0)
WORK = Model(tau_m=1.0, delta=1.0, a=0.5, gamma=10.0, mass=2.0)

SPECS = [CircuitSpec(), CircuitSpec(diode="1N4148"), CircuitSpec(diode="BAT54"),
         CircuitSpec(coulomb="behavioural"), CircuitSpec(coulomb="behavioural-sgn"),
         CircuitSpec(time_scale=2e-4, capacitance=1e-9, volts_per_velocity=3.0, noise_dt=0.002)]


@pytest.mark.parametrize("model", [STICK, SLIP, WORK])
@pytest.mark.parametrize("spec", SPECS)
def test_round_trip_recovers_effective_model(model, spec):
    m = map_model(model, spec)
    back = m.to_model()
    eff = m.model_effective
    for key in ("tau_m", "delta", "a", "gamma", "mass", "epsilon"):
        assert getattr(back, key) == pytest.approx(getattr(eff, key), rel=1e-12, abs=1e-15), key
    # the effective model is the requested one with only the smoothing width set
    assert eff.replace(epsilon=0.0) == model
    assert m.D_effective == pytest.approx(1.0 / model.gamma, rel=1e-12)


def test_smoothing_meets_request():
    for spec in SPECS[:4]:
        m = map_model(STICK, spec)
        assert m.smoothing_fraction == pytest.approx(spec.smoothing, rel=1e-9)
    assert map_model(STICK, CircuitSpec(coulomb="behavioural-sgn")).epsilon == 0.0


@pytest.mark.parametrize("spec", [CircuitSpec(), CircuitSpec(diode="BAT54"),
                                  CircuitSpec(coulomb="behavioural", time_scale=1e-5)])
def test_circuit_ode_in_si_units_reproduces_model_motion(spec):
    """Integrate C dV/dt_c = -V/R_tot - I_Delta tanh(V/eps_V) + I_F in seconds and volts and
    compare, via V = kappa v and t_c = theta t, with the model's own deterministic motion."""
    model = STICK
    m = map_model(model, spec)
    v0 = 1.5
    t_model = np.linspace(0.0, 3.0, 31)

    def rhs(tc, V):
        coul = m.i_delta_total * np.tanh(V / m.eps_volts)
        return (-V / m.r_total - coul + m.i_force) / m.capacitance

    sol = integrate.solve_ivp(rhs, (0.0, t_model[-1] * m.theta), [v0 * m.kappa], method="Radau",
                              t_eval=t_model * m.theta, rtol=1e-10, atol=1e-12 * m.kappa)
    v_circuit = sol.y[0] / m.kappa
    v_model = m.model_effective.deterministic(v0, t_model)
    np.testing.assert_allclose(v_circuit, v_model, atol=1e-6)
    # and the real diode's physical resistor and leakage add up to the viscous resistance
    if m.part is not None and m.part.rp:
        assert 1.0 / m.resistance + 2.0 / m.part.rp == pytest.approx(1.0 / m.r_total, rel=1e-12)


def test_position_scale_integrates_velocity():
    """V(x) = (g kappa theta / C_x) * integral v dt: a constant velocity u for model time T
    charges C_x with g kappa u for theta T seconds."""
    m = map_model(SLIP)
    u, T = 0.37, 2.5
    vx = m.g_x * m.kappa * u * (m.theta * T) / m.cap_x
    assert vx * m.to_model_x == pytest.approx(u * T, rel=1e-12)


def test_held_noise_intensity_by_monte_carlo():
    """A held Gaussian sequence of std s and hold TS has D = s^2 TS/2: integrals over k aligned
    holds have variance 2 D k TS, and over a random phase 2 D k TS (k - 1/3)/k."""
    m = map_model(STICK)
    rng = np.random.default_rng(2024)
    n, k, sub = 20000, 5, 6  # sub: points per hold for the random phase
    held = rng.normal(0.0, m.noise_stddev, size=(n, k + 1))  # model-unit noise, hold noise_dt
    h = m.noise_dt
    D = 1.0 / STICK.gamma  # the model-unit intensity that the node nz must carry
    aligned = held[:, :k].sum(axis=1) * h
    var = aligned.var(ddof=1)
    se = var * math.sqrt(2.0 / (n - 1))
    assert abs(var - 2 * D * k * h) < 4 * se
    phase = rng.integers(0, sub, size=n) / sub  # window start inside hold 0
    shifted = (held[:, 0] * (1 - phase) + held[:, 1:k].sum(axis=1) + held[:, k] * phase) * h
    var = shifted.var(ddof=1)
    se = var * math.sqrt(2.0 / (n - 1))
    # discrete phases j/sub: E[(1-p)^2 + p^2] = 1 - 2E[p] + 2E[p^2]; the mapping's (k-1/3)/k
    # is the continuous-phase limit, off by 1/(3 sub^2)/k here.
    p = np.arange(sub) / sub
    exact = (k - 1 + np.mean((1 - p) ** 2 + p**2)) / k
    assert abs(var - 2 * D * k * h * exact) < 4 * se
    assert m.window_factor(k) == pytest.approx((k - 1 + 2 / 3) / k)
    assert abs(exact - m.window_factor(k)) < 1.0 / (3 * sub**2 * k) + 1e-15
    assert m.window_factor(k, aligned=True) == 1.0


def test_thermal_voltage_is_ngspice_value():
    assert thermal_voltage() == pytest.approx(0.025865, abs=2e-6)  # k T/q at 27 C


def test_bridge_law_closed_form_and_inverse():
    part = ideal_diode(0.3)
    v = np.linspace(-0.2, 0.2, 41)
    i = bridge_current(part, 1e-3, v)
    np.testing.assert_allclose(i, (1e-3 + 2 * part.IS) * np.tanh(v / (0.6 * thermal_voltage())),
                               rtol=1e-12)
    real = PARTS["BAT54"]
    i = bridge_current(real, 1e-3, v)
    from analogue.circuit.parts import bridge_voltage
    np.testing.assert_allclose(bridge_voltage(real, 1e-3, i), v, atol=1e-12)


def test_table_rows_have_units_and_meanings():
    rows = map_model(STICK, CircuitSpec(diode="1N4148")).table()
    names = [r[0] for r in rows]
    assert len(names) == len(set(names))
    for name, value, unit, meaning in rows:
        assert math.isfinite(value) and unit and meaning
    assert {"R", "C", "I_Delta", "I_F", "kappa", "theta", "N", "noise_stddev", "noise_TS"} <= set(names)


# ------------------------------------------------------------------ refusals
def test_bias_from_smoothing_is_refused_unless_allowed():
    model = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=100.0)
    fine_noise = CircuitSpec(noise_dt=0.002)
    with pytest.raises(ValueError, match="smoothing.*bias_tolerance"):
        map_model(model, fine_noise)
    m = map_model(model, fine_noise.replace(allow_bias=True))
    assert m.bias["smoothing"] > 0.05
    assert map_model(model, fine_noise.replace(smoothing=0.01)).bias["smoothing"] <= 0.05


@pytest.mark.parametrize("model", [STICK, SLIP, WORK, Model(1.0, 0.7, 0.2, 300.0), Model(1.0, 0.7, -1.5, 50.0)])
def test_bias_measures_against_brute_force_grids(model):
    """stationary_std (closed form) and central_bin_bias (shifted integrals near 0) against
    plain grid integration of the normalised stationary densities (eq. p_stat)."""
    from analogue.circuit.mapping import central_bin_bias, stationary_std
    eps = 0.02 * model.velocity_scale
    v = np.linspace(-4.0, 4.0, 2_000_001)
    p0 = model.stationary_pdf(v)
    mean = np.trapezoid(v * p0, v)
    std = math.sqrt(np.trapezoid((v - mean) ** 2 * p0, v))
    assert stationary_std(model) == pytest.approx(std, rel=1e-4)
    inside = np.abs(v) <= 0.05 * std
    p_eps = model.replace(epsilon=eps).stationary_pdf(v)
    brute = abs(np.trapezoid(p_eps * inside, v) / np.trapezoid(p0 * inside, v) - 1.0)
    # the grid resolves the bin with ~ 0.1 std / 4e-6 points: a few 1e-3 of the bias
    assert central_bin_bias(model, eps) == pytest.approx(brute, rel=0.02, abs=1e-4)


def test_bias_from_noise_hold_is_refused_unless_allowed():
    with pytest.raises(ValueError, match="noise_dt"):
        map_model(STICK, CircuitSpec(noise_dt=0.2))
    # weak noise in the stick regime: the peak at v = 0 relaxes in ~ gamma std^2 << tau_m
    with pytest.raises(ValueError, match="noise_dt.*t_rel"):
        map_model(Model(1.0, 0.7, 0.2, 100.0), CircuitSpec(smoothing=0.01))
    assert map_model(STICK, CircuitSpec(noise_dt=0.2, allow_bias=True)).noise_correlation == pytest.approx(0.2)


def test_real_part_limits():
    with pytest.raises(ValueError, match="I_Delta.*maximum forward current"):
        map_model(STICK, CircuitSpec(diode="1N4148", capacitance=2e-5, volts_per_velocity=20.0))
    with pytest.raises(ValueError, match="volts_per_velocity.*reverse-voltage"):
        map_model(SLIP, CircuitSpec(diode="BAT54", smoothing=0.01))
    with pytest.raises(ValueError, match="smoothing"):
        map_model(STICK, CircuitSpec(diode="1N4148", volts_per_velocity=2.0))
    # an ideal diode has no such limits
    assert map_model(SLIP, CircuitSpec(smoothing=0.01)).part.ideal


@pytest.mark.parametrize("kwargs, name", [
    ({"coulomb": "sgn"}, "coulomb"), ({"diode": "1N4001"}, "diode"), ({"smoothing": 1.5}, "smoothing"),
    ({"smoothing": float("nan")}, "smoothing"), ({"capacitance": -1.0}, "capacitance"),
    ({"time_scale": "1e-3"}, "time_scale"), ({"noise_dt": 0.0}, "noise_dt"), ({"method": "euler"}, "method"),
    ({"allow_bias": 1}, "allow_bias"), ({"reltol": 0.5}, "reltol")])
def test_spec_validation(kwargs, name):
    with pytest.raises(ValueError, match=name):
        CircuitSpec(**kwargs)


def test_voltage_tolerance_stays_below_friction_width():
    for gamma in (10.0, 1e4):
        m = map_model(Model(1.0, 0.7, 0.2, gamma), CircuitSpec(smoothing=0.002, noise_dt=1e-4, allow_bias=True))
        assert m.vntol <= 1e-3 * m.eps_volts
    assert map_model(STICK, CircuitSpec(vntol=1e-9)).vntol == 1e-9


def test_map_model_type_checks():
    with pytest.raises(ValueError, match="model"):
        map_model({"tau_m": 1})
    with pytest.raises(ValueError, match="spec"):
        map_model(STICK, {"diode": "ideal"})


def test_noise_bias_estimate_matches_exact_held_noise_ou():
    """For Delta = 0 the velocity is an OU process driven by held noise; its exact variance a
    fraction u into a hold is e^{-2 lam u h} V + s^2 (1 - e^{-lam u h})^2 / lam^2 with the
    grid variance V = s^2 tanh(lam h / 2) / lam^2.  Averaged over u it falls short of the
    white-noise value by noise_dt/(3 tau_m) to first order, the mapping's bias estimate."""
    for noise_dt in (0.01, 0.003):
        model = Model(tau_m=1.0, delta=0.0, a=0.0, gamma=10.0)
        m = map_model(model, CircuitSpec(coulomb="behavioural", noise_dt=noise_dt))
        lam, h, s2 = 1.0 / model.tau_m, m.noise_dt, m.noise_stddev**2
        grid_var = s2 * math.tanh(lam * h / 2) / lam**2
        u = np.linspace(0.0, 1.0, 20001)
        var_u = np.exp(-2 * lam * u * h) * grid_var + s2 * (1 - np.exp(-lam * u * h)) ** 2 / lam**2
        mean_var = integrate.simpson(var_u, x=u)
        drop = 1.0 - mean_var / (model.tau_m / model.gamma)
        assert drop == pytest.approx(m.bias["noise"], rel=3 * lam * h)  # next order is O(h^2)


@pytest.mark.parametrize("alpha", [-2.0, 0.0, 3.0, 39.0, 41.0, 200.0, 5000.0])
def test_positive_part_moments_by_quadrature(alpha):
    """Y ~ N(-alpha, 1) conditioned on Y > 0 has density ~ exp(-y^2/2 - alpha y) on y > 0:
    its mean and variance by quadrature against the closed form / asymptotic series."""
    from analogue.circuit.mapping import _positive_part_moments
    top = 60.0 / max(alpha, 1.0) + max(-alpha, 0.0) + 10.0
    mom = [integrate.quad(lambda y: y**k * math.exp(-y * y / 2 - alpha * y), 0.0, top,
                          epsabs=0, epsrel=1e-13, limit=400)[0] for k in range(3)]
    mean, var = _positive_part_moments(-alpha, 1.0)
    assert mean == pytest.approx(mom[1] / mom[0], rel=1e-6)
    assert var == pytest.approx(mom[2] / mom[0] - (mom[1] / mom[0]) ** 2, rel=1e-6)
    # and the scale: N(-alpha s, s^2) gives s * mean, s^2 * var
    m2, v2 = _positive_part_moments(-alpha * 0.01, 0.01)
    assert m2 == pytest.approx(0.01 * mean, rel=1e-12) and v2 == pytest.approx(1e-4 * var, rel=1e-12)
