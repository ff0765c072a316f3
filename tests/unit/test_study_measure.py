"""The chapter "What experiments measure" (study.measure, issue 23): on Monte Carlo runs of the
circuit's effective model in place of the circuit (the report's runs, same sizes), every
spectrum band and first-passage row lies within its budget, the budget's terms are the ones
the module docstring names, and the rows' theory values are the exact theory's."""
import math

import numpy as np
import pytest

from analogue.circuit.experiments import load_experiment, standard_circuit
from analogue.montecarlo import simulate_sde
from analogue.report import measure_chapter
from analogue.study.settings import RunOptions, stationary_noise_dt
from analogue.study.runs import ExperimentRuns
from analogue.study import measure as M
from analogue.theory import first_passage as tfp
from analogue.theory import spectrum as tsp

QUICK = RunOptions(quick=True)


def _mc_runs(exp, replicas=250, stationary=32):
    """Held-noise SDE ensembles of the effective model at the circuit's hold, the quick
    report's sizes (the circuit's law: a tanh bridge, noise held for noise_dt)."""
    settings = exp.report.for_options(QUICK)
    mapping = exp.mapping()
    m, hold = mapping.model_effective, mapping.noise_dt

    def sde(noise_dt, *, t_end, replicas, seed, **k):
        per = 8         # fine steps per hold; the held value is the mean of per normals
        n_hold = round(t_end / noise_dt)
        z = np.random.default_rng(seed).standard_normal((replicas, n_hold)) / math.sqrt(per)
        e = simulate_sde(m, sample_dt=exp.sample_dt, dt=noise_dt / per, noise_hold=per,
                         noise=z, t_end=t_end, replicas=replicas, seed=seed, **k)
        e.meta["model_effective"] = m.as_dict()
        return e
    tr = {v0: sde(hold, v0=v0, t_end=exp.t_end, replicas=replicas, seed=exp.seed + i)
          for i, v0 in enumerate(exp.v0)}
    st_hold = stationary_noise_dt(hold, settings)
    st = sde(st_hold, v0="stationary", t_end=settings.stationary_t_end, replicas=stationary,
             seed=exp.seed + 9)
    chk_t = sde(hold, v0=exp.v0[0], t_end=exp.t_end, replicas=8, seed=exp.seed)
    return ExperimentRuns(exp=exp, settings=settings, quick=True, transition=tr, stationary=st,
                          noise_free=chk_t, check_transition=chk_t, check_stationary=st)


@pytest.fixture(scope="module")
def stick():
    exp = load_experiment(standard_circuit("stick"))
    theory = M.measure_theory(exp, exp.report.for_options(QUICK))
    runs = _mc_runs(exp)
    return exp, theory, M.analyse_measure(runs, theory), runs


@pytest.mark.slow
def test_rows_within_budget_on_the_circuits_law(stick):
    """9 rows (5 bands, per v0 the mean and P(T <= t_a)): every one within its budget,
    every budget finite."""
    exp, theory, a, runs = stick
    comps = a.comparisons
    assert [c.observable for c in comps[:5]] == [M.band_label(lo, hi) for lo, hi in
                                                 zip(M.BANDS[:-1], M.BANDS[1:])]
    assert {c.observable for c in comps[5:]} == {
        "first passage mean from v0=2", "P(T<=1.61) from v0=2",
        "first passage mean from v0=-2", "P(T<=1.17) from v0=-2"}
    for c in comps:
        assert math.isfinite(c.budget.total()) and c.circuit_stderr > 0, c.observable
        assert c.within_budget, (c.observable, c.z, c.budget)


@pytest.mark.slow
def test_theory_values_and_terms(stick):
    """The theory values are the exact S band averages and the exact first-passage law; the
    sampling term of a band is E[Welch] - S (exact), of a mean the sampling bias bound; the
    hold lowers the stick spectrum (held minus white < 0 in the lowest band, beyond its SE)."""
    exp, theory, a, runs = stick
    sp = theory.spectrum
    rows = {r.label: r for r in a.rows}
    lo, hi = M.BANDS[0], M.BANDS[1]
    sel = (sp.omega >= lo) & (sp.omega < hi)
    r = rows[M.band_label(lo, hi)]
    assert r.theory == pytest.approx(float(tsp.velocity_spectrum(exp.model, sp.omega[sel]).mean()),
                                     rel=1e-9)
    assert r.sampling == pytest.approx(float(sp.expected[sel].mean()) - r.theory, rel=1e-9)
    # the hold's term is measured, not sinc^2: at the stationary hold T = 0.0033 the linear
    # factor moves this band by ~1e-6 relative, the pair by -0.4 % (the stick regime's
    # variance itself is lowered by the hold)
    d, se = sp.hold[r.label]
    linear = 1.0 - float(tsp.noise_hold_factor(math.sqrt(lo * hi), sp.hold_dt))
    assert d < -2 * se and -d / r.theory > 100 * linear
    m = rows["first passage mean from v0=2"]
    assert m.theory == pytest.approx(tfp.first_passage_mean(exp.model, 2.0), rel=1e-6)
    assert m.sampling == pytest.approx(theory.first_passage[2.0].sampling_bound)
    p = rows["P(T<=1.61) from v0=2"]
    assert p.theory == pytest.approx(1 - tfp.first_passage_survival(exp.model, 2.0,
                                                                    [exp.model.stick_time(2.0)])[0])
    # the crossovers drawn in the figure: 1/tau_m and the sticking rate
    assert sp.crossovers[0] == 1.0 and 1.0 < sp.crossovers[1] < 2.0


def test_slip_rows_use_the_record_end_where_the_noise_free_path_never_stops():
    """Slip from v0 = 2: the noise-free path never stops (t_a = inf) and the exact survival at
    the record's end is 0.34, so there is no mean row and P(T <= 8) is the row."""
    exp = load_experiment(standard_circuit("slip"))
    mean, prob, t = M._fp_labels(2.0, exp.model.stick_time(2.0), exp.t_end,
                                 float(tfp.first_passage_survival(exp.model, 2.0,
                                                                  [exp.t_end])[0]) < M.CENSORED_LIMIT)
    assert mean is None and prob == "P(T<=8) from v0=2" and t == 8.0
    assert measure_chapter.wants(exp)
    user = load_experiment(standard_circuit("slip"))
    object.__setattr__(user, "source", None)     # built in memory: not the paper's file
    assert not measure_chapter.wants(user)


def test_first_passage_values_count_censored_paths_at_the_record_end():
    from analogue import Ensemble
    t = np.arange(5) * 0.5
    v = np.array([[1.0, 0.5, -0.5, 0.2, 0.1],     # crosses at 0.75
                  [1.0, 0.8, 0.6, 0.4, 0.2]])     # never: counted at 2.0
    vals = M.FirstPassageValues("mean", "P", 1.0)(Ensemble(t, v, np.zeros_like(v)))
    assert vals == {"P": 0.5, "mean": pytest.approx((0.75 + 2.0) / 2)}


@pytest.mark.slow
def test_chapter_section_from_the_numbers(stick, tmp_path):
    """The chapter's page section: its table has every row, its text quotes the exact
    numbers (mean time to rest / t_a = 1.477/1.609 and 1.123/1.170), its figures exist."""
    from concurrent.futures import Future
    exp, theory, a, runs = stick
    f: Future = Future()
    f.set_result(theory)
    failures = []

    def attempt(section, stage, fn, experiment=None):
        try:
            return fn(), None
        except Exception as exc:  # recorded, as the pipeline's Failures does
            failures.append((section, stage, exc))
            return None, str(exc)
    res = measure_chapter.chapter([runs], {exp.name: f}, tmp_path, attempt)
    assert not failures
    sec = res.sections[0]
    assert sec.title == measure_chapter.CHAPTER_TITLE and sec.error is None
    assert len(sec.tables[0].rows) == len(a.rows) == 9
    text = " ".join(str(p) for p in sec.paragraphs)
    assert "0.92 and 0.96 of the noise-free stick time" in text
    assert "sticking rate 1.31" in text
    assert {p.path.name for p in sec.figures} == {"spectra_stick.png", "first_passage_stick.png"}


def test_sweep_points_become_comparisons_with_the_datasets_budget():
    """A one-dimensional sweep dataset's points (the layout of analogue.study.sweep) become
    rows with its circuit value, stderr, exact value and budget terms, judged by the report's
    criterion; a point without a value (NaN) is left out."""
    import xarray as xr
    from analogue.study.sweep import BUDGET_TERMS
    a = np.array([0.0, 0.3, 0.6])
    terms = np.zeros((3, len(BUDGET_TERMS)))
    terms[:, BUDGET_TERMS.index("bandwidth")] = [0.001, 0.002, 0.0]
    ds = xr.Dataset({"mean_v": ("a", [0.004, 0.09, np.nan]),
                     "mean_v_stderr": ("a", [0.002, 0.003, 0.004]),
                     "mean_v_theory": ("a", [0.0, 0.1, 0.2]),
                     "mean_v_budget_terms": (("a", "budget_term"), terms)},
                    coords={"a": a, "budget_term": list(BUDGET_TERMS)})
    comps = measure_chapter.sweep_comparisons(ds, "mean_v", "stick")
    assert [c.observable for c in comps] == ["sweep: drift <v> at a=0", "sweep: drift <v> at a=0.3"]
    assert comps[0].z == pytest.approx(2.0) and comps[0].budget.bandwidth == 0.001
    assert comps[0].within_budget                       # 0.004 <= 3 * 0.002 + 0.001
    assert comps[1].within_budget                       # 0.01 <= 3 * 0.003 + 0.002
    assert comps[1].budget.total() == pytest.approx(0.002)


def test_the_sweep_curves_run_with_the_reports_runner(tmp_path, monkeypatch):
    """The chapter's two sweeps get the report's Runner (silent), not its options one by one
    (issue 20: no run options as keywords between the layers); a failed sweep is an error
    line, not an exception."""
    seen = []

    def sweep(exp, vary, **kw):
        seen.append((vary, kw))
        raise RuntimeError("stop")
    monkeypatch.setattr(measure_chapter, "sweep", sweep)
    opts = RunOptions(store=tmp_path / "store", workers=3, timeout=42.0, quick=True)

    def attempt(section, what, fn, name):
        try:
            return fn(), None
        except RuntimeError as exc:
            return None, str(exc)
    comps, figs, errors = measure_chapter.run_sweeps(load_experiment("stick"), opts, tmp_path,
                                                     attempt)
    assert (comps, figs) == ([], []) and len(errors) == len(measure_chapter.SWEEPS) == len(seen)
    for _vary, kw in seen:
        assert set(kw) == {"quick", "runner"} and kw["quick"] is True
        assert kw["runner"] == opts.runner(progress=False)
        assert (kw["runner"].store, kw["runner"].workers, kw["runner"].timeout) == \
            (tmp_path / "store", 3, 42.0)


def test_cli_offers_the_sweep_curves():
    from click.testing import CliRunner
    from analogue.cli import main
    for cmd in ("report", "paper"):
        r = CliRunner().invoke(main, [cmd, "--help"])
        assert r.exit_code == 0 and "--sweeps" in r.output


def test_the_report_starts_its_sweeps_in_the_studys_deck_pool(tmp_path, monkeypatch):
    """With --sweeps the page hands the study its two sweeps as circuit work (issue 22: not
    after the paper's chapters): each with the report's runner, its decks in the study's one
    deck pool behind the paper's and the members' (SWEEP_DECKS), each point a phase; without
    --sweeps, or without the paper's stick experiment, nothing."""
    from analogue.circuit.deck_pool import DeckPool, PoolView
    from analogue.report.pipeline import _Drawer
    from analogue.study.schedule import SWEEP_DECKS, Phases
    from analogue.study.run import StudyResult
    seen = []
    monkeypatch.setattr(measure_chapter, "sweep", lambda exp, vary, **kw: seen.append(
        (exp.name, vary, kw)) or len(seen))
    stick = load_experiment(standard_circuit("stick"))
    pool = DeckPool(1)
    try:
        result = StudyResult(experiments=[stick], members=[], quick=True, phases=Phases(),
                             failures=None, t0=0.0, load0=(0, 0, 0), deck_pool=pool)
        opts = RunOptions(quick=True, sweeps=True, workers=1, store=tmp_path / "s")
        tasks = _Drawer(tmp_path, opts, [stick]).circuit_background(result)
        assert sorted(tasks) == sorted(f"{measure_chapter.SWEEP_PHASE}: {n}"
                                       for n in measure_chapter.SWEEPS)
        assert [fn() for fn in tasks.values()] == [1, 2]
        for (name, vary, kw), (want, _o, _f) in zip(seen, measure_chapter.SWEEPS.values()):
            assert name == "stick" and vary == want and kw["quick"] is True
            assert kw["phases"] is result.phases
            view = kw["runner"].executor
            assert isinstance(view, PoolView) and view.pool is pool
            assert view.priority == SWEEP_DECKS
            assert kw["runner"].store == tmp_path / "s" and kw["runner"].progress is False
        assert _Drawer(tmp_path, RunOptions(quick=True), [stick]).circuit_background(
            result) == {}
        slip = load_experiment(standard_circuit("slip"))
        assert _Drawer(tmp_path, opts, [slip]).circuit_background(result) == {}
    finally:
        pool.shutdown()
