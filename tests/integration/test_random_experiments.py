"""Random valid experiments through the whole report (issue 20, "must show"): a seeded
generator draws experiments a user could write (a copy of ``circuits/stick.toml`` with its
``[report]`` section kept, other parameters across an order of magnitude, every model variant:
Gaussian or shot noise, Coulomb, cubic or Stribeck friction, a spring; ideal or real diodes;
stick and slip) and each is reported at a tiny size:

- nothing crashes and no section fails: every figure is drawn, or refused when the file is
  loaded with one line saying what to change;
- every comparison has a finite error budget (and a finite z);
- every number the page's prose gives for a parameter is the experiment's.

The circuit runs are SDE ensembles of the circuit's effective model (the circuit itself has its
own tests; here the report's half is under test): paper-model experiments through
``run_experiment_runs``, members through ``members._member_circuits``.  Everything after the runs
(theory, budgets, comparisons, figures, prose, page) is the report's own code.  One draw (the
first: Gaussian noise on the paper's model) also goes through ngspice itself, calibrations
and integration checks included (:func:`test_one_random_experiment_through_ngspice`).
"""
from __future__ import annotations

import dataclasses
import html as html_lib
import json
import math
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

import analogue
from analogue.circuit.experiments import load_experiment
from analogue.ensemble import Ensemble
from analogue.montecarlo import simulate_sde
from analogue.study import members as M
from analogue.study import run as S
from analogue.study.runs import ExperimentRuns
from conftest import toml_text

ROOT = Path(__file__).resolve().parents[2]
NUM = r"(-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?|inf)"
VARIANTS = ("gaussian", "shot", "cubic", "stribeck", "spring")
N_EXPERIMENTS = 5


def draw_experiment(rng: np.random.Generator, variant: str, i: int) -> dict:
    """A copy of circuits/stick.toml (its [report] section kept) with drawn parameters."""
    d = tomllib.loads((ROOT / "circuits" / "stick.toml").read_text())
    d["name"] = f"random{i}_{variant}"
    d["description"] = f"Random experiment {i}: the {variant} variant."
    # tau_m over a factor 4 (at tau_m = 5 one member's quick analysis alone took 140 s: the
    # report's quick sizes are in units of tau_m); gamma and the kick rate span a factor 10
    tau_m = float(rng.choice([0.5, 1.0, 2.0]))
    delta = float(rng.uniform(0.2, 1.0))
    stick = bool(rng.integers(2))
    a = delta * float(rng.uniform(0.1, 0.8) if stick else rng.uniform(1.3, 3.0))
    a *= float(rng.choice([-1.0, 1.0]))
    m = {"tau_m": tau_m, "delta": round(delta, 3), "a": round(a, 3),
         "gamma": float(round(rng.uniform(5.0, 50.0), 1)), "mass": 1.0}
    d["model"] = m
    d["circuit"]["diode"] = str(rng.choice(["ideal", "1N4148"]))
    if variant == "shot":
        m["gamma"] = math.inf
        m["shot"] = {"rate": float(round(rng.uniform(0.5, 5.0), 2)),
                     "mean": float(round(rng.uniform(0.1, 1.0), 2)), "two_sided": bool(rng.integers(2))}
    elif variant == "cubic":
        m["cubic"] = float(round(rng.uniform(0.2, 2.0), 2))
    elif variant == "stribeck":
        m["stribeck"] = [float(round(rng.uniform(0.2, 1.0), 2)), float(round(rng.uniform(0.1, 0.5), 2))]
        d["circuit"]["smoothing"] = 0.01
    elif variant == "spring":
        m["spring"] = float(round(rng.uniform(0.3, 3.0), 2))
        m["x0"] = float(round(rng.uniform(0.5, 3.0), 2))
        d["circuit"]["time_scale"] = 1e-4
        d["circuit"]["inductor_q"] = 3000.0  # the default 100 leaks: refused at load, naming it
    ex = d["experiment"]
    # (the copied prehistory targets reach t = 3: a shorter run is refused at load)
    ex.update(replicas=32, t_end=4.0 * max(tau_m, 1.0), seed=int(rng.integers(1, 10_000)),
              # (up to one tau_m: a real diode's transition element integrates the exact
              # propagator to each time; to 4 tau_m at tau_m = 2 it took 62 s alone)
              histogram_times=[round(x * tau_m, 6) for x in (0.25, 0.5, 1.0)])
    if variant != "gaussian":
        ex["burn_in"] = 2.0 * tau_m
    d["report"].update(stationary_replicas=16, stationary_t_end=8.0 * tau_m,
                       stationary_burn_in=1.5 * tau_m)
    return d


def _sde(model, **kw) -> Ensemble:
    e = simulate_sde(model, **kw)
    e.meta.update(model_effective=model.as_dict(), ngspice_version="sde", deck_sha256="sde")
    return e


def fake_runs(exp, opts, settings=None, on_stationary=None) -> ExperimentRuns:
    """The runs of a paper-model experiment, from the SDE of the circuit's effective model."""
    settings = exp.report.for_options(opts)
    m = exp.mapping().model_effective
    kw = dict(sample_dt=exp.sample_dt)
    tr = {v0: _sde(m, v0=v0, t_end=exp.t_end, replicas=32, seed=exp.seed + i, **kw)
          for i, v0 in enumerate(exp.v0)}
    st = _sde(m, v0="stationary", t_end=settings.stationary_t_end, replicas=16,
              seed=exp.seed + 9, **kw)
    chk_t = _sde(m, v0=exp.v0[0], t_end=exp.t_end, replicas=8, seed=exp.seed, **kw)
    chk_s = _sde(m, v0="stationary", t_end=settings.stationary_t_end, replicas=8,
                 seed=exp.seed + 9, **kw)
    nf = _sde(m, v0=np.asarray(exp.v0, float), t_end=exp.t_end, replicas=len(exp.v0), seed=1,
              **kw)
    return ExperimentRuns(exp=exp, settings=settings, quick=opts.quick, transition=tr,
                          stationary=st, noise_free=nf, check_transition=chk_t,
                          check_stationary=chk_s)


_NOMINAL: dict = {}


def fake_member_circuit(exp, *, v0, t_end, replicas, seed, sizes, spec=None) -> Ensemble:
    """A member's circuit run, from the SDE of its effective model (the spring's position read
    back as the inductor's would be).  The integration check (``spec`` given) re-runs the
    first rows of the nominal run on the same noise: here, exactly those rows (a zero
    integration difference, as a circuit with no integration error would give)."""
    key = (exp.name, seed, float(t_end))
    if spec is not None:
        e = _NOMINAL[key]
        rec = None if e.records is None else {k: v[:replicas] for k, v in e.records.items()}
        return Ensemble(e.t, e.v[:replicas], e.x[:replicas], dict(e.meta), records=rec)
    m = exp.mapping().model_effective
    e = _sde(m, v0=v0, t_end=t_end, replicas=replicas, seed=seed, sample_dt=sizes.sample_dt)
    if m.spring > 0:
        e = dataclasses.replace(e, records={"x_spring": m.x0 + e.x})
    _NOMINAL[key] = e
    return e


def fake_member_circuits(exp, sizes, runner, runs, t_start):
    """``members._member_circuits`` from the SDE (:func:`fake_member_circuit`): the nominal
    runs first, then the checks (``spec`` given) that re-read their first rows."""
    out = {r.name: fake_member_circuit(exp, v0=r.v0, t_end=r.t_end, replicas=r.replicas,
                                       seed=r.seed, sizes=sizes)
           for r in runs if r.spec is None}
    out.update({r.name: fake_member_circuit(exp, v0=r.v0, t_end=r.t_end, replicas=r.replicas,
                                            seed=r.seed, sizes=sizes, spec=r.spec)
                for r in runs if r.spec is not None})
    return out, {}


def _sections(path: Path) -> dict:
    """The page's sections: title -> text (tags stripped)."""
    parts = re.split(r"<h2[^>]*>(.*?)</h2>", path.read_text())
    return {html_lib.unescape(t): html_lib.unescape(re.sub(r"<[^>]+>", " ", body))
            for t, body in zip(parts[1::2], parts[2::2])}


def _parameter_numbers(text: str, names) -> dict:
    """Every "name = number" of a parameter (not "(a - Delta sgn a) tau_m = v_ss")."""
    out: dict = {}
    for name in names:
        for x in re.findall(rf"(?<![\w/.)])(?<!\) ){re.escape(name)} = {NUM}", text):
            out.setdefault(name, []).append(float(x))
    return out


def _want(m) -> dict:
    d = {"tau_m": m.tau_m, "Delta": m.delta, "a": m.a, "gamma": m.gamma}
    if m.shot is not None:
        d.update(rate=m.shot.rate, mean=m.shot.mean)
    if m.spring:
        d.update(spring=m.spring, x0=m.x0)
    return d


def _experiment(tmp_path: Path, i: int):
    """Experiment i of the draw (seeded by i alone: each can be run on its own)."""
    rng = np.random.default_rng([20, i])
    d = draw_experiment(rng, VARIANTS[i % len(VARIANTS)], i)   # every variant, then again
    path = tmp_path / f"{d['name']}.toml"
    path.write_text(toml_text(d))
    return load_experiment(path)


def _experiments(tmp_path: Path) -> list:
    return [_experiment(tmp_path, i) for i in range(N_EXPERIMENTS)]


def test_the_generator_covers_every_variant_diode_and_regime(tmp_path):
    exps = _experiments(tmp_path)
    kinds = {("shot" if e.model.shot is not None else "spring" if e.model.spring
              else "cubic" if e.model.cubic else "stribeck" if e.model.stribeck is not None
              else "gaussian") for e in exps}
    assert kinds == set(VARIANTS)
    assert {e.spec.diode for e in exps} == {"ideal", "1N4148"}
    assert {abs(e.model.a) < e.model.delta for e in exps} == {True, False}
    taus = [e.model.tau_m for e in exps]
    assert max(taus) / min(taus) >= 4
    gammas = [e.model.gamma for e in exps if math.isfinite(e.model.gamma)]
    assert max(gammas) / min(gammas) >= 2.5


def _check_report(exp, res, out: Path) -> None:
    """What every random experiment's report must show (module docstring)."""
    assert not res.failures.items, res.failures.items
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["comparisons"], exp.name
    for c in res.comparisons:
        assert math.isfinite(c.budget.total()) and math.isfinite(c.z), c
    figs = res.figures[exp.name]
    assert figs and all(p.exists() for p in figs), exp.name
    sections = _sections(res.page)
    # a user's report claims none of the paper's figures or chapters as its own (issue 20 item 3)
    assert not [t for t in sections if t.lower().startswith(("paper", "the paper"))], list(sections)
    # the experiment's own section(s) and the page's opening: the prose about this experiment
    text = " ".join(body for title, body in sections.items()
                    if exp.name in title or title in ("Summary",))
    want = _want(exp.model)
    got = _parameter_numbers(text, want)
    for name in ("tau_m", "Delta", "a"):
        assert name in got, (exp.name, name)
    wrong = [f"page says {name} = {x:g}, the model has {want[name]:g}"
             for name, xs in got.items() for x in xs
             if x != pytest.approx(want[name], rel=2e-3, abs=1e-12)]
    assert not wrong, wrong


@pytest.mark.slow
@pytest.mark.parametrize("i", range(N_EXPERIMENTS))
def test_random_experiment_through_the_whole_report(tmp_path, monkeypatch, i):
    monkeypatch.setenv("ANALOGUE_THEORY_CACHE", str(tmp_path / "theory"))
    monkeypatch.setattr(S, "run_experiment_runs", fake_runs)
    monkeypatch.setattr(M, "_member_circuits", fake_member_circuits)
    exp = _experiment(tmp_path, i)
    out = tmp_path / exp.name
    res = analogue.report(exp, out=out, quick=True)
    _check_report(exp, res, out)


@pytest.mark.slow
@pytest.mark.requires_ngspice
def test_one_random_experiment_through_ngspice(tmp_path, monkeypatch):
    """The first draw (Gaussian noise, the paper's model) with its runs from ngspice, not
    the SDE: tolerance and deck-size calibrations, every run, the integration checks and the
    noise-free run through the circuit, then the same checks on the page.  Measured cold
    (empty store and theory cache) on a shared 2-core machine: 35.8 s at load 15-22, beside
    36.7 s for the same draw from the SDE (the report's theory and analysis dominate, not
    ngspice); 46.5 s at load 5-6 outside pytest.  A member's draw (the cubic one, i = 2)
    took 107.5 s there and is left to the SDE test above."""
    monkeypatch.setenv("ANALOGUE_THEORY_CACHE", str(tmp_path / "theory"))
    exp = _experiment(tmp_path, 0)
    assert VARIANTS[0] == "gaussian" and exp.model.shot is None and not exp.model.spring
    out = tmp_path / exp.name
    runner = analogue.Runner(store=tmp_path / "store", progress=False)
    res = analogue.report(exp, out=out, quick=True, runner=runner)
    _check_report(exp, res, out)
    runs = res.runs[exp.name].by_role()
    for role, ens in runs.items():   # every run is the circuit's
        assert ens.meta["source"] == "circuit", role
        assert ens.meta["ngspice_version"] not in (None, "sde"), role
        assert ens.meta["deck_sha256"], role
