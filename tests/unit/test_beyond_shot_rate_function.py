"""The shot-noise member's work rate function in "Beyond the paper" (issue 9, Report): the
figure data of circuits/shot.toml (pure one-sided shot noise, gamma = inf), built from an
event-driven Monte Carlo ensemble in place of the circuit's stationary run (no ngspice)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from analogue.circuit.experiments import load_experiment
from analogue.montecarlo import simulate_sde
from analogue.report import beyond
from analogue.report.family_figures import fig_member_rate_function


@pytest.fixture(scope="module")
def shot_data():
    exp = load_experiment("circuits/shot.toml")
    m = exp.model
    assert m.shot is not None and not math.isfinite(m.gamma) and not m.shot.two_sided
    ens = simulate_sde(m, v0=0.0, t_end=45.0, replicas=24, seed=11, sample_dt=0.01)
    return exp, beyond.rate_function_data(m, ens, burn=5.0)


def test_shot_rate_function_data(shot_data):
    exp, d = shot_data
    m = exp.model
    w, J = np.asarray(d["w"]), np.asarray(d["member"])
    assert d["pure_shot"] and d["ylabel"] == "J(w)" and d["scale"] == 1.0
    assert "paper" not in d  # no paper's curve at gamma = inf
    assert np.all(np.isfinite(J))
    # the grid starts at the edge of the support (the kicks only push up, stuck state 0):
    # there J = rate, the probability e^{-rate tau} of no kick in the whole window
    assert w[0] == d["edge"] == 0.0
    assert J[0] == pytest.approx(m.shot.rate, rel=1e-12)
    # J >= 0, zero at <w> (on the grid: w[3] = <w>), convex on the grid
    assert w[3] == pytest.approx(d["mean"])
    assert J[3] == 0.0 and np.all(J >= 0.0)
    assert np.all(np.diff(J, 2) >= -1e-9)
    # J at the largest w lies below the asymptotic line's slope: its chord slope over the last
    # step is less than k_pole = 1/(F tau_m mean) (convex, asymptotically linear with slope
    # k_pole from below)
    k_pole = 1.0 / (m.force * m.tau_m * m.shot.mean)
    assert d["k_pole"] == pytest.approx(k_pole)
    assert 0.0 < (J[-1] - J[-2]) / (w[-1] - w[-2]) < k_pole
    # the asymptote curve is matched at the grid's last point
    wa, asy = np.asarray(d["w_asymptote"]), np.asarray(d["asymptote"])
    i = int(np.argmin(np.abs(wa - w[-1])))
    assert abs(wa[i] - w[-1]) < (wa[1] - wa[0]) and asy[i] == pytest.approx(J[-1], abs=0.05)
    # the finite-tau estimate is scaled by tau alone (gamma = inf): shifted to minimum 0 and
    # on the scale of J (a factor gamma would make it 0 or inf)
    rc = np.asarray(d["rate_circuit"])
    assert rc.min() == 0.0 and 0.05 < rc.max() < 5.0
    assert d["tau"] == beyond.work_tau(m) == 4.0 * m.tau_m


def test_shot_rate_function_figure(shot_data, tmp_path):
    exp, d = shot_data

    class A:  # the analysis' fields the figure reads
        pass
    a = A()
    a.exp, a.figures = exp, {"rate_function": d}
    path, cap = fig_member_rate_function(a, tmp_path)
    assert path.exists() and path.stat().st_size > 0
    assert "J(w)" in cap and "no 1/gamma" in cap and "-ln P_tau(w)/tau " in cap
    assert "gamma)" not in cap.split("points:")[1]
