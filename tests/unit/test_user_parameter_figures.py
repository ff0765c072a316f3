"""Issue 20 items 1 and 2: a user's own parameters in the paper's figures.

A copy of circuits/stick.toml with tau_m = 2, Delta = 0.5, a = 0.3, gamma = 15 and a real
diode: its stick time from v0 = 2 is t_a = tau_m ln(1 + v0/(tau_m (Delta - a))) = 2 ln 6 = 3.58,
after Fig. 5's former constant example time t = 3 (the report failed after all its circuit
work).  Every time and range of the figures must come from the model; what cannot be drawn is
refused when the file is loaded; every prehistory target is reported with its path count.
"""
from __future__ import annotations

import logging
import math
import re
import tomllib
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from analogue import Model
from analogue.circuit.experiments import experiment_from_dict
from analogue.montecarlo import simulate_sde
from analogue.plots.paper_theory import fig5_layout
from analogue.report import figures
from analogue.report.plan import ReportSettings
from analogue.study.theory_curves import FigureCurves, _prehistory_curves
from analogue.theory import weak_noise
from conftest import toml_text

ROOT = Path(__file__).resolve().parents[2]
USER = {"tau_m": 2.0, "delta": 0.5, "a": 0.3, "gamma": 15.0}


def user_doc(**report) -> dict:
    d = tomllib.loads(toml_text(tomllib.loads((ROOT / "circuits" / "stick.toml").read_text())))
    d["name"] = "mine"
    d["model"].update(USER)
    d["circuit"]["diode"] = "1N4148"
    d["report"].update(report)
    return d


def test_fig5_layout_follows_the_stick_time_of_the_model():
    m = Model(**USER)
    for v0 in (2.0, -2.0, 0.5, 0.0):
        lay = fig5_layout(m, v0)
        # t_a from eq. (31) written out independently of Model.stick_time
        da = m.delta - m.a if v0 > 0 else m.delta + m.a
        assert lay["t_a"] == pytest.approx(m.tau_m * math.log1p(abs(v0) / (m.tau_m * da)), rel=1e-12)
        assert lay["t_a"] < lay["t_example"] < lay["t_max"]
        for kind, v_end in lay["examples"].items():
            assert abs(v_end) < lay["v_lim"]
            # each example path ends on the side of the boundaries its kind names (from rest,
            # v0 = 0, no path crosses: the kinds are named for v0 -> 0+)
            if v0 != 0:
                assert weak_noise.optimal_path(m, v_end, lay["t_example"], v0, n=200).kind == kind
    assert fig5_layout(m, 2.0)["t_a"] == pytest.approx(2 * math.log(6), rel=1e-12)
    # the paper's panel (a): tau_m = 1, Delta = 0.7, a = 0.2, v0 = 2 (t_a+ = ln 5) keeps its
    # times (3.0 and 4.0 in the paper's figure) to 1 %
    paper = fig5_layout(Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0), 2.0)
    assert paper["t_example"] == pytest.approx(3.0, rel=0.01)
    assert paper["t_max"] == pytest.approx(4.0, rel=0.01)
    assert paper["margin"] == pytest.approx(0.8)


def test_fig_boundaries_draws_for_a_user_model(tmp_path):
    exp = experiment_from_dict(user_doc())
    # before: ValueError "t=3.0 is before the stick time t_a"
    path, caption = figures.fig_boundaries(SimpleNamespace(exp=exp), tmp_path)
    assert path.is_file() and path.stat().st_size > 10_000
    t_as = [float(x) for x in re.findall(r"t_a = ([0-9.]+)", caption)]
    assert t_as == pytest.approx([exp.model.stick_time(2.0), exp.model.stick_time(-2.0)], rel=1e-2)


def test_load_refuses_what_the_figures_cannot_draw():
    # work paths without a force (W = F x = 0): refused at load, naming both keys
    d = user_doc(work_paths=[[0.5, 5.0]])
    d["model"]["a"] = 0.0
    with pytest.raises(ValueError, match=r"report\.work_paths .*model\.a") as exc:
        experiment_from_dict(d)
    assert "\n" not in str(exc.value)


def test_prehistory_pair_that_reads_both_ways_is_refused_with_the_fix():
    with pytest.raises(ValueError) as exc:
        experiment_from_dict(user_doc(prehistory=[[2.0, 0.2]]))
    msg = str(exc.value)
    assert "\n" not in msg
    assert "report.prehistory" in msg and "[2.0, 0.2]" in msg and "[2, 2, 0.2]" in msg
    # a pair whose first number is no starting velocity is read as [v, t] from v0[0], and
    # the experiment carries the explicit triple from then on
    exp = experiment_from_dict(user_doc(prehistory=[[0.9, 1.0], [-2.0, 0.5, 1.0]]))
    assert exp.report.prehistory == ((2.0, 0.9, 1.0), (-2.0, 0.5, 1.0))


@pytest.mark.parametrize("entry", [[2.0, 0.5, 1.0, 4.0], [2.0, "0.5", 1.0], [1.0]])
def test_malformed_prehistory_entry_is_named(entry):
    with pytest.raises(ValueError) as exc:
        ReportSettings(prehistory=[[2.0, 0.9, 1.0], entry])
    msg = str(exc.value)
    assert "report.prehistory" in msg and repr(entry) in msg and "[v0, v, t]" in msg


def test_fig_prehistory_reports_every_target_with_its_count(tmp_path, caplog):
    exp = experiment_from_dict(user_doc())          # the copied targets, one unreachable
    m = exp.model
    ens = {v0: simulate_sde(m, v0=v0, t_end=3.0, replicas=200, seed=5) for v0 in exp.v0}
    settings = exp.report
    runs = SimpleNamespace(exp=exp, settings=settings, transition=ens)
    curves = FigureCurves()
    curves.set("prehistory", _prehistory_curves(runs))
    analysis = SimpleNamespace(runs=runs, curves=curves)
    with caplog.at_level(logging.INFO, logger="analogue.report"):
        path, caption = figures.fig_prehistory(analysis, tmp_path, "paths")
    assert path.is_file()
    w = settings.prehistory_window
    for v0, v, t in settings.prehistory:
        i = int(np.argmin(np.abs(ens[v0].t - t)))
        n = int(np.sum(np.abs(ens[v0].v[:, i] - v) < w))   # counted here, independently
        line = f"v0={v0:g} to (v={v:g}, t={t:g})"
        assert f"{n} of 200 circuit paths" in caption.split(line)[1].split(";")[0], (line, caption)
        assert any(line in r.getMessage() and f"{n} of 200" in r.getMessage()
                   for r in caplog.records), line
    # the copied target (v = -0.1, t = 1.3) is out of reach for this model (t_a = 3.58)
    i = int(np.argmin(np.abs(ens[2.0].t - 1.3)))
    assert np.sum(np.abs(ens[2.0].v[:, i] + 0.1) < w) == 0
    assert "No circuit path reached v=-0.1, t=1.3" in caption


def test_fig5_layout_for_stick_models_across_orders_of_magnitude():
    """Seeded sweep: Delta over 1.5 decades, tau_m over 2, a of either sign inside the stick
    regime, v0 of either sign and from rest: every panel has its layout and every example
    path (v0 != 0) has the kind it is drawn as."""
    rng = np.random.default_rng(20)
    for _ in range(60):
        delta = 10 ** rng.uniform(-1.5, 1.0)
        m = Model(tau_m=10 ** rng.uniform(-1.0, 1.0), delta=delta,
                  a=rng.uniform(-0.95, 0.95) * delta, gamma=10.0)
        for v0 in (float(rng.normal(0.0, 3.0)), 0.0):
            lay = fig5_layout(m, v0)
            assert lay["t_a"] < lay["t_example"] < lay["t_max"]
            if v0 != 0:
                for kind, v_end in lay["examples"].items():
                    assert weak_noise.optimal_path(m, v_end, lay["t_example"], v0, n=64).kind \
                        == kind, (m, v0, kind)
