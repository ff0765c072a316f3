"""The weak-noise stationary law of the cubic and Stribeck members in "Beyond the paper"
(issue 9, Report; analogue.theory.weak_noise_family): exp(-gamma U)/Z from the
quasi-potential against the exact grid law, the minima of U against the noise-free fixed
points (roots found here by brentq), and the member text's weak-noise sentence."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from analogue.circuit.experiments import load_experiment
from analogue.report import beyond
from analogue.study import members
from analogue.report.family_figures import fig_member_stationary
from analogue.theory import family


def _member(name):
    exp = load_experiment(f"circuits/{name}.toml")
    m = exp.model
    v, dens, atom = family.stationary_law(m, h=members._h(exp) / 2)
    assert atom == 0.0
    return exp, m, v, dens, beyond.weak_noise_law(m, v, dens)


def _slide(m):
    # the stable sliding fixed point: v/tau_m + cubic v^3 + Delta(v) = a, the larger root
    # (Stribeck: the smaller, unstable one lies below v = 0.3; g(0.5) < 0 for both members)
    def g(x):
        return x / m.tau_m + m.cubic * x ** 3 + float(m.friction_magnitude(np.array(x))) - m.a
    return brentq(g, 0.5, 10.0)


@pytest.mark.parametrize("name", ["cubic", "stribeck"])
def test_weak_noise_law_is_the_exact_law(name):
    exp, m, v, dens, r = _member(name)
    wn = r["weak_noise_density"]
    assert np.trapezoid(wn, v) == pytest.approx(1.0, rel=1e-12)
    # exp(-gamma U) is exact at every gamma for 1-D Gaussian members and stationary_law is
    # exp(-gamma U)/Z with the exact Z: the L1 distance is the trapezoid's normalisation error
    # of the weak-noise law alone (the cusp at v = 0; measured 4.8e-7 cubic, 3.3e-5 stribeck)
    assert r["weak_noise_l1"] == pytest.approx(abs(1.0 - np.trapezoid(dens, v)), abs=1e-9)
    assert r["weak_noise_l1"] < 1e-4
    h = float(np.max(np.diff(v)))
    mins = np.asarray(r["u_minima"])
    assert abs(mins[np.argmin(r["u_at_minima"])] - _slide(m)) <= h
    assert min(r["u_at_minima"]) < 1e-3
    if name == "cubic":
        # slip regime (a > Delta): one well, at the slide
        assert mins.size == 1 and r["u_barrier_tops"].size == 0
    else:
        # Stribeck, Delta < a < delta_s: sticking (cusp at 0) and sliding both stable
        assert mins.size == 2 and abs(mins[0]) <= h
        u0 = float(m.potential(np.array(0.0)) - m.potential(np.array(_slide(m))))
        assert r["u_at_minima"][0] == pytest.approx(u0, abs=1e-6)
        assert r["u_barrier_tops"][0] > r["u_at_minima"][0]


@pytest.mark.parametrize("name", ["cubic", "stribeck"])
def test_weak_noise_text_and_figure(name, tmp_path):
    exp, m, v, dens, r = _member(name)
    f = {"weak_noise_l1": r["weak_noise_l1"], "u_minima": list(r["u_minima"]),
         "u_at_minima": list(r["u_at_minima"]), "u_barrier_tops": list(r["u_barrier_tops"])}
    text = beyond.weak_noise_text(m, f)
    assert "exp(-gamma U)" in text and "eq. (16)" in text
    if name == "cubic":
        assert "not free" in text and "single minimum" in text
    else:
        # a = 0.7 <= delta_s = 1: sticking is free; bimodal: eq. (64) does not apply
        assert "Delta(0) = 1 (here a = 0.7: free)" in text and "eq. (64)" in text

    class A:  # the analysis' fields the figure reads
        pass
    a = A()
    a.exp = exp
    s = family.sample_stationary(m, 400, seed=1)
    a.figures = {"stationary": {"v": v, "density": dens, "atom": 0.0, "samples": s,
                                "threshold": 0.05, "atom_measured": 0.0,
                                "label": name, **r}}
    path, cap = fig_member_stationary(a, tmp_path)
    assert path.exists() and "weak-noise law exp(-gamma U)/Z" in cap and "minima of U" in cap
