"""Board Monte Carlo, calibration and the whole job in ngspice (tiny sizes)."""
import json

import numpy as np
import pytest
from click.testing import CliRunner

from analogue import Model
from analogue.board import noise_chain
from analogue.board.calibration import calibrate_board
from analogue.board.design import design_board
from analogue.board.job import JobSettings, run_board_job
from analogue.board.netlist import build_board_deck, nominal_instance
from analogue.board.runner import run_board
from analogue.board.tolerance import Tolerances, draw_board, effective_model
from analogue.circuit import ngspice as ng
from analogue.cli import main
from analogue.study.metrics import validate_metrics

pytestmark = pytest.mark.slow
STICK = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)
DESIGN = design_board(STICK, v0=[2.0, -2.0])


def test_monte_carlo_board_runs_are_seeded(tmp_path):
    b = draw_board(DESIGN, Tolerances(), 9, 0)
    kw = {"v0": [0.1, -0.1], "t_end": 2.0, "sample_dt": 0.01, "seed": 4, "store": False, "workers": 1}
    e1 = run_board(DESIGN, b, **kw)
    e2 = run_board(DESIGN, draw_board(DESIGN, Tolerances(), 9, 0), **kw)
    assert np.array_equal(e1.v, e2.v)
    e3 = run_board(DESIGN, draw_board(DESIGN, Tolerances(), 9, 1), **kw)
    assert not np.array_equal(e1.v, e3.v)


def test_calibration_recovers_the_parameters_of_a_random_board(tmp_path):
    b = draw_board(DESIGN, Tolerances(), 21, 2)
    eff = effective_model(DESIGN, b)
    cal = calibrate_board(DESIGN, b, seed=3, noise_dir=tmp_path)
    # tolerances: tau_m and Delta from noise-free fits (measured errors 0.07 %, 0.2 %); a
    # carries the ADC offset vos/kappa (<= 10 mV/4.8 V = 0.002); gamma from the regression on
    # the known DAC sequence (measured 0.3 %)
    assert cal.tau_m == pytest.approx(eff.tau_m, rel=3e-3)
    assert cal.delta == pytest.approx(eff.delta, rel=5e-3)
    assert cal.a == pytest.approx(eff.a, abs=4e-3)
    assert cal.gamma == pytest.approx(eff.gamma, rel=1e-2)
    # the bridge width from the stuck velocities at +-Delta/2 (measured 9e-4; the drawn board
    # sits at another temperature, so its width differs from the design's by more)
    assert cal.epsilon == pytest.approx(eff.epsilon, rel=5e-3)
    # and it is closer to the board than the design values are (the board's tolerances moved
    # at least one parameter by more than these errors)
    real = DESIGN.realised
    worst_nominal = max(abs(getattr(real, p) / getattr(eff, p) - 1) for p in ("tau_m", "delta", "gamma"))
    worst_cal = max(abs(getattr(cal, p) / getattr(eff, p) - 1) for p in ("tau_m", "delta", "gamma"))
    assert worst_cal < worst_nominal


def test_ngspice_noise_chain_follows_the_seeded_sequence(tmp_path):
    t_end = 1.0
    deck = build_board_deck(DESIGN, nominal_instance(DESIGN), v0=[0.0], t_end=t_end, sample_dt=0.01,
                            seed=5, noise_dir=tmp_path, save_all=True)
    plot = ng.run_deck(deck.text, t_stop=t_end * DESIGN.theta, files=deck.noise_files).plot
    # R_N runs from the Bessel output (no AC-coupling capacitor by default, issue 21 item 6)
    i_spice = (plot["v(bo0)"] - plot["v(sj0)"]) / DESIGN.values["R_N"]
    n = int(np.ceil(t_end * DESIGN.theta / DESIGN.noise_ts)) + 2
    seq = noise_chain.dac_sequence(DESIGN, 5, 0, n)
    t, cur = noise_chain.chain_current(DESIGN.values, np.concatenate([[0.0], seq]), DESIGN.noise_ts)
    grid = np.linspace(2 * DESIGN.noise_ts, t_end * DESIGN.theta - 2 * DESIGN.noise_ts, 3000)
    a, b = np.interp(grid, plot["time"], i_spice), np.interp(grid, t, cur)
    # trajectory by trajectory: the filesource misses some DAC edges by a fraction of a step
    # (measured correlation 0.99)
    assert np.corrcoef(a, b)[0, 1] > 0.97
    assert np.std(a) == pytest.approx(np.std(b), rel=0.03)


TINY = JobSettings(replicas=4, t_end=4.0, burn_in=1.0, pair_replicas=16, integ_replicas=4,
                   boards=2, mc_replicas=2, mc_t_end=3.0, sens_boards=8, cal_ou_t=6.0,
                   rate_points=False)


def test_board_job_writes_every_output(tmp_path):
    # under a directory with capitals and a space, store and output both (ngspice lower-cases
    # the paths it opens: the DAC files must still reach every deck; this was a second whole
    # board job in tests/faults/test_faults_filesource.py)
    root = tmp_path / "Capital Dir"
    index = run_board_job("stick", root / "Board", store=root / "Store", workers=2,
                          settings=TINY, log=lambda *_: None)
    out = index.parent
    for name in ("schematic.svg", "bom.csv", "board.net", "board.kicad_sch", "board.cir",
                 "metrics.json", "index.html"):
        assert (out / name).stat().st_size > 0, name
    metrics = json.loads((out / "metrics.json").read_text())
    validate_metrics(metrics)
    assert len(metrics["boards"]) == 2
    assert len(metrics["bandwidth_study"]) == 8 and metrics["trajectory_check"]["rms"] < 0.01
    assert "<svg" in (out / "schematic.svg").read_text()
    assert (out / "bom.csv").read_text().startswith("references,quantity,value,description,"
                                                    "manufacturer,mpn,second_source,footprint")
    assert (out / "board.net").read_text().startswith('(export (version "E")')
    # every compared observable carries a plausible statistical error (issue 21 item 12: a
    # 4-replica jackknife printed exactly 0, and 0.001 on a stick fraction whose error is about
    # 0.02): with 4 replicas it comes from the SDE ensemble scaled to the run, and a 4 x 4 tau_m
    # run's error exceeds the full job's (32 x 40 tau_m)
    ref = metrics["matching"]["reference_stderr"]
    # the reference error (matching advice, U1's offset limit, the BOM) is the full job's
    # whatever this run's sizes: TINY's burn-in (1) is not FULL's (2)
    from analogue.board import budget
    from analogue.board.job import FULL, reference_stderr
    from analogue.circuit.experiments import load_experiment
    from analogue.study.seeds import SeedPlan
    assert TINY.burn_in != FULL.burn_in
    thr = 0.1 * STICK.velocity_scale
    fn_full = budget.observables_fn(STICK, burn_in=FULL.burn_in, threshold=thr, taus=(1.0,))
    want = reference_stderr(DESIGN, fn_full, seed=SeedPlan(load_experiment("stick").seed).board_pair)
    assert ref == pytest.approx(want, rel=1e-12)
    for c in metrics["comparisons"]:
        assert c["stderr_method"].startswith("SDE ensemble"), c
        assert c["circuit_stderr"] > 2.0 * ref[c["observable"]], c
    bench = metrics["bench"]
    assert bench["common_mode"]["min_margin"] > 0.5
    assert bench["residual_friction"]["relative_to_I0"] < 1e-3
    assert bench["reset_start"]["rms_vs_ic_start"] < 5e-3
    # every part inside its absolute maximum ratings in every bench mode simulated, and every
    # DAQ input current-limited on the board with the supply off
    assert bench["stresses"]["all_ok"], [r for r in bench["stresses"]["rows"] if not r["ok"]]
    assert len(bench["stresses"]["modes"]) == 4
    assert bench["unpowered_inputs"] and all(r["ok"] for r in bench["unpowered_inputs"])
    assert "Bench procedure" in (out / "index.html").read_text()
    deck = (out / "board.cir").read_text()
    assert ".control" not in deck
    assert "Capital" not in deck and "capital" not in deck
    # every calibrated board's gamma is the board's own, within its tolerances (the noise
    # vanished before, when a DAC file under capitals was not found: 1e11-1e15)
    gammas = [b["calibrated"]["gamma"] for b in metrics["boards"]]
    assert gammas and all(5.0 < g < 20.0 for g in gammas), gammas


def test_board_cli_refuses_unknown_experiment(tmp_path):
    res = CliRunner().invoke(main, ["board", "no_such_experiment", "--out", str(tmp_path)])
    assert res.exit_code == 2
    assert "experiment" in res.output
    # a family member the board does not build: one line naming the parameter, nothing written
    res = CliRunner().invoke(main, ["board", "cubic", "--out", str(tmp_path / "cubic")])
    assert res.exit_code == 2 and "cubic" in res.output
    assert not (tmp_path / "cubic").exists()


def test_vendor_model_file_is_validated_and_used(tmp_path):
    lib = tmp_path / "my_amp.lib"
    # a "downloaded" model: a plain one-pole rail-to-rail-input amplifier (the vendor model
    # serves every op-amp, and the servos' inputs sit 2.5 V from a rail)
    lib.write_text("* user's vendor file\n.subckt VENDAMP inp inn vcc vee out\n"
                   "Rin inp inn 1e12\nBgm 0 g i=1e-3*tanh(3*(v(inp)-v(inn)))\nR1 g 0 1e9\n"
                   "C1 g 0 1.6e-11\nEbuf o1 0 g 0 1\nRout o1 out 50\n.ends VENDAMP\n")
    deck = build_board_deck(DESIGN, nominal_instance(DESIGN), v0=[0.5], t_end=0.5, sample_dt=0.01,
                            seed=2, noise_dir=tmp_path, vendor=(lib, "VENDAMP"))
    assert "X1 inp inn vcc vee out VENDAMP" in deck.text and ".include" not in deck.text
    plot = ng.run_deck(deck.text, t_stop=0.5 * DESIGN.theta, files=deck.noise_files).plot
    assert plot.n_points > 10
    bad = tmp_path / "bad.lib"
    bad.write_text(".subckt VENDAMP 1 2 3 4 5\n.ends\n.control\nshell echo hi\n.endc\n")
    with pytest.raises(ValueError, match="forbidden"):
        build_board_deck(DESIGN, nominal_instance(DESIGN), v0=[0.5], t_end=0.5, sample_dt=0.01,
                         seed=2, noise_dir=tmp_path, vendor=(bad, "VENDAMP"))
