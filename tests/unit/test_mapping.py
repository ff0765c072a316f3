"""Model <-> circuit mapping: independent routes, not the mapping's own formulas."""
import math

import numpy as np
import pytest
from scipy import integrate

from analogue import Model
from analogue.circuit import CircuitSpec, map_model
from analogue.circuit.parts import PARTS, thermal_voltage, bridge_current, ideal_diode
from conftest import SLIP_A12, STICK_A02

WORK = Model(tau_m=1.0, delta=1.0, a=0.5, gamma=10.0, mass=2.0)

SPECS = [CircuitSpec(), CircuitSpec(diode="1N4148"), CircuitSpec(diode="BAT54"),
         CircuitSpec(coulomb="behavioural"), CircuitSpec(coulomb="behavioural-sgn"),
         CircuitSpec(time_scale=2e-4, capacitance=1e-9, volts_per_velocity=3.0, noise_dt=0.002)]


@pytest.mark.parametrize("model", [STICK_A02, SLIP_A12, WORK])
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
        m = map_model(STICK_A02, spec)
        # the spec's smoothing, or (unset) the one chosen from the model
        assert m.smoothing_fraction == pytest.approx(m.smoothing, rel=1e-9)
        assert m.smoothing == (spec.smoothing if spec.smoothing is not None else 0.02)
    assert map_model(STICK_A02, CircuitSpec(coulomb="behavioural-sgn")).epsilon == 0.0


@pytest.mark.parametrize("spec", [CircuitSpec(), CircuitSpec(diode="BAT54"),
                                  CircuitSpec(coulomb="behavioural", time_scale=1e-5)])
def test_circuit_ode_in_si_units_reproduces_model_motion(spec):
    """Integrate C dV/dt_c = -V/R_tot - I_Delta tanh(V/eps_V) + I_F in seconds and volts and
    compare, via V = kappa v and t_c = theta t, with the model's own deterministic motion."""
    model = STICK_A02
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
    m = map_model(SLIP_A12)
    u, T = 0.37, 2.5
    vx = m.g_x * m.kappa * u * (m.theta * T) / m.cap_x
    assert vx * m.to_model_x == pytest.approx(u * T, rel=1e-12)


def test_held_noise_intensity_by_monte_carlo():
    """A held Gaussian sequence of std s and hold TS has D = s^2 TS/2: integrals over k aligned
    holds have variance 2 D k TS, and over a random phase 2 D k TS (k - 1/3)/k."""
    m = map_model(STICK_A02)
    rng = np.random.default_rng(2024)
    n, k, sub = 20000, 5, 6  # sub: points per hold for the random phase
    held = rng.normal(0.0, m.noise_stddev, size=(n, k + 1))  # model-unit noise, hold noise_dt
    h = m.noise_dt
    D = 1.0 / STICK_A02.gamma  # the model-unit intensity that the node nz must carry
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
    rows = map_model(STICK_A02, CircuitSpec(diode="1N4148")).table()
    names = [r[0] for r in rows]
    assert len(names) == len(set(names))
    for _name, value, unit, meaning in rows:
        assert math.isfinite(value) and unit and meaning
    assert {"R", "C", "I_Delta", "I_F", "kappa", "theta", "N", "noise_stddev", "noise_TS"} <= set(names)


# ------------------------------------------------------------------ refusals
def test_bias_from_smoothing_is_refused_unless_allowed():
    model = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=100.0)
    # a smoothing the user sets is checked as before; unset, it is chosen to pass (issue 20)
    fine_noise = CircuitSpec(noise_dt=0.002, smoothing=0.02)
    assert map_model(model, CircuitSpec(noise_dt=0.002)).bias["smoothing"] <= 0.04
    with pytest.raises(ValueError, match="smoothing.*bias_tolerance"):
        map_model(model, fine_noise)
    m = map_model(model, fine_noise.replace(allow_bias=True))
    assert m.bias["smoothing"] > 0.05
    assert map_model(model, fine_noise.replace(smoothing=0.01)).bias["smoothing"] <= 0.05


@pytest.mark.parametrize("model", [STICK_A02, SLIP_A12, WORK, Model(1.0, 0.7, 0.2, 300.0), Model(1.0, 0.7, -1.5, 50.0)])
def test_bias_measures_against_brute_force_grids(model):
    """stationary_std (closed form) and central_bin_bias (shifted integrals near 0) against
    plain grid integration of the normalised stationary densities (eq. (6))."""
    from analogue.theory.stationary import central_bin_bias, stationary_std
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
        map_model(STICK_A02, CircuitSpec(noise_dt=0.2))
    # weak noise in the stick regime: the peak at v = 0 relaxes in ~ gamma std^2 << tau_m
    with pytest.raises(ValueError, match="noise_dt.*t_rel"):
        map_model(Model(1.0, 0.7, 0.2, 100.0), CircuitSpec(smoothing=0.01, noise_dt=0.01))
    # unset, noise_dt is chosen from the model so that the same check passes
    # (at 0.8 of bias_tolerance = 0.05)
    chosen = map_model(Model(1.0, 0.7, 0.2, 100.0), CircuitSpec(smoothing=0.01))
    assert chosen.bias["noise"] == pytest.approx(0.04, rel=1e-9)
    assert chosen.noise_dt < 0.01 and "noise_dt" in chosen.chosen
    assert map_model(STICK_A02, CircuitSpec(noise_dt=0.2, allow_bias=True)).noise_correlation == pytest.approx(0.2)


def test_real_part_limits():
    with pytest.raises(ValueError, match="I_Delta.*maximum forward current"):
        map_model(STICK_A02, CircuitSpec(diode="1N4148", capacitance=2e-5, volts_per_velocity=20.0))
    with pytest.raises(ValueError, match="volts_per_velocity.*reverse-voltage"):
        map_model(SLIP_A12, CircuitSpec(diode="BAT54", smoothing=0.01))
    with pytest.raises(ValueError, match="smoothing"):
        map_model(STICK_A02, CircuitSpec(diode="1N4148", volts_per_velocity=2.0))
    # an ideal diode has no such limits
    assert map_model(SLIP_A12, CircuitSpec(smoothing=0.01)).part.ideal


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
    assert map_model(STICK_A02, CircuitSpec(vntol=1e-9)).vntol == 1e-9


def test_map_model_type_checks():
    with pytest.raises(ValueError, match="model"):
        map_model({"tau_m": 1})
    with pytest.raises(ValueError, match="spec"):
        map_model(STICK_A02, {"diode": "ideal"})


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
    from analogue.theory.stationary import _positive_part_moments
    top = 60.0 / max(alpha, 1.0) + max(-alpha, 0.0) + 10.0
    mom = [integrate.quad(lambda y: y**k * math.exp(-y * y / 2 - alpha * y), 0.0, top,
                          epsabs=0, epsrel=1e-13, limit=400)[0] for k in range(3)]
    mean, var = _positive_part_moments(-alpha, 1.0)
    assert mean == pytest.approx(mom[1] / mom[0], rel=1e-6)
    assert var == pytest.approx(mom[2] / mom[0] - (mom[1] / mom[0]) ** 2, rel=1e-6)
    # and the scale: N(-alpha s, s^2) gives s * mean, s^2 * var
    m2, v2 = _positive_part_moments(-alpha * 0.01, 0.01)
    assert m2 == pytest.approx(0.01 * mean, rel=1e-12) and v2 == pytest.approx(1e-4 * var, rel=1e-12)


# ------------------------------------------------------------------ edge cases (issue 4)
OU = Model(tau_m=1.0, delta=0.0, a=0.5, gamma=10.0)
ALL_ELEMENTS = [CircuitSpec(), CircuitSpec(diode="1N4148"), CircuitSpec(diode="BAT54"),
                CircuitSpec(coulomb="behavioural"), CircuitSpec(coulomb="behavioural-sgn")]
EDGE_MODELS = [Model(1.0, 0.7, -0.2, 10.0), Model(1.0, 0.7, -1.2, 10.0), Model(1.0, 0.7, 0.0, 10.0),
               Model(1.0, 0.7, 0.7, 10.0), Model(1.0, 0.7, -0.7, 10.0),
               Model(5.0, 0.7, 0.2, 10.0, mass=3.0), Model(0.2, 0.7, 0.2, 10.0, mass=0.5),
               Model(1.0, 0.7, 0.2, 0.01)]


@pytest.mark.parametrize("spec", ALL_ELEMENTS)
@pytest.mark.parametrize("model", [OU, OU.replace(a=-0.5), OU.replace(a=0.0, tau_m=3.0, mass=2.0)])
def test_zero_delta_maps_to_rc_circuit_without_coulomb_element(model, spec):
    """Delta = 0 (Ornstein-Uhlenbeck) is a legitimate model: no Coulomb element, no smoothing,
    the exact model is realised, and the table says there is no element."""
    m = map_model(model, spec)
    assert m.coulomb_element is None and m.part is None and m.emission is None
    assert m.i_delta == 0.0 and m.i_delta_total == 0.0
    assert m.epsilon == 0.0 and m.eps_volts == 0.0 and m.smoothing_fraction == 0.0
    assert m.model_effective == model
    assert m.resistance == m.r_total  # no diode leakage to compensate
    back = m.to_model()
    for key in ("tau_m", "delta", "a", "gamma", "mass", "epsilon"):
        assert getattr(back, key) == pytest.approx(getattr(model, key), rel=1e-12, abs=1e-15), key
    rows = {r[0]: r for r in m.table()}
    assert rows["coulomb_elements"][1] == 0.0 and "Delta = 0" in rows["coulomb_elements"][3]
    assert all(math.isfinite(r[1]) for r in rows.values())
    assert m.bias["smoothing"] == 0.0
    # kappa is the user's or 1 V (the diode's choice of kappa does not apply without a diode)
    assert m.kappa == (spec.volts_per_velocity or 1.0)
    # a Delta > 0 model with the same spec does have its element
    assert {r[0]: r[1] for r in map_model(STICK_A02, spec).table()}["coulomb_elements"] == 1.0


def test_zero_delta_rc_circuit_relaxes_like_ou():
    """C dV/dt_c = -V/R + I_F in closed form, V = R I_F + (V0 - R I_F) e^{-t_c/(R C)}, against
    the model's own deterministic OU motion through V = kappa v, t_c = theta t."""
    for spec in ALL_ELEMENTS:
        m = map_model(OU, spec)
        v0, t = -1.3, np.linspace(0.0, 4.0, 9)
        tc = t * m.theta
        V = m.resistance * m.i_force + (v0 * m.kappa - m.resistance * m.i_force) * np.exp(
            -tc / (m.resistance * m.capacitance))
        np.testing.assert_allclose(V / m.kappa, OU.deterministic(v0, t), rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("spec", ALL_ELEMENTS)
@pytest.mark.parametrize("model", EDGE_MODELS)
def test_edge_models_round_trip_with_signed_force(model, spec):
    """a < 0, a = 0, a = +-Delta, mass and tau_m != 1, very weak noise: the mapping inverts,
    the force current has the sign of a (I_F = a C kappa/theta) and the friction source is
    positive."""
    m = map_model(model, spec)
    back = m.to_model()
    for key in ("tau_m", "delta", "a", "gamma", "mass", "epsilon"):
        assert getattr(back, key) == pytest.approx(getattr(m.model_effective, key), rel=1e-12, abs=1e-15)
    assert m.i_force == pytest.approx(model.a * m.capacitance * m.kappa / m.theta, rel=1e-12, abs=0)
    assert np.sign(m.i_force) == np.sign(model.a)
    assert m.i_delta > 0 and m.coulomb_element == spec.coulomb
    assert math.isfinite(m.voltage_swing) and m.voltage_swing > 0


def test_tiny_delta_keeps_ideal_bridge_source_positive():
    """Delta so small that I_Delta < 2e-14 A: the ideal diode's IS shrinks with it, so the
    bridge source stays positive, the amplitude is still I_Delta_total and the .ic voltages of
    the inner nodes are finite (they were inf when the source went negative)."""
    from analogue.circuit.parts import bridge_node_voltages
    model = Model(1.0, 1e-12, 0.2, 10.0)
    m = map_model(model)
    assert 0 < m.i_delta < m.i_delta_total
    assert m.i_delta + 2 * m.part.IS == pytest.approx(m.i_delta_total, rel=1e-12)
    assert m.part.IS <= 1e-6 * m.i_delta_total
    vp, vn = bridge_node_voltages(m.part, m.i_delta, np.array([-3.0, 0.0, 1e-3, 3.0]))
    assert np.all(np.isfinite(vp)) and np.all(np.isfinite(vn))
    # above ~1e-8 A the ideal diode keeps the standard IS = 1e-14 A
    assert map_model(STICK_A02).part.IS == 1e-14


def test_bridge_law_refuses_source_below_minus_two_is():
    from analogue.circuit.parts import bridge_node_voltages, bridge_voltage
    part = ideal_diode(0.3)
    for f in (bridge_current, bridge_voltage, bridge_node_voltages):
        with pytest.raises(ValueError, match="i0"):
            f(part, -2.0 * part.IS, np.array([0.1]))
        with pytest.raises(ValueError, match="i0"):
            f(part, float("nan"), np.array([0.1]))
    with pytest.raises(ValueError, match="saturation_current"):
        ideal_diode(0.3, saturation_current=0.0)
    # a slightly negative source is still a valid Shockley bridge: amplitude I0 + 2 IS
    i = bridge_current(part, -part.IS, np.array([1.0]))
    assert i[0] == pytest.approx(part.IS, rel=1e-12)


def test_stationary_range_by_grid():
    """The rating swing: the ends of {gamma (U - U_min) <= 32} against a fine grid, inside the
    bound sqrt(64 tau_m/gamma) around the minimum, and far inside it in the stick regime at
    weak noise (U rises linearly there)."""
    from analogue.circuit.mapping import stationary_range
    for model in (STICK_A02, SLIP_A12, OU, Model(1.0, 0.7, -0.2, 1e3), Model(1.0, 0.7, 0.2, 1e3, epsilon=1e-4)):
        lo, hi = stationary_range(model)
        c = model.potential_minimum()
        w = 8.0 * model.velocity_scale
        v = np.linspace(c - 1.01 * w, c + 1.01 * w, 2_000_001)
        inside = v[model.gamma * (model.potential(v) - model.potential(c)) <= 32.0]
        step = v[1] - v[0]
        assert lo == pytest.approx(inside[0], abs=step) and hi == pytest.approx(inside[-1], abs=step)
        assert c - w * (1 + 1e-9) <= lo < c < hi <= c + w * (1 + 1e-9)
    lo, hi = stationary_range(Model(1.0, 0.7, 0.2, 1e3))
    assert hi - lo < 0.4 * 16 * math.sqrt(1e-3)
    m = map_model(SLIP_A12)
    assert m.voltage_swing == pytest.approx(m.kappa * max(abs(b) for b in stationary_range(m.model_effective)))


def test_real_diode_reaches_weak_noise_stick_regime():
    """gamma = 1e3 in the stick regime with a 1N4148: fine smoothing needs a large kappa, which
    the stationary swing (not a flat 8 widths) admits under the 100 V rating."""
    m = map_model(Model(1.0, 0.7, 0.2, 1e3), CircuitSpec(diode="1N4148", smoothing=0.005, noise_dt=5e-4))
    assert m.voltage_swing < 100.0 < m.kappa * 8.0 * m.model.velocity_scale
    assert m.bias["smoothing"] <= 0.05 and m.bias["noise"] <= 0.05


# Each refusal names the parameter and a fix; following the fix must get past that refusal.
def test_refusals_give_working_fixes():
    import re as _re
    weak = Model(1.0, 0.7, 0.2, 1e3)
    # smoothing bias at weak noise -> lower smoothing below the stated value
    with pytest.raises(ValueError, match="smoothing.*lower smoothing below about") as exc:
        map_model(weak, CircuitSpec(noise_dt=5e-4, smoothing=0.02))
    s_fix = float(_re.search(r"below about ([0-9.e+-]+)", str(exc.value)).group(1))
    assert map_model(weak, CircuitSpec(noise_dt=5e-4, smoothing=0.9 * s_fix)).bias["smoothing"] <= 0.05
    # held-noise bias -> lower noise_dt below the stated value
    with pytest.raises(ValueError, match="noise_dt.*lower noise_dt below") as exc:
        map_model(weak, CircuitSpec(smoothing=0.005, noise_dt=0.01))
    n_fix = float(_re.search(r"lower noise_dt below ([0-9.e+-]+)", str(exc.value)).group(1))
    map_model(weak, CircuitSpec(smoothing=0.005, noise_dt=0.9 * n_fix))
    # reverse-voltage rating with automatic kappa -> raise smoothing above the stated value
    with pytest.raises(ValueError, match="reverse-voltage.*raise smoothing above about") as exc:
        map_model(weak, CircuitSpec(diode="1N4148", smoothing=0.002, noise_dt=5e-5, capacitance=1e-8))
    s_fix = float(_re.search(r"above about ([0-9.e+-]+)", str(exc.value)).group(1))
    map_model(weak, CircuitSpec(diode="1N4148", smoothing=1.1 * s_fix, noise_dt=5e-5, capacitance=1e-8))
    # ... with a given kappa -> lower volts_per_velocity
    spec = CircuitSpec(diode="BAT54", volts_per_velocity=1e3, noise_dt=5e-4, smoothing=0.005, allow_bias=True)
    with pytest.raises(ValueError, match="lower volts_per_velocity below") as exc:
        map_model(weak, spec)
    k_fix = float(_re.search(r"below ([0-9.e+-]+) V", str(exc.value)).group(1))
    assert map_model(weak, spec.replace(volts_per_velocity=0.9 * k_fix)).voltage_swing < 30.0
    # series resistance too wide for the smoothing -> lower capacitance/time_scale by the factor
    big = Model(1.0, 100.0, 0.0, 10.0)
    with pytest.raises(ValueError, match="smoothing.*unreachable.*capacitance/time_scale by more than a factor") as exc:
        map_model(big, CircuitSpec(diode="BAT54", allow_bias=True))
    f_fix = float(_re.search(r"a factor ([0-9.e+-]+)", str(exc.value)).group(1))
    m = map_model(big, CircuitSpec(diode="BAT54", allow_bias=True, capacitance=1e-7 / (1.2 * f_fix)))
    assert m.smoothing_fraction == pytest.approx(0.02, rel=1e-9)
    # leakage of the parallel resistors beyond tau_m -> raise capacitance (or lower time_scale)
    slow = Model(3000.0, 0.7, 0.2, 10.0)
    with pytest.raises(ValueError, match="tau_m.*raise capacitance or lower time_scale"):
        map_model(slow, CircuitSpec(diode="BAT54", allow_bias=True))
    m = map_model(slow, CircuitSpec(diode="BAT54", allow_bias=True, time_scale=1e-4))
    assert 1.0 / m.resistance + 2.0 / m.part.rp == pytest.approx(1.0 / m.r_total, rel=1e-12)
    # friction current below the diodes' reverse current -> raise capacitance
    small = Model(1.0, 1e-5, 0.0, 10.0)
    with pytest.raises(ValueError, match="Delta.*reverse current.*raise capacitance"):
        map_model(small, CircuitSpec(diode="BAT54"))
    assert map_model(small, CircuitSpec(diode="BAT54", capacitance=1e-3, allow_bias=True)).i_delta > 0


def test_extreme_noise_strengths_map_without_overflow():
    """gamma from 1e-4 to 1e16 in both regimes, with the biases allowed: no overflow warning
    (the central-bin integrand used to overflow in the slip regime at weak noise), finite
    biases and a swing inside the 8-width bound (where rounding swamps U - U_min the bound
    itself is returned)."""
    import warnings
    from analogue.circuit.mapping import stationary_range
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for gamma in (1e-4, 1e12, 1e16):
            for a in (0.2, 1.2, -1.2):
                model = Model(1.0, 0.7, a, gamma)
                m = map_model(model, CircuitSpec(coulomb="behavioural", allow_bias=True))
                assert all(math.isfinite(b) for b in m.bias.values())
                lo, hi = stationary_range(m.model_effective)
                c, w = m.model_effective.potential_minimum(), 8.0 * 1.001 * model.velocity_scale
                assert c - w * (1 + 1e-9) <= lo <= c <= hi <= c + w * (1 + 1e-9)


def test_rating_refusal_when_the_motion_itself_is_too_large():
    """A huge slip velocity v_ss: no smoothing < 1 helps; the message says so and names the
    way out (a smaller volts_per_velocity with allow_bias), which works."""
    model = Model(1.0, 0.7, 1e3, 10.0)
    with pytest.raises(ValueError, match="smoothing would have to exceed 1.*volts_per_velocity"):
        map_model(model, CircuitSpec(diode="BAT54"))
    m = map_model(model, CircuitSpec(diode="BAT54", volts_per_velocity=0.02, allow_bias=True))
    assert m.voltage_swing < 30.0
