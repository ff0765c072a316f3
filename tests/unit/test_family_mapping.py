"""Issue 9 mapping and decks (no ngspice): component formulas derived here from the
force-current analogy, spec validation, budget enforcement naming the parameter to change,
deck contents, and the seeded kicks."""
import math
import re

import numpy as np
import pytest
from scipy.linalg import expm

from analogue import Model, ShotNoise
from analogue.circuit import CircuitSpec, build_deck, map_model
from analogue.circuit.experiments import experiment_from_dict
from analogue.circuit.shot import pulse_pwl, replica_kicks

BASE = {"tau_m": 1.0, "delta": 0.5, "a": 0.2, "gamma": 10.0}
CUBIC = Model(**BASE, cubic=1.0)
STRIBECK = Model(tau_m=2.0, delta=0.3, a=0.7, gamma=10.0, stribeck=(1.0, 0.2))
SPRING = Model(tau_m=3.0, delta=0.5, a=0.1, gamma=20.0, spring=2.0, x0=0.7)
SHOT = Model(tau_m=1.0, delta=0.5, a=0.2, gamma=math.inf, shot=ShotNoise(rate=1.0, mean=0.5))


# ------------------------------------------------------------------ spec validation
@pytest.mark.parametrize("field,value", [
    ("cubic_element", "spline"), ("cubic_diode", "1N914"), ("cubic_branches", 0),
    ("cubic_branches", 17), ("cubic_branches", True), ("cubic_branches", 2.0),
    ("inductor_q", 0.0), ("inductor_q", "100"), ("inductor_resistance", -1.0),
    ("shot_width", 0.0), ("shot_width", math.inf)])
def test_spec_refuses_bad_family_fields(field, value):
    with pytest.raises(ValueError, match=field):
        CircuitSpec(**{field: value})


# ------------------------------------------------------------------ component values
def test_cubic_conductance_formula():
    spec = CircuitSpec(time_scale=2e-3, capacitance=47e-9, coulomb="behavioural", volts_per_velocity=0.5)
    m = map_model(CUBIC, spec)
    # current per unit acceleration C kappa/theta; I = C kappa/theta cubic (V/kappa)^3
    assert m.g3 == pytest.approx(47e-9 * 0.5 / 2e-3 * 1.0 / 0.5**3, rel=1e-12)
    assert m.to_model().cubic == pytest.approx(1.0, rel=1e-12)


def test_spring_inductor_formulas():
    spec = CircuitSpec(time_scale=1e-4, capacitance=100e-9, inductor_q=50.0, allow_bias=True)
    m = map_model(SPRING, spec)
    k, theta, c = 2.0, 1e-4, 100e-9
    # C dV/dt_c = -I_L, L dI_L/dt_c = V: I_L = kappa theta x/L must be k x C kappa/theta
    assert m.inductance == pytest.approx(theta**2 / (k * c), rel=1e-12)
    assert m.inductor_rs == pytest.approx(math.sqrt(k) / theta * m.inductance / 50.0, rel=1e-12)
    assert m.spring_leak_time == pytest.approx(50.0 / math.sqrt(k), rel=1e-12)
    assert m.inductor_ic == pytest.approx(k * 0.7 * c * m.kappa / theta, rel=1e-12)
    assert m.x_spring_gain * m.inductor_ic == pytest.approx(0.7, rel=1e-12)  # 1 V per unit x
    back = m.to_model()
    assert back.spring == pytest.approx(k, rel=1e-12) and back.x0 == pytest.approx(0.7, rel=1e-12)
    assert map_model(SPRING, spec.replace(inductor_resistance=0.0)).spring_leak_time == math.inf


def test_spring_leak_budget_matches_covariance_integral():
    """Lyapunov budget vs the stationary covariance as int_0^inf e^{At} B B^T e^{A^T t} dt."""
    spec = CircuitSpec(time_scale=1e-4, inductor_q=20.0, allow_bias=True)
    m = map_model(SPRING, spec)

    def cov(leak):
        A = np.array([[-1 / 3.0, -2.0], [1.0, -leak]])
        t = np.linspace(0.0, 120.0, 24001)
        step = expm(A * (t[1] - t[0]))
        e = np.eye(2)
        vals = []
        for _ in t:
            vals.append(e @ np.diag([1.0, 0.0]) @ e.T)
            e = step @ e
        return np.trapezoid(np.array(vals), t, axis=0)

    ideal, leaky = cov(0.0), cov(1.0 / m.spring_leak_time)
    assert m.bias["spring_leak_var_v"] == pytest.approx(abs(leaky[0, 0] / ideal[0, 0] - 1), rel=1e-3)
    assert m.bias["spring_leak_var_x"] == pytest.approx(abs(leaky[1, 1] / ideal[1, 1] - 1), rel=1e-3)
    # creep of the mean velocity a/(k tau_L + 1/tau_m) relative to sqrt(tau_m/gamma)
    creep = 0.1 / (2.0 * m.spring_leak_time + 1 / 3.0) / math.sqrt(3.0 / 20.0)
    assert m.bias["spring_creep"] == pytest.approx(creep, rel=1e-12)


def test_stribeck_and_shot_values():
    m = map_model(STRIBECK, CircuitSpec(coulomb="behavioural", smoothing=0.01))
    iu = m.capacitance * m.kappa / m.theta
    assert m.i_stribeck == pytest.approx((1.0 - 0.3) * iu, rel=1e-12)
    assert m.stribeck_volts == pytest.approx(0.2 * m.kappa, rel=1e-12)
    assert m.to_model().stribeck == pytest.approx((1.0, 0.2), rel=1e-12)
    s = map_model(SHOT)
    assert s.shot_charge == pytest.approx(s.capacitance * s.kappa, rel=1e-12)
    assert not s.gaussian_noise and s.noise_D == 0 and s.to_model().gamma == math.inf
    assert s.bias["shot_pulse"] == pytest.approx(1e-3, rel=1e-9)  # the automatic width's target


# ------------------------------------------------------------------ enforced budget terms
@pytest.mark.parametrize("model,spec,name", [
    (CUBIC, CircuitSpec(cubic_element="diode-network", cubic_branches=1), "cubic_branches"),
    (SPRING, CircuitSpec(time_scale=1e-4, inductor_q=5.0), "inductor_q"),
    (SHOT, CircuitSpec(shot_width=0.2), "shot_width"),
    (STRIBECK.replace(stribeck=(1.0, 0.01)), CircuitSpec(coulomb="behavioural", smoothing=0.02),
     "smoothing"),
])
def test_bias_refused_naming_the_parameter(model, spec, name):
    with pytest.raises(ValueError, match=name):
        map_model(model, spec)
    map_model(model, spec.replace(allow_bias=True))  # accepted when asked to


def test_network_forward_current_rating():
    """A 1N4148 branch carrying more than 200 mA at the swing edge is refused."""
    spec = CircuitSpec(cubic_element="diode-network", capacitance=1e-3, coulomb="behavioural")
    with pytest.raises(ValueError, match="capacitance"):
        map_model(CUBIC, spec)


# ------------------------------------------------------------------ decks
def deck(model, spec=None, replicas=3, seed=4, t_end=20.0):
    return build_deck(map_model(model, spec), replicas=replicas, v0=np.zeros(replicas),
                      t_end=t_end, seed=seed, sample_dt=0.01)


def test_cubic_deck_elements():
    d = deck(CUBIC, CircuitSpec(coulomb="behavioural"))
    assert re.search(r"^Bcubic v 0 i=[0-9.e+-]+\*V\(v\)\*V\(v\)\*V\(v\)$", d.text, re.MULTILINE)
    n = deck(CUBIC, CircuitSpec(cubic_element="diode-network", cubic_branches=4))
    assert len(re.findall(r"^D\d[pn] ", n.text, re.MULTILINE)) == 8
    assert ".model dcubic D" in n.text and "xcubic" in n.text.lower()


def test_spring_deck_elements():
    d = deck(SPRING, CircuitSpec(time_scale=1e-4))
    assert re.search(r"^Lspring v ls [0-9.e+-]+ ic=[0-9.e+-]+$", d.text, re.MULTILINE)
    assert "Hxs xs 0 vsense" in d.text and d.vectors["x_spring"] == ["v(xs0)", "v(xs1)", "v(xs2)"]
    assert d.x_spring_initial == 0.7
    ideal = deck(SPRING, CircuitSpec(time_scale=1e-4, inductor_resistance=0.0))
    assert re.search(r"^Lspring v lg ", ideal.text, re.MULTILINE) and "Rleak" not in ideal.text


def test_shot_deck_pwl_and_kicks():
    d = deck(SHOT, replicas=3, seed=4)
    assert "trrandom" not in d.text and d.vectors["noise"] == []
    assert len(re.findall(r"^Ishot\d pwl|^Ishot\d 0 v\d pwl\($", d.text, re.MULTILINE)) == 3
    assert deck(SHOT, replicas=3, seed=4).text == d.text          # reproducible
    assert deck(SHOT, replicas=3, seed=5).text != d.text          # and seeded
    assert len(d.kicks) == 3 and all(len(t) == len(z) for t, z in d.kicks)


def test_pulse_pwl_delivers_each_charge():
    rng = np.random.default_rng(0)
    starts = np.sort(rng.uniform(0, 1.0, 50))
    q = rng.exponential(2.0, 50)
    t, i = pulse_pwl(starts, q, 1e-2)  # many overlap
    assert np.all(np.diff(t) > 0) and t[0] == 0 and i[0] == 0
    assert np.trapezoid(i, t) == pytest.approx(q.sum(), rel=1e-9)
    # the charge delivered up to any time between pulses equals the kicks started before it
    gap = np.flatnonzero(np.diff(starts) > 0.02)[5]
    cut = starts[gap] + 0.0105
    sel = t <= cut
    assert np.trapezoid(i[sel], t[sel]) == pytest.approx(q[:gap + 1].sum(), rel=1e-9)


@pytest.mark.parametrize("two_sided", [False, True])
def test_kick_statistics(two_sided):
    rate, mean, t_end = 2.0, 0.3, 5000.0
    t, z = replica_kicks(rate, mean, two_sided, t_end, seed=17, index=3)
    n = t.size
    assert abs(n - rate * t_end) < 4 * math.sqrt(rate * t_end)  # Poisson count
    size = np.abs(z)
    assert abs(size.mean() - mean) < 4 * mean / math.sqrt(n)    # exponential: sd = mean
    if two_sided:
        assert abs(np.mean(z > 0) - 0.5) < 4 * 0.5 / math.sqrt(n)
    else:
        assert np.all(z > 0)
    gaps = np.diff(t)
    assert abs(gaps.mean() - 1 / rate) < 4 / rate / math.sqrt(n)
    again = replica_kicks(rate, mean, two_sided, t_end, seed=17, index=3)
    np.testing.assert_array_equal(again[0], t)


# ------------------------------------------------------------------ TOML keys
def test_toml_family_keys():
    doc = {"name": "fam", "model": {**BASE, "gamma": math.inf, "shot": {"rate": 1.0, "mean": 0.5}},
           "experiment": {"v0": [0.0], "t_end": 1.0, "sample_dt": 0.01}}
    exp = experiment_from_dict(doc)
    assert exp.model.shot == ShotNoise(1.0, 0.5) and exp.model.gamma == math.inf
    bad = {**doc, "model": {**BASE, "stribeck": [1.0]}}
    with pytest.raises(ValueError, match="stribeck"):
        experiment_from_dict(bad)


def test_without_noise_removes_every_noise_source():
    for model in (SHOT, SHOT.replace(gamma=10.0), SPRING):
        quiet = map_model(model, CircuitSpec(time_scale=1e-4)).without_noise()
        d = build_deck(quiet, replicas=2, v0=np.zeros(2), t_end=5.0, seed=1, sample_dt=0.01)
        assert "trrandom" not in d.text and "pwl(" not in d.text and d.kicks == ()
        back = quiet.to_model()
        assert back.gamma == math.inf and back.shot is None
