"""Decks: structure, injection safety, experiments, and ngspice runs checked pathwise against
the model integrated with the very noise the circuit recorded."""
import hashlib
import re
import subprocess
import tomllib
from pathlib import Path

import numpy as np
import pytest

from analogue import Model
from analogue.circuit import CircuitSpec, Deck, build_deck, map_model
from analogue.circuit.experiments import (CIRCUITS_DIR, experiment_from_dict, experiment_names,
                                          load_experiment, regenerate_netlists)
from analogue.circuit.rawfile import read_raw
from conftest import STICK_A02

pytestmark = pytest.mark.requires_ngspice


def deck_for(spec=None, replicas=3, seed=7, **kw):
    args = dict(replicas=replicas, v0=np.linspace(-1.0, 1.0, replicas), t_end=1.0, seed=seed,
                sample_dt=0.01)
    args.update(kw)
    return build_deck(map_model(STICK_A02, spec), **args)


def run(deck: Deck, tmp_path: Path):
    (tmp_path / "deck.cir").write_text(deck.text)
    proc = subprocess.run(["ngspice", "-b", "-r", "out.raw", "deck.cir"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "error" not in (proc.stdout + proc.stderr).lower()
    plot = read_raw(tmp_path / "out.raw")[0]
    t = plot["time"] / deck.time_scale
    v = plot.columns(deck.vectors["v"]) * deck.to_model_v
    x = plot.columns(deck.vectors["x"]) * deck.to_model_x
    nz = plot.columns(deck.vectors["noise"]) * deck.to_model_noise
    return t, v, x, nz


# ------------------------------------------------------------------ structure
@pytest.mark.parametrize("spec", [CircuitSpec(), CircuitSpec(diode="BAT54"),
                                  CircuitSpec(coulomb="behavioural"), CircuitSpec(coulomb="behavioural-sgn")])
def test_deck_structure(spec):
    d = deck_for(spec, replicas=3, seed=42)
    lines = d.text.splitlines()
    assert d.text.endswith(".end\n") and lines[-1] == ".end"
    assert d.sha256 == hashlib.sha256(d.text.encode()).hexdigest()
    assert not re.search(r"^\s*\.(control|endc)", d.text, re.I | re.M)
    opts = [l for l in lines if l.lower().startswith(".options")]
    assert len(opts) == 1 and "seed=42" in opts[0].split()
    tran = [l for l in lines if l.lower().startswith(".tran")]
    assert len(tran) == 1 and tran[0].split()[-1] == "uic"
    assert float(tran[0].split()[1]) == pytest.approx(0.01 * d.time_scale)
    assert float(tran[0].split()[2]) == pytest.approx(1.0 * d.time_scale)
    saves = [l for l in lines if l.lower().startswith(".save")]
    assert len(saves) == 1
    assert set(saves[0].split()[1:]) == set(d.vectors["v"] + d.vectors["x"] + d.vectors["noise"])
    assert d.vectors["v"] == ["v(v0)", "v(v1)", "v(v2)"]
    for names in d.vectors.values():
        assert all(n == n.lower() for n in names)
    assert d.replicas == 3 and d.seed == 42
    assert deck_for(spec, replicas=3, seed=42).text == d.text  # deterministic


@pytest.mark.parametrize("title", ["x\n.control\nshell rm -rf /", "a b", "1abc", "", "a" * 33, "ok;rm",
                                   "x\r.endc", None, 3])
def test_injection_through_title_is_rejected(title):
    with pytest.raises(ValueError, match="title"):
        deck_for(title=title)


@pytest.mark.parametrize("kwargs, name", [
    ({"seed": -1}, "seed"), ({"seed": 1.5}, "seed"), ({"seed": True}, "seed"), ({"seed": "1"}, "seed"),
    ({"replicas": 0}, "replicas"), ({"v0": [0.0, 1.0]}, "v0"), ({"v0": [0.0, np.nan, 1.0]}, "v0"),
    ({"v0": ["0", "1", "2;.control"]}, "v0"), ({"t_end": float("inf")}, "t_end"), ({"t_end": -1.0}, "t_end"),
    ({"sample_dt": 2.0}, "sample_dt"), ({"sample_dt": "0.01\n.control"}, "sample_dt")])
def test_bad_deck_arguments(kwargs, name):
    with pytest.raises(ValueError, match=name):
        deck_for(**kwargs)


def test_v0_beyond_reverse_rating_is_refused():
    with pytest.raises(ValueError, match="v0.*reverse-voltage"):
        deck_for(CircuitSpec(diode="BAT54"), v0=np.array([0.0, 1.0, 5.0]))


# ---------------------------------------------------------------- experiments
def test_standard_experiments():
    assert {"stick", "slip", "work"} <= set(experiment_names())
    stick, slip, work = (load_experiment(n) for n in ("stick", "slip", "work"))
    assert (stick.model.tau_m, stick.model.delta, stick.model.a) == (1.0, 0.7, 0.2)
    assert (slip.model.tau_m, slip.model.delta, slip.model.a) == (1.0, 0.7, 1.2)
    assert (work.model.tau_m, work.model.delta, work.model.a) == (1.0, 1.0, 0.5)
    assert stick.model.regime == "stick" and slip.model.regime == "slip"
    assert work.work_taus and stick.histogram_times
    assert load_experiment(CIRCUITS_DIR / "stick.toml") == stick
    v0 = stick.initial_velocities()
    assert v0.shape == (len(stick.v0) * stick.replicas,)


def test_committed_netlists_are_fresh():
    assert regenerate_netlists(check=True) == []


def base_doc():
    with open(CIRCUITS_DIR / "stick.toml", "rb") as fh:
        return tomllib.load(fh)


@pytest.mark.parametrize("mutate, name", [
    (lambda d: d.update(colour="red"), "colour"),
    (lambda d: d["model"].update(tau=1.0), "model.tau"),
    (lambda d: d["circuit"].update(kappa=1.0), "circuit.kappa"),
    (lambda d: d["experiment"].update(t_stop=1.0), "experiment.t_stop"),
    (lambda d: d["netlist"].update(seed=1), "netlist.seed"),
    (lambda d: d["model"].pop("gamma"), "model.gamma"),
    (lambda d: d["experiment"].pop("v0"), "experiment.v0"),
    (lambda d: d.update(name="x\n.control"), "name"),
    (lambda d: d["experiment"].update(histogram_times=[100.0]), "histogram_times"),
    (lambda d: d["experiment"].update(seed=-3), "seed"),
    (lambda d: d["circuit"].update(diode="1N4001"), "diode"),
    # a smoothing the user sets is kept and checked (unset, it is chosen to fit: issue 20)
    (lambda d: (d["model"].update(gamma=1e4), d["circuit"].update(smoothing=0.02)), "smoothing"),
])
def test_experiment_schema_errors_name_the_key(mutate, name):
    doc = base_doc()
    mutate(doc)
    with pytest.raises(ValueError, match=re.escape(name)):
        experiment_from_dict(doc, where="test.toml")


def test_load_experiment_errors(tmp_path):
    with pytest.raises(ValueError, match="experiment name"):
        load_experiment("nonexistent")
    bad = tmp_path / "bad.toml"
    bad.write_text("name = \n")
    with pytest.raises(ValueError, match="TOML"):
        load_experiment(bad)


# ------------------------------------------------------------------ ngspice runs
def held_values(t, nz, h, n_holds):
    """The noise's held value over each [k h, (k+1) h), read from the raw points inside it."""
    out = np.empty((nz.shape[0], n_holds))
    for k in range(n_holds):
        inside = (t > (k + 1e-6) * h) & (t < (k + 1 - 1e-6) * h)
        vals = nz[:, inside]
        assert vals.shape[1] > 0
        assert np.all(vals == vals[:, :1]), "noise not held constant within a hold interval"
        out[:, k] = vals[:, 0]
    return out


def integrate_model(model, v0, held, h, sub=20):
    """RK4 of dv = -U'(v) dt + eta dt with eta piecewise constant (the recorded held noise);
    also x = integral v.  Returns values at the hold boundaries."""
    v = np.array(v0, dtype=float)
    x = np.zeros_like(v)
    V, X = [v.copy()], [x.copy()]
    dt = h / sub
    for k in range(held.shape[1]):
        f = lambda u: model.drift(u) + held[:, k]
        for _ in range(sub):
            k1 = f(v)
            k2 = f(v + dt / 2 * k1)
            k3 = f(v + dt / 2 * k2)
            k4 = f(v + dt * k3)
            x = x + dt / 6 * (v + 2 * (v + dt / 2 * k1) + 2 * (v + dt / 2 * k2) + (v + dt * k3))
            v = v + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        V.append(v.copy())
        X.append(x.copy())
    return np.array(V).T, np.array(X).T


@pytest.mark.parametrize("spec, tol", [
    (CircuitSpec(reltol=1e-6), 2e-4),
    (CircuitSpec(diode="1N4148"), 1e-3),
    (CircuitSpec(coulomb="behavioural", reltol=1e-6), 2e-4),
])
def test_circuit_follows_model_pathwise_with_recorded_noise(tmp_path, spec, tol):
    """The recorded noise fed to an RK4 integration of the (smoothed) model reproduces the
    circuit's v and x: this checks R, C, I_F, I_Delta, the bridge, kappa, theta, the noise gain
    and the integrator together.  Tolerances: solver error, measured to fall from 3.6e-4 to
    1.8e-5 as reltol goes 1e-4 -> 1e-6 (ideal diodes, kappa = 1 V)."""
    m = map_model(STICK_A02, spec)
    v0 = np.array([2.0, -2.0, 0.5, -0.3, 0.0, 1.0])
    t_end = 2.0
    deck = build_deck(m, replicas=6, v0=v0, t_end=t_end, seed=5, sample_dt=0.01)
    t, v, x, nz = run(deck, tmp_path)
    assert t[-1] == pytest.approx(t_end)
    h = m.noise_dt
    n_holds = int(round(t_end / h))
    held = held_values(t, nz, h, n_holds)
    V, X = integrate_model(m.model_effective, v0, held, h)
    grid = np.arange(1, n_holds + 1) * h  # ngspice's uic run writes no t = 0 point
    vc = np.array([np.interp(grid, t, row) for row in v])
    xc = np.array([np.interp(grid, t, row) for row in x])
    assert np.max(np.abs(vc - V[:, 1:])) < tol
    assert np.max(np.abs(xc - X[:, 1:])) < tol


def test_noise_is_reproducible_gaussian_and_independent(tmp_path):
    m = map_model(STICK_A02)
    replicas, t_end = 8, 2.0
    deck = build_deck(m, replicas=replicas, v0=np.zeros(replicas), t_end=t_end, seed=99, sample_dt=0.01)
    for name in ("a", "b", "c"):
        (tmp_path / name).mkdir()
    t1, v1, _, nz1 = run(deck, tmp_path / "a")
    t2, v2, _, nz2 = run(deck, tmp_path / "b")
    assert np.array_equal(t1, t2) and np.array_equal(v1, v2) and np.array_equal(nz1, nz2)
    other = build_deck(m, replicas=replicas, v0=np.zeros(replicas), t_end=t_end, seed=100, sample_dt=0.01)
    t3, _, _, nz3 = run(other, tmp_path / "c")
    h = m.noise_dt
    n = int(round(t_end / h))
    held = held_values(t1, nz1, h, n)
    held3 = held_values(t3, nz3, h, n)
    assert not np.allclose(held, held3)
    # variance of the held values: std error sqrt(2/(N-1)) relative
    N = held.size
    ratio = held.var() / m.noise_stddev**2
    assert abs(ratio - 1.0) < 4 * np.sqrt(2.0 / (N - 1))
    assert abs(held.mean()) < 4 * m.noise_stddev / np.sqrt(N)
    # independence: correlations between replicas and between successive holds ~ N(0, 1/n)
    c = np.corrcoef(held)
    off = c[~np.eye(replicas, dtype=bool)]
    assert np.max(np.abs(off)) < 4.5 / np.sqrt(n)  # 28 pairs: 4.5 sigma keeps the family-wise rate small
    lag1 = np.mean(held[:, 1:] * held[:, :-1]) / held.var()
    assert abs(lag1) < 4 / np.sqrt(replicas * (n - 1))


# ------------------------------------------------------------------ edge cases (issue 4)
OU = Model(tau_m=1.0, delta=0.0, a=0.5, gamma=10.0)
ELEMENTS = [CircuitSpec(), CircuitSpec(diode="1N4148"), CircuitSpec(diode="BAT54"),
            CircuitSpec(coulomb="behavioural"), CircuitSpec(coulomb="behavioural-sgn")]


@pytest.mark.parametrize("spec", ELEMENTS)
def test_zero_delta_deck_has_no_coulomb_element(spec):
    """Delta = 0: the deck builds (it used to fail on an infinite .ic value of the bridge's
    inner nodes) and holds only C, R, the force and noise sources and the integrator; with no
    diodes there is no reverse-voltage limit on v0 either."""
    m = map_model(OU, spec)
    d = build_deck(m, replicas=3, v0=np.array([-50.0, 0.0, 50.0]), t_end=1.0, seed=3, sample_dt=0.01)
    text = d.text.lower()
    assert "coulomb" not in text and ".model" not in text and "bridge" not in text
    assert not re.search(r"^\s*[db]\w*\s", text, re.M)  # no diode, no B-source
    ic = [l for l in d.text.splitlines() if l.lower().startswith(".ic")][0]
    assert ic.split()[1:] == ["v(v0)=-50", "v(x0)=0", "v(v1)=0", "v(x1)=0", "v(v2)=50", "v(x2)=0"]
    replica = d.text[d.text.lower().index(".subckt replica"):d.text.lower().index(".ends replica")]
    kinds = sorted(l.split()[0][0].lower() for l in replica.splitlines()[1:] if l.strip())
    assert kinds == ["c", "c", "g", "g", "i", "r", "v"]
    from analogue.circuit.netlist import bridge_dc_deck
    with pytest.raises(ValueError, match="Delta = 0"):
        bridge_dc_deck(m, 0.1)


@pytest.mark.parametrize("spec", ELEMENTS)
@pytest.mark.parametrize("model", [Model(1.0, 0.7, -1.2, 10.0), Model(1.0, 0.7, 0.7, 10.0),
                                   Model(2.0, 0.7, 0.0, 10.0, mass=3.0)])
def test_edge_decks_are_finite_and_signed(model, spec):
    """Negative force, a = Delta, a = 0 with tau_m, mass != 1: every number in the deck is
    finite and the force source carries the sign of a."""
    m = map_model(model, spec)
    d = build_deck(m, replicas=2, v0=np.array([-1.0, 1.0]), t_end=1.0, seed=1, sample_dt=0.01)
    assert "inf" not in d.text.lower() and "nan" not in d.text.lower()
    force = [l for l in d.text.splitlines() if l.lower().startswith("iforce")][0]
    assert float(force.split()[-1]) == pytest.approx(m.i_force, rel=1e-14)
    assert np.sign(float(force.split()[-1])) == np.sign(model.a)


def test_v0_rating_refusal_states_the_limit():
    spec = CircuitSpec(diode="BAT54")
    m = map_model(STICK_A02, spec)
    with pytest.raises(ValueError, match=r"v0.*reverse-voltage.*keep \|v0\| below") as exc:
        deck_for(spec, v0=np.array([0.0, 1.0, 5.0]))
    limit = float(re.search(r"below ([0-9.e+-]+)", str(exc.value)).group(1))
    assert limit == pytest.approx(30.0 / m.kappa, rel=1e-2)
    deck_for(spec, v0=np.array([0.0, -0.99 * limit, 0.99 * limit]))


@pytest.mark.parametrize("model, spec", [
    (OU, CircuitSpec(reltol=1e-6)),                        # Delta = 0 through the default bridge spec
    (Model(1.0, 0.7, -1.2, 10.0), CircuitSpec(reltol=1e-6)),  # negative force, slip to v < 0
    (Model(1.0, 1e-12, 0.5, 10.0), CircuitSpec(reltol=1e-6)),  # tiny Delta: ideal IS ~ 1e-22 A
])
def test_edge_circuits_follow_model_pathwise(tmp_path, model, spec):
    """ngspice runs of the edge cases against RK4 of the model driven by the recorded noise
    (as test_circuit_follows_model_pathwise_with_recorded_noise; tolerance: solver error)."""
    m = map_model(model, spec)
    v0 = np.array([2.0, -2.0, 0.0])
    t_end = 1.0
    deck = build_deck(m, replicas=3, v0=v0, t_end=t_end, seed=11, sample_dt=0.01)
    t, v, x, nz = run(deck, tmp_path)
    h = m.noise_dt
    n_holds = int(round(t_end / h))
    held = held_values(t, nz, h, n_holds)
    V, X = integrate_model(m.model_effective, v0, held, h)
    grid = np.arange(1, n_holds + 1) * h
    vc = np.array([np.interp(grid, t, row) for row in v])
    xc = np.array([np.interp(grid, t, row) for row in x])
    assert np.max(np.abs(vc - V[:, 1:])) < 2e-4
    assert np.max(np.abs(xc - X[:, 1:])) < 2e-4
