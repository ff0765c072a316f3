"""``analogue.Runner`` (how decks run) and what runs through it, without ngspice: the
constructor's checks, simulate's runner= against its run keywords, the calibrations that no
longer call simulate back (issue 20), and the progress with its time-left estimate."""
from __future__ import annotations

import concurrent.futures as cf
import io
from dataclasses import FrozenInstanceError, dataclass, field

import numpy as np
import pytest

import analogue
from analogue import Ensemble, Model
from analogue.circuit import deck_size as ds
from analogue.circuit import decks as D
from analogue.circuit import runner as R
from analogue.circuit import simulate as S
from analogue.circuit import tolerances as tl
from analogue.circuit.mapping import CircuitSpec
from analogue.circuit.runner import Runner

STICK = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)


# ------------------------------------------------------------------------- the object
def test_runner_is_public_frozen_and_lists_in_dir() -> None:
    assert analogue.Runner is Runner is analogue.circuit.Runner
    assert "Runner" in dir(analogue)
    r = Runner(store=False, workers=2, timeout=5)
    with pytest.raises(FrozenInstanceError):
        r.workers = 3  # type: ignore[misc]
    assert r.replace(workers=3).workers == 3 and r.workers == 2
    cal = Runner(store=False, workers=2, replicas_per_deck=8, progress=True,
                 label="x").for_calibration()
    assert (cal.workers, cal.progress, cal.label, cal.replicas_per_deck) == (2, False, None,
                                                                              None)


@pytest.mark.parametrize("kw, kind, words", [
    ({"workers": 0}, ValueError, "workers must be"),
    ({"workers": 1.5}, TypeError, "workers must be"),
    ({"replicas_per_deck": 0}, ValueError, "replicas_per_deck must be"),
    ({"timeout": 0}, ValueError, "timeout must be"),
    ({"timeout": float("nan")}, ValueError, "timeout"),
    ({"progress": "yes"}, TypeError, "progress must be True, False or None"),
    ({"label": "a\nb"}, ValueError, "label must be a printable str"),
    ({"label": 3}, TypeError, "label must be a printable str"),
    ({"store": 3}, TypeError, "store must be a directory path"),
    ({"store": ""}, ValueError, "store must be a directory path"),
    ({"scheduler": "tcp://host:99999"}, ValueError, "port 1-65535"),
    ({"scheduler": 3}, TypeError, "scheduler must be a Dask scheduler address"),
    ({"executor": "pool"}, TypeError, "executor must be a concurrent.futures.Executor"),
])
def test_bad_runner_arguments_are_named(kw, kind, words) -> None:
    with pytest.raises(kind, match=words):
        Runner(**kw)


def test_scheduler_and_executor_together_are_refused() -> None:
    with cf.ThreadPoolExecutor(1) as pool, pytest.raises(ValueError, match="not both"):
        Runner(store=False, scheduler="tcp://127.0.0.1:8786", executor=pool)


@pytest.mark.parametrize("kw", [{"workers": 2}, {"store": False}, {"timeout": 10.0},
                                {"progress": False}, {"label": "x"},
                                {"replicas_per_deck": 4}])
def test_runner_and_run_keywords_together_are_refused(kw) -> None:
    with pytest.raises(TypeError, match="either runner= or the run keywords"):
        analogue.simulate(STICK, v0=0.0, t_end=1.0, replicas=2, seed=0,
                          runner=Runner(store=False), **kw)


def test_runner_must_be_a_runner() -> None:
    with pytest.raises(TypeError, match="runner must be an analogue.Runner"):
        analogue.simulate(STICK, v0=0.0, t_end=1.0, replicas=2, seed=0,
                          runner={"workers": 2})  # type: ignore[arg-type]


# -------------------------------------------------------- calibrations and simulate
def _fake_ensemble(replicas: int, points: float) -> Ensemble:
    t = np.linspace(0.0, 1.0, 3)
    v = np.tile(np.linspace(-1.0, 1.0, replicas)[:, None], (1, 3))
    return Ensemble(t, v, np.zeros_like(v), {"deck_raw_points": [points], "wall_time": 0.1})


def test_calibrations_run_through_run_ensemble_never_simulate(monkeypatch) -> None:
    """simulate -> tolerances / deck_size -> simulate was a loop (issue 20).  With simulate
    itself made to fail, a run large enough for both calibrations still goes through: they
    and the run itself use decks.run_ensemble, each with the caller's runner."""
    real = S.simulate

    def no_recursion(*args, **kwargs):
        raise AssertionError("simulate was called back by a calibration")
    monkeypatch.setattr(S, "simulate", no_recursion)
    monkeypatch.setattr(analogue, "simulate", no_recursion, raising=False)
    calls: list = []

    def fake_run(model, spec, *, v0, t_end, replicas, seed, sample_dt, runner, **kw):
        calls.append((spec, replicas, runner))
        return _fake_ensemble(replicas, 10.0 * runner.replicas_per_deck)
    for mod in (tl, ds, S):
        monkeypatch.setattr(mod, "run_ensemble", fake_run, raising=False)
    tl._MEMO.clear()
    ds._MEMO.clear()
    try:
        runner = Runner(store=False, workers=1, timeout=7.0)
        ens = real(STICK, v0=0.0, t_end=200.0, replicas=400, seed=1, sample_dt=1.0,
                   runner=runner)
    finally:
        tl._MEMO.clear()
        ds._MEMO.clear()
    n_tol = len(tl.CANDIDATES) + 1          # the candidates and the reference
    assert len(calls) == n_tol + len(ds.CAL_SIZES) + 1
    cal = calls[:-1]
    # every calibration run: the caller's store, processes and deck time limit, silent
    assert all(r.store is False and r.workers == 1 and r.timeout == 7.0 and
               r.progress is False for _, _, r in cal)
    assert [r.replicas_per_deck for _, _, r in cal[:n_tol]] == [tl.CAL_DECK] * n_tol
    assert [r.replicas_per_deck for _, _, r in cal[n_tol:]] == list(ds.CAL_SIZES)
    spec, replicas, run = calls[-1]
    assert replicas == 400 and not spec.unset_tolerances
    assert run.replicas_per_deck in ds.SIZES and run.timeout == 7.0
    assert ens.replicas == 400


def test_choosers_without_run_calibrate_through_run_ensemble(monkeypatch) -> None:
    """The choosers need no simulate handed in any more (issue 20): called directly, they
    run their calibration with the runner given, or one made of the run options."""
    seen: list = []

    def fake_run(model, spec, *, replicas, runner, **kw):
        seen.append(runner)
        return _fake_ensemble(replicas, 10.0 * runner.replicas_per_deck)
    monkeypatch.setattr(tl, "run_ensemble", fake_run)
    monkeypatch.setattr(ds, "run_ensemble", fake_run)
    tl._MEMO.clear()
    ds._MEMO.clear()
    try:
        c = tl.choose_tolerances(STICK, CircuitSpec(), replicas=16, t_end=1.0, store=False,
                                 timeout=9.0)
        d = ds.choose_deck_size(STICK, CircuitSpec(**c.tolerances.as_dict()),
                                replicas=512, t_end=10.0, workers=2,
                                runner=Runner(store=False, workers=1))
    finally:
        tl._MEMO.clear()
        ds._MEMO.clear()
    assert c.source == "measured" and d.source == "measured"
    assert {r.timeout for r in seen[:len(tl.CANDIDATES) + 1]} == {9.0}
    assert [r.workers for r in seen[len(tl.CANDIDATES) + 1:]] == [1] * len(ds.CAL_SIZES)
    with pytest.raises(TypeError, match="either runner= or the run options"):
        tl.choose_tolerances(STICK, CircuitSpec(), replicas=16, t_end=1.0, store=False,
                             runner=Runner(store=False))
    with pytest.raises(TypeError, match="run must be callable"):
        tl.choose_tolerances(STICK, CircuitSpec(), replicas=16, t_end=1.0, run="ngspice")


def test_run_ensemble_refuses_anything_left_to_choose() -> None:
    with pytest.raises(ValueError, match="tolerances set"):
        D.run_ensemble(STICK, CircuitSpec(), v0=0.0, t_end=1.0, replicas=1, seed=0,
                       sample_dt=0.1, runner=Runner(store=False, replicas_per_deck=1))
    with pytest.raises(ValueError, match="replicas_per_deck"):
        D.run_ensemble(STICK, CircuitSpec(reltol=1e-3, trtol=7.0, method="gear"), v0=0.0,
                       t_end=1.0, replicas=1, seed=0, sample_dt=0.1, runner=Runner(store=False))


# ------------------------------------------------------------------------- progress
def test_eta_from_finished_deck_times() -> None:
    # 10 decks, 4 done at 2 s each, 3 processes: 6 left x 2 s / 3 = 4 s
    assert R.eta_seconds([1.0, 3.0, 2.0, 2.0], 10, 3) == pytest.approx(4.0)
    # fewer decks left than processes: they run side by side, one deck's time
    assert R.eta_seconds([2.0] * 9, 10, 4) == pytest.approx(2.0)
    assert R.eta_seconds([], 5, 2) is None                # nothing finished: no estimate
    assert R.eta_seconds([None, None], 5, 2) is None      # no times known
    assert R.eta_seconds([None, 4.0], 4, 1) == pytest.approx(8.0)
    assert R.eta_seconds([1.0] * 3, 3, 2) == 0.0
    with pytest.raises(ValueError, match="more than total"):
        R.eta_seconds([1.0] * 4, 3, 2)
    with pytest.raises(ValueError, match="workers must be"):
        R.eta_seconds([1.0], 3, 0)


def test_progress_line_and_durations() -> None:
    assert R.format_duration(42.4) == "42 s"
    assert R.format_duration(200) == "3 min 20 s"
    assert R.format_duration(7500) == "2 h 05 min"
    assert R.progress_line("stick", 12, 40, 65.0, 130.0) == \
        "stick: 12/40 decks done, 1 min 05 s, about 2 min 10 s left"
    assert R.progress_line("stick", 0, 40, 1.0, None) == "stick: 0/40 decks done, 1 s"


@dataclass
class _Deck:
    """A hand-written deck (the Deck protocol) whose 'ngspice' is the executor below."""
    replicas: int
    text: str
    vectors: dict = field(default_factory=lambda: {"v": ["v1"], "x": ["x1"]})
    to_model_v: float = 1.0
    to_model_x: float = 1.0
    time_scale: float = 1.0


class _Instant(cf.Executor):
    """Returns each deck's result at once, as if its ngspice had run for 2 s."""

    def submit(self, fn, /, *args, **kwargs):
        task = args[0]
        fut: cf.Future = cf.Future()
        n = task.v0.size
        fut.set_result({"v": np.zeros((n, task.times.size)), "x": np.zeros((n, task.times.size)),
                        "info": {"wall_time": 2.0, "raw_points": 5, "ngspice_version": "fake"}})
        return fut


def test_progress_lines_report_decks_done_of_total_and_time_left(monkeypatch) -> None:
    monkeypatch.setattr(D._ng, "ngspice_version", lambda: "fake")
    monkeypatch.setattr(R, "PROGRESS_EVERY_S", 0.0)       # a line per deck, for the test
    monkeypatch.setattr(R.sys, "stderr", io.StringIO())   # not a terminal: plain lines
    decks = [_Deck(1, f"deck {b}") for b in range(3)]
    times = np.linspace(0.0, 1.0, 4)
    D.run_decks(decks, times, np.zeros(3), store=False, workers=1, progress=True,
                label="lbl", executor=_Instant())
    err = R.sys.stderr.getvalue().splitlines()
    assert err[0].startswith("lbl: 1/3 decks done, ") and err[0].endswith("about 4 s left")
    assert err[1].startswith("lbl: 2/3 decks done, ") and err[1].endswith("about 2 s left")
    assert err[2].startswith("lbl: 3 decks (0 from the store, 3 run) in ")
    assert len(err) == 3
