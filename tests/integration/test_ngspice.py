"""ngspice runner: version, raw reader, failures, resampling, delivered noise intensity.

These tests use a hand-written deck (``ou_deck``: an RC node driven by ``trrandom`` noise
plus a VCCS integrator for the position) whose mapping to model units is derived here,
independently of analogue.circuit.mapping / netlist, so the runner is checked on its own.
"""
from __future__ import annotations

import math
import re
import subprocess
from dataclasses import dataclass

import numpy as np
import pytest

from analogue.circuit import ngspice as ng
from analogue.circuit.rawfile import RawPlot, read_raw


# ---------------------------------------------------------------- hand-written OU deck
@dataclass(frozen=True)
class HandDeck:
    """A hand-written deck: just the :class:`analogue.circuit.simulate.Deck` protocol."""

    text: str
    vectors: dict
    to_model_v: float
    to_model_x: float
    time_scale: float
    replicas: int


def ou_deck(*, replicas, v0, t_end, seed, tau_m=1.0, gamma=10.0, noise_dt=0.01,
            sample_dt=0.01, theta=1e-3, cap=1e-6, kappa=1.0):
    """OU velocity dv = -v/tau_m dt + sqrt(2/gamma) dW as a circuit (Delta = 0).

    C dV/dt_c = -V/R + I_n with V = kappa v and t_c = theta t gives tau_m = R C / theta and
    velocity-noise intensity 1/gamma = theta D_I / (C kappa)^2, where a Gaussian current held
    constant over TS with std S has low-frequency intensity D_I = S^2 TS / 2.  Position: a
    VCCS g V into C_x, x = V_x C_x / (g kappa theta); g = 1e-3 S, C_x = 1e-6 F make it 1.
    """
    v0 = np.broadcast_to(np.asarray(v0, dtype=float), (replicas,))
    R = tau_m * theta / cap
    D_I = (cap * kappa) ** 2 / (gamma * theta)
    TS = noise_dt * theta
    S = math.sqrt(2 * D_I / TS)
    g, cx = 1e-3, 1e-6
    lines = ["* hand-written OU test deck", f".options seed={seed} reltol=1e-5 abstol=1e-15"]
    for i in range(replicas):
        lines += [f"C{i} v{i} 0 {cap:.12g}", f"R{i} v{i} 0 {R:.12g}",
                  f"I{i} 0 v{i} trrandom(2 {TS:.12g} 0 {S:.12g} 0)",
                  f"G{i} 0 x{i} v{i} 0 {g:.12g}", f"CX{i} x{i} 0 {cx:.12g}",
                  f"RX{i} x{i} 0 1e15"]
    ic = " ".join(f"v(v{i})={kappa * v0[i]:.12g} v(x{i})=0" for i in range(replicas))
    lines += [f".ic {ic}", f".tran {sample_dt * theta:.12g} {t_end * theta:.12g} uic",
              ".save " + " ".join(f"v(v{i}) v(x{i})" for i in range(replicas)), ".end"]
    return HandDeck(text="\n".join(lines) + "\n",
                    vectors={"v": [f"v(v{i})" for i in range(replicas)],
                             "x": [f"v(x{i})" for i in range(replicas)], "noise": None},
                    to_model_v=1.0 / kappa, to_model_x=cx / (g * kappa * theta),
                    time_scale=theta, replicas=replicas)


def held_ou_variance(t, tau_m, gamma, h):
    """Var v(t) from v(0) fixed, for OU driven by noise held constant over steps h (the
    discretisation trrandom delivers), at t = k h:  (tau_m/gamma) * tanh(x/2)/(x/2) *
    (1 - exp(-2 t/tau_m)), x = h/tau_m.  (Exact sum of the k held-noise kicks.)"""
    x = h / tau_m
    return tau_m / gamma * math.tanh(x / 2) / (x / 2) * (1 - np.exp(-2 * np.asarray(t) / tau_m))


# ------------------------------------------------------------------------- version, PATH
def test_version_matches_ngspice_banner():
    v = ng.ngspice_version()
    assert re.fullmatch(r"\d+(\.\d+)*\+?", v)
    banner = subprocess.run(["ngspice", "-v"], capture_output=True, text=True).stdout
    assert f"ngspice-{v} " in banner or f"ngspice-{v}:" in banner


def test_missing_ngspice_gives_install_hint(monkeypatch, tmp_path):
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(ng.NgspiceNotFoundError, match="apt-get install ngspice"):
        ng.ngspice_version()
    with pytest.raises(ng.NgspiceNotFoundError, match="apt-get install ngspice"):
        ng.run_deck("t\n.end\n")


# --------------------------------------------------------------------------- raw reader
def test_raw_reader_agrees_with_spicelib(tmp_path):
    deck = ou_deck(replicas=3, v0=[0.5, -0.2, 1.0], t_end=0.5, seed=5)
    ng.run_deck(deck.text, keep_dir=tmp_path)
    plots = read_raw(tmp_path / "out.raw")
    assert len(plots) == 1 and "transient" in plots[0].plotname.lower()
    plot = plots[0]
    assert plot.names == ("time", "v(v0)", "v(x0)", "v(v1)", "v(x1)", "v(v2)", "v(x2)")
    from spicelib import RawRead
    ref = RawRead(str(tmp_path / "out.raw"), dialect="ngspice", verbose=False)
    for name in plot.names:
        np.testing.assert_array_equal(plot[name], np.asarray(ref.get_trace(name).get_wave(), float))
    assert plot.n_points > 50
    with pytest.raises(KeyError, match="v\\(nope\\)"):
        plot["v(nope)"]


def test_raw_reader_clips_truncated_data(tmp_path):
    header = ("Title: t\nDate: x\nPlotname: Transient Analysis\nFlags: real\nNo. Variables: 2\n"
              "No. Points: 5\nVariables:\n\t0\ttime\ttime\n\t1\tv(a)\tvoltage\nBinary:\n")
    data = np.arange(7, dtype="<f8")  # 3.5 points written out of 5 declared
    p = tmp_path / "t.raw"
    p.write_bytes(header.encode() + data.tobytes())
    (plot,) = read_raw(p)
    assert plot.n_points == 3
    np.testing.assert_array_equal(plot["time"], [0, 2, 4])
    np.testing.assert_array_equal(plot["v(a)"], [1, 3, 5])


# ------------------------------------------------------------------------------ failures
def test_parse_error_quotes_ngspice():
    deck = "bad\nC1 v1 0 1e-6\nQ1 a b c nosuchmodel\n.tran 1e-5 1e-3 uic\n.end\n"
    with pytest.raises(ng.NgspiceError, match="nosuchmodel"):
        ng.run_deck(deck)


def test_aborted_transient_quotes_ngspice():
    deck = ("abort\nC1 v1 0 1e-12\nB1 v1 0 I=V(v1)>0 ? 1e3 : -1e3\n.ic v(v1)=0.1\n"
            ".tran 1e-5 0.01 uic\n.save v(v1)\n.end\n")
    with pytest.raises(ng.NgspiceError, match="[Tt]imestep too small"):
        ng.run_deck(deck, t_stop=0.01)


def test_timeout_kills_run():
    deck = ou_deck(replicas=20, v0=0.0, t_end=2000.0, seed=1, noise_dt=0.001)
    with pytest.raises(ng.NgspiceError, match="timeout=0.3"):
        ng.run_deck(deck.text, timeout=0.3)


def test_run_deck_rejects_bad_arguments():
    with pytest.raises(ValueError, match="text"):
        ng.run_deck("")
    with pytest.raises(ValueError, match="text"):
        ng.run_deck("title\nR1 1 0 1\n")  # no .end
    with pytest.raises(ValueError, match="timeout"):
        ng.run_deck("t\n.end\n", timeout=0)


# ---------------------------------------------------------------------------- resampling
def _plot(t, cols):
    names = ("time",) + tuple(f"v(c{k})" for k in range(len(cols)))
    return RawPlot("t", "Transient Analysis", "real", names, np.column_stack([t, *cols]))


def test_resample_is_linear_interpolation_with_initial_point():
    t = np.array([1e-3, 2e-3, 2e-3, 5e-3, 1e-2])  # starts after 0, has a repeated breakpoint
    a, b = 3.0 + 2.0 * t * 100, -1.0 + 7.0 * t * 100  # linear in t
    plot = _plot(t, [a, b])
    tq = np.linspace(0.0, 1e-2, 41)
    out = ng.resample(plot, ["v(c1)", "v(c0)"], tq, initial=[-1.0, 3.0])
    np.testing.assert_allclose(out[0], -1.0 + 7.0 * tq * 100, rtol=0, atol=1e-12)
    np.testing.assert_allclose(out[1], 3.0 + 2.0 * tq * 100, rtol=0, atol=1e-12)
    with pytest.raises(ValueError, match="outside the simulated interval"):
        ng.resample(plot, ["v(c0)"], [0.0, 2e-2], initial=[3.0])


# ---------------------------------------------------------------- delivered noise (OU)
@pytest.mark.slow
def test_delivered_noise_intensity_ou():
    """Delta = 0 circuit driven by trrandom: the increment variance at a lag of s = 10 noise
    steps and the stationary variance match the held-noise OU values; errors from the spread of
    per-replica time averages (replicas are independent)."""
    tau, gamma, h = 1.0, 10.0, 0.01
    R, T = 24, 60.0
    deck = ou_deck(replicas=R, v0=0.0, t_end=T, seed=11, tau_m=tau, gamma=gamma, noise_dt=h,
                   sample_dt=h)
    res = ng.run_deck(deck.text, t_stop=T * deck.time_scale)
    times = np.arange(round(T / h) + 1) * h
    v = ng.resample(res.plot, deck.vectors["v"], times * deck.time_scale,
                    initial=np.zeros(R)) * deck.to_model_v
    x = ng.resample(res.plot, deck.vectors["x"], times * deck.time_scale,
                    initial=np.zeros(R)) * deck.to_model_x

    var_inf = float(held_ou_variance(np.inf, tau, gamma, h))
    # Position really is the integral of velocity (trapezoid on the 0.01 grid: O(h^2) error).
    x_trap = np.concatenate([np.zeros((R, 1)), np.cumsum(0.5 * (v[:, 1:] + v[:, :-1]) * h, 1)], 1)
    assert np.max(np.abs(x - x_trap)) < 0.01 * math.sqrt(var_inf) * T ** 0.5

    burn = times >= 5 * tau  # v(0) = 0: wait for e^{-10} of the initial transient
    vs = v[:, burn]
    per_rep_var = np.mean(vs ** 2, axis=1)  # mean is 0 exactly for Delta = a = 0
    est, se = per_rep_var.mean(), per_rep_var.std(ddof=1) / math.sqrt(R)
    assert abs(est - var_inf) < 4 * se, (est, var_inf, se)
    assert se < 0.05 * var_inf  # the test has power

    lag = 10  # s = 10 h = 0.1 tau: increment variance 2 var_inf (1 - e^{-s/tau}) ~ 2 s / gamma
    s = lag * h
    inc = vs[:, lag:] - vs[:, :-lag]
    per_rep_inc = np.mean(inc ** 2, axis=1)
    expect = 2 * var_inf * (1 - math.exp(-s / tau))
    est, se = per_rep_inc.mean(), per_rep_inc.std(ddof=1) / math.sqrt(R)
    assert abs(est - expect) < 4 * se, (est, expect, se)
    assert se < 0.05 * expect
    # and this is the white-noise growth 2 D s (D = 1/gamma) up to the O(s/tau) relaxation
    assert abs(expect / (2 * s / gamma) - 1) < 0.06


def test_terminate_group_stops_only_that_group():
    import threading
    slow = ou_deck(replicas=20, v0=0.0, t_end=2000.0, seed=1, noise_dt=0.001).text
    quick = ou_deck(replicas=1, v0=0.0, t_end=1.0, seed=2).text
    errors = {}

    def target():
        try:
            ng.run_deck(slow, group="g-slow", timeout=60)
        except ng.NgspiceError as exc:
            errors["slow"] = str(exc)

    th = threading.Thread(target=target)
    th.start()
    for _ in range(3000):  # wait (up to 30 s on a busy machine) until the process exists
        if ng._ACTIVE.get("g-slow"):
            break
        threading.Event().wait(0.01)
    assert ng.terminate_group("g-other") == 0
    res = ng.run_deck(quick, group="g-other2")  # another group is unaffected
    assert res.plot.n_points > 10
    assert ng.terminate_group("g-slow") == 1
    th.join(timeout=30)
    assert not th.is_alive()
    assert "stopped by signal" in errors["slow"]
    with pytest.raises(ng.NgspiceError, match="stopped by signal"):
        ng.run_deck(quick, group="g-slow")  # a cancelled group starts nothing new


def test_batch_without_integrator_node_integrates_velocity():
    """run_batch: positions from the deck's integrator node agree with the fallback (trapezoid
    on the simulator's own points) used when a deck has no x vectors."""
    from analogue.circuit.simulate import BatchTask, run_batch
    deck = ou_deck(replicas=3, v0=[0.5, -0.3, 0.0], t_end=4.0, seed=9)
    times = np.arange(401) * 0.01
    common = dict(index=0, text=deck.text, v_names=tuple(deck.vectors["v"]),
                  to_model_v=deck.to_model_v, to_model_x=deck.to_model_x,
                  time_scale=deck.time_scale, times=times, v0=np.array([0.5, -0.3, 0.0]))
    with_node = run_batch(BatchTask(x_names=tuple(deck.vectors["x"]), **common))
    without = run_batch(BatchTask(x_names=None, **common))
    np.testing.assert_array_equal(with_node["v"], without["v"])
    np.testing.assert_array_equal(without["x"][:, 0], 0.0)
    scale = np.max(np.abs(with_node["x"]))
    assert scale > 0.1
    # integrator node (solver reltol 1e-5) vs trapezoid on the solver points
    np.testing.assert_allclose(without["x"], with_node["x"], rtol=0, atol=1e-3 * scale)


def test_run_decks_takes_any_deck_with_the_protocol():
    """run_decks needs only the Deck protocol: the hand-written deck runs through it."""
    from analogue.circuit.simulate import Deck, run_decks
    v0 = np.array([0.5, -0.3])
    deck = ou_deck(replicas=2, v0=v0, t_end=0.5, seed=3)
    assert isinstance(deck, Deck)
    times = np.linspace(0.0, 0.5, 51)
    v, x, noise, info = run_decks([deck], times, v0, store=False, workers=1, progress=False)
    assert v.shape == x.shape == (2, 51) and noise is None and info["ran"] == 1
    np.testing.assert_allclose(v[:, 0], v0)
    np.testing.assert_allclose(x[:, 0], 0.0)
