"""Issue 20: every time, range and window of a family member's analysis ("Beyond the paper")
follows from the member's model, not from the shipped members' parameters.

Two exact symmetries of the model pin what "follows from the model" means:

* time units: t -> s t with tau_m -> s tau_m, Delta -> Delta/s, a -> a/s, gamma -> s gamma
  leaves the velocity process unchanged in law (dv/dt picks up 1/s, the noise sqrt(1/s));
  every time of the analysis (run length, work window) must scale by s, every velocity window
  stay put;
* velocity units: v -> c v with Delta -> c Delta, a -> c a, gamma -> gamma/c^2 (tau_m kept);
  every velocity window must scale by c.

The shipped files (circuits/*.toml) are copied with changed parameters, as a user would.
Nothing runs ngspice here.
"""
from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from analogue.circuit.experiments import load_experiment
from analogue.montecarlo import simulate_sde
from analogue.study import members as beyond
from analogue.study import catalogue as C
from conftest import toml_text

ROOT = Path(__file__).resolve().parents[2]


def _copy(name: str, tmp_path: Path, new_name: str, *, experiment=None, circuit=None,
          report=None, drop=(), **model):
    d = tomllib.loads((ROOT / "circuits" / f"{name}.toml").read_text())
    d["name"] = new_name
    d["model"].update(model)
    d["experiment"].update(experiment or {})
    d["circuit"].update(circuit or {})
    if report:
        d.setdefault("report", {}).update(report)
    for k in drop:
        d["experiment"].pop(k, None)
    path = tmp_path / f"{new_name}.toml"
    path.write_text(toml_text(d))
    return load_experiment(path)


def _time_scaled(name: str, tmp_path: Path, s: float):
    d = tomllib.loads((ROOT / "circuits" / f"{name}.toml").read_text())
    m, e = d["model"], d["experiment"]
    stribeck = m.get("stribeck")
    return _copy(name, tmp_path, f"{name}_t{int(s * 10)}", tau_m=m["tau_m"] * s, delta=m["delta"] / s,
                 a=m["a"] / s, gamma=m["gamma"] * s,
                 **({"stribeck": [stribeck[0] / s, stribeck[1]]} if stribeck else {}),
                 experiment={"t_end": e["t_end"] * s, "burn_in": e["burn_in"] * s,
                             "sample_dt": e["sample_dt"] * s,
                             "histogram_times": [t * s for t in e["histogram_times"]]},
                 # the [report] defaults (stationary_t_end 100, burn-in 2) are the user's
                 # to scale
                 report={"stationary_t_end": 100.0 * s, "stationary_burn_in": 2.0 * s})


@pytest.mark.parametrize("name", ["cubic", "stribeck"])
@pytest.mark.parametrize("s", [0.1, 10.0])
def test_times_scale_with_the_model_time_unit(name, s, tmp_path):
    base = _time_scaled(name, tmp_path, 1.0)
    scaled = _time_scaled(name, tmp_path, s)
    assert scaled.model.velocity_scale == pytest.approx(base.model.velocity_scale)
    for quick in (True, False):
        a, b = beyond.member_sizes(base, quick), beyond.member_sizes(scaled, quick)
        assert b.stationary_t_end == pytest.approx(s * a.stationary_t_end, rel=1e-12)
        # samples every 0.02 tau_m, never coarser than 0.02
        assert b.sample_dt == pytest.approx(0.02 * min(1.0, scaled.model.tau_m))
    assert beyond.work_tau(scaled.model) == pytest.approx(s * beyond.work_tau(base.model))
    # velocities are unchanged: the stick window too
    assert beyond.stick_window(scaled) == pytest.approx(beyond.stick_window(base), rel=1e-9)


@pytest.mark.parametrize("c", [0.2, 5.0])
def test_stick_window_scales_with_the_velocity_unit(c, tmp_path):
    base = load_experiment(ROOT / "circuits" / "shot.toml")
    d = tomllib.loads((ROOT / "circuits" / "shot.toml").read_text())
    shot = dict(d["model"]["shot"], mean=d["model"]["shot"]["mean"] * c)
    # (circuit.smoothing is in units of the velocity scale already: kept)
    scaled = _copy("shot", tmp_path, "myshot", delta=0.5 * c, a=0.2 * c, shot=shot)
    assert beyond.stick_window(scaled) == pytest.approx(c * beyond.stick_window(base), rel=1e-9)


def test_stick_window_is_the_report_stick_threshold_and_holds_the_circuit_stuck_state():
    for name in ("cubic", "stribeck", "shot"):
        exp = load_experiment(ROOT / "circuits" / f"{name}.toml")
        m, eps = exp.model, exp.mapping().model_effective.epsilon
        w = beyond.stick_window(exp)
        assert w >= exp.report.stick_threshold * m.velocity_scale
        if abs(m.a) < m.static_friction:   # the bridge holds a stuck object here
            assert w > 2 * eps * math.atanh(abs(m.a) / m.static_friction)
    # shot.toml: 0.1 sqrt(tau_m rate mean^2) = 0.05, the window it always had
    assert beyond.stick_window(load_experiment(ROOT / "circuits" / "shot.toml")) == \
        pytest.approx(0.05)


def test_shot_transition_stuck_row_uses_one_window_in_estimator_and_theory(tmp_path):
    """Estimator and theory of "P(v=0) at t" read the same window, the member's."""
    exp = _copy("shot", tmp_path, "wideshot", delta=5.0, a=2.0,
                shot={"rate": 1.0, "mean": 5.0, "two_sided": False})
    thr = beyond.stick_window(exp)
    assert thr == pytest.approx(0.5)   # 10x shot.toml's, as every velocity
    obs = [o for o in C.member_observables(exp.model, v0=0.0, times=[1.0])
           if o.kind == "P(v=0)" and o.run == C.TRANSITION]
    assert obs
    v = np.array([0.0, 0.3, -0.3, 0.6, 2.0, 0.49, -0.51, 0.1])
    ens_at = type("E", (), {"at": lambda self, t: v})()
    got = C.estimate(obs[0], ens_at, burn_in=0.0, threshold=thr, force=exp.model.force)
    assert got == pytest.approx(np.mean(np.abs(v) < thr))
    grid = np.linspace(-4.0, 4.0, 801)
    f = np.exp(-0.5 * grid ** 2) / math.sqrt(2 * math.pi)
    law = C.law_moments(grid, f, 0.0, window=thr)
    from scipy.special import ndtr
    assert law.p_stuck == pytest.approx(ndtr(thr) - ndtr(-thr), abs=1e-4)


def test_member_without_histogram_times_is_analysed_without_transition_rows(tmp_path):
    exp = _copy("cubic", tmp_path, "notimes", drop=("histogram_times",))
    assert exp.histogram_times == ()
    obs = C.member_observables(exp.model, v0=float(exp.v0[0]), times=exp.histogram_times)
    assert obs and all(o.run == C.STATIONARY for o in obs)
    # (the runs and the report without a transition run: tests/integration/
    # test_member_run_then_report.py, the shot copy)


def test_rate_function_grid_covers_the_work_spread_when_the_mean_is_small(tmp_path):
    """a just above 0 in the stick regime: <w> = F <v> is tiny against the spread of w, and
    mu * linspace(-0.5, 2.5) squeezed the exact curve onto a point while the finite-tau
    estimate spread over the whole work distribution."""
    exp = _copy("cubic", tmp_path, "smalla", a=0.02, delta=0.5, gamma=10.0)
    m = exp.model
    ens = simulate_sde(m, v0=0.0, t_end=30.0, replicas=16, seed=5, sample_dt=0.02)
    d = beyond.rate_function_data(m, ens, 2.0)
    w = np.asarray(d["w"])
    assert np.all(np.isfinite(d["member"])) and np.all(np.diff(w) > 0)
    wc = np.asarray(d["w_circuit"])
    assert wc.size >= 3
    # the exact curve spans the circuit's finite-tau points
    assert w[0] <= wc.min() and w[-1] >= wc.max()
    assert w[0] < d["mean"] < w[-1]


def test_bandwidth_pair_samples_at_the_members_interval(tmp_path, monkeypatch):
    """The held/white Monte Carlo pair of the bandwidth term reads the member's own sample
    interval (0.02 tau_m at tau_m = 0.1), not an absolute 0.02 (10 samples per tau_m)."""
    exp = _time_scaled("cubic", tmp_path, 0.1)
    seen = {}

    def fake_pair(model, **kw):
        seen.update(kw)
        raise RuntimeError("stop")
    monkeypatch.setattr(beyond, "held_noise_pair", fake_pair)
    sizes = beyond.member_sizes(exp, True)
    with pytest.raises(RuntimeError, match="stop"):
        beyond._band(exp, {}, 0.0, 1.0, 8, 1, sample_dt=sizes.sample_dt)
    assert seen["sample_dt"] == pytest.approx(0.002)


def test_spring_first_swing_is_the_same_in_other_velocity_units(tmp_path):
    """A spring copy in velocity units 100x smaller (Delta, a, x0 x 0.01, gamma x 1e4): the same
    noise gives the same paths times 0.01 (Monte Carlo, same seed), so the same first swing.
    The absolute departure threshold |v| > 0.05 never fired there (swing speed ~0.015): every
    half period NaN."""
    c = 0.01
    base = load_experiment(ROOT / "circuits" / "spring.toml")
    m0 = base.model
    small = _copy("spring", tmp_path, "myspring", delta=m0.delta * c, a=m0.a * c,
                  x0=m0.x0 * c, gamma=m0.gamma / c ** 2)
    obs = [o for o in C.member_observables(small.model) if o.kind.endswith("(first swing)")]
    assert len(obs) == 2
    got = {}
    for exp in (base, small):
        ens = simulate_sde(exp.model, v0=0.0, t_end=12.0, replicas=16, seed=9, sample_dt=0.01)
        ens.meta["_x0"] = exp.model.x0
        fns = beyond._estimators(exp, obs, beyond.stick_window(exp))
        got[exp.name] = {o.kind: fns[o.label](ens) for o in obs}
    assert beyond.stick_window(small) == pytest.approx(c * beyond.stick_window(base))
    half = "half period (first swing)"
    assert math.isfinite(got["myspring"][half])
    assert got["myspring"][half] == pytest.approx(got["spring"][half], abs=0.02)
    amp = "amplitude (first swing)"
    assert got["myspring"][amp] == pytest.approx(c * got["spring"][amp], rel=0.02)


def test_bandwidth_pair_of_a_hold_that_does_not_divide_the_run(tmp_path):
    """Found by tests/integration/test_random_experiments.py (a cubic member with tau_m = 2):
    the pair's run length is rounded to whole holds, but the pair samples every
    round(sample_dt / hold) holds, and 333 holds of 0.003 are no whole number of 7-hold
    samples: 'ValueError: t_end=... must be a whole multiple of sample_dt=...'.  The run is
    now rounded to whole samples (unchanged where it already was)."""
    exp = _copy("cubic", tmp_path, "cubic_hold", circuit={"noise_dt": 0.003})
    assert exp.mapping().noise_dt == pytest.approx(0.003)
    fns = {"mean v": lambda e: float(e.v.mean())}
    band = beyond._band(exp, fns, 0.0, 1.0, 8, 1, sample_dt=0.02)
    d, se = band["mean v"]
    assert math.isfinite(d) and math.isfinite(se)
