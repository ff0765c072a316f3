"""The report's schedule (issue 10): circuit runs longest first, experiments compared in the
order their runs complete (the page keeps the given order), the family members' circuit work
only after every paper run, and none of it changes a number.  No ngspice: the "circuit" runs
are SDE ensembles of the circuit's effective model; figures are stubs."""
from __future__ import annotations

import json
import threading
import tomllib
import types
from pathlib import Path

import pytest

from analogue.circuit.experiments import experiment_from_dict, load_experiment, standard_circuit
from analogue.montecarlo import simulate_sde
from analogue.report import pipeline as P
from analogue.study import run as S
from analogue.study import schedule as SCH
from analogue.study.comparisons import analyse
from analogue.report.html import Section
from analogue.report.plan import RunOptions
from analogue.study.runs import ExperimentRuns

ROOT = Path(__file__).resolve().parents[2]


def _exp(name: str, stationary_t_end: float, seed: int):
    d = tomllib.loads((ROOT / "circuits" / "stick.toml").read_text())
    d["name"] = name
    d["experiment"].update(t_end=2.0, histogram_times=[0.5, 2.0], seed=seed, replicas=32)
    d["report"].update(stationary_t_end=stationary_t_end, stationary_burn_in=1.0,
                       stationary_replicas=16, prehistory=[[2.0, 0.9, 1.0]])
    return experiment_from_dict(d)


def _fake_runs(exp, opts):
    """SDE ensembles in place of the circuit's (a function of the experiment alone)."""
    settings = exp.report.for_options(opts)
    m = exp.mapping().model_effective
    kw = dict(sample_dt=exp.sample_dt)

    def sde(**k):
        e = simulate_sde(m, **k, **kw)
        e.meta["model_effective"] = m.as_dict()
        return e
    tr = {v0: sde(v0=v0, t_end=exp.t_end, replicas=32, seed=exp.seed + i)
          for i, v0 in enumerate(exp.v0)}
    st = sde(v0="stationary", t_end=settings.stationary_t_end, replicas=16, seed=exp.seed + 9)
    chk_t = sde(v0=exp.v0[0], t_end=exp.t_end, replicas=8, seed=exp.seed)
    chk_s = sde(v0="stationary", t_end=settings.stationary_t_end, replicas=8, seed=exp.seed + 9)
    return ExperimentRuns(exp=exp, settings=settings, quick=opts.quick, transition=tr,
                          stationary=st, noise_free=chk_t, check_transition=chk_t,
                          check_stationary=chk_s)


def test_circuit_cost_puts_the_papers_work_experiment_first():
    """At both sizes (measured at --quick: work's runs 58 s, stick's 30 s, slip's 15 s)."""
    exps = [load_experiment(standard_circuit(n)) for n in ("stick", "slip", "work")]
    for quick in (True, False):
        costs = [SCH.circuit_cost(e, RunOptions(quick=quick)) for e in exps]
        assert costs[2] > max(costs[:2])


def test_gated_task_waits_for_every_gate_and_is_cancelled_by_close():
    from concurrent.futures import Future
    pool = SCH.Workers(SCH.Phases(), "circuit", 2)
    try:
        g1, g2 = Future(), Future()
        f = pool.submit_after([g1, g2], "family member", "m", lambda: 7)
        g1.set_result(1)
        assert not f.done()
        g2.set_exception(RuntimeError("a failed run opens the gate too"))
        assert f.result(timeout=30) == 7
        g3 = Future()
        late = pool.submit_after([g3], "family member", "n", lambda: 8)
    finally:
        pool.close()
    g3.set_result(1)            # the gate opens after close: cancelled, never left pending
    assert late.cancelled()


@pytest.fixture(params=[1, 2], ids=["one circuit thread", "two circuit threads"])
def schedule(request, tmp_path, monkeypatch):
    """A report of two experiments given as [small, big] (big: longer stationary run) and
    one family member.  With two circuit threads, big's runs wait (up to 120 s) until small's
    comparisons have started: the main thread must take small's runs first."""
    threads = request.param
    monkeypatch.setattr(S, "CIRCUIT_THREADS", threads)
    # a small machine's schedule (members after the paper's runs), whatever runs the test
    monkeypatch.setattr(SCH, "usable_cpus", lambda: 2)
    monkeypatch.setenv("ANALOGUE_THEORY_CACHE", str(tmp_path / "theory"))
    big, small = _exp("big", 12.0, 21), _exp("small", 6.0, 22)
    events: list = []
    small_compared = threading.Event()
    lock = threading.Lock()

    def runs(exp, opts, settings=None, on_stationary=None):
        with lock:
            events.append(("runs start", exp.name))
        if exp.name == "big" and threads == 2:
            waited = small_compared.wait(120)  # a hang detector: set within seconds
            with lock:
                events.append(("big waited for small's comparisons", waited))
        r = _fake_runs(exp, opts)
        with lock:
            events.append(("runs done", exp.name))
        return r

    real_analyse = analyse

    def analyse_(runs, **kw):
        with lock:
            events.append(("compare", runs.exp.name))
        if runs.exp.name == "small":
            small_compared.set()
        return real_analyse(runs, **kw)

    def member(exp, opts):
        with lock:
            events.append(("member start", exp.name))
        raise RuntimeError("member stub")

    from analogue.plots.style import new_figure, save
    fig, ax = new_figure()
    png = save(fig, tmp_path / "stub.png")
    def drawn(n):
        with lock:
            events.append(("figure", n))
        return png, n
    for name in ("fig_prehistory", "fig_boundaries", "fig_propagator", "fig_stationary",
                 "fig_work_paths", "fig_rate_function", "fig_budget", "fig_deterministic"):
        monkeypatch.setattr(P.figures, name, lambda *a, n=name, **k: drawn(n))
    monkeypatch.setattr(S, "run_experiment_runs", runs)
    monkeypatch.setattr(S, "analyse", analyse_)
    monkeypatch.setattr(S, "member_task", member)
    monkeypatch.setattr(P, "_open_question_data", lambda opts: None)
    monkeypatch.setattr(P, "_open_question_section",
                        lambda out, opts, data=None: Section("The paper's open question", ["q"]))
    opts = RunOptions(quick=True, progress=False)
    out = tmp_path / "report"
    with pytest.raises(P.ReportIncomplete) as exc:
        P.build_report([small, big], out, opts, title="t",
                       chapter=[load_experiment(standard_circuit("cubic"))])
    return dict(big=big, small=small, opts=opts, out=out, events=events, exc=exc.value,
                threads=threads)


def test_schedule_longest_first_completion_order_members_last(schedule):
    ev = schedule["events"]
    starts = [e[1] for e in ev if e[0] == "runs start"]
    assert starts == ["big", "small"]                     # queued longest first
    compared = [e[1] for e in ev if e[0] == "compare"]
    if schedule["threads"] == 2:                          # in the order the runs complete
        assert ("big waited for small's comparisons", True) in ev
        assert compared == ["small", "big"]
    else:
        assert compared == ["big", "small"]
    # the member's circuit work starts once every paper run is done (issue 22: when ngspice
    # leaves the cores, not after the paper's figures)
    i_member = ev.index(("member start", "cubic"))
    assert {e[1] for e in ev[:i_member] if e[0] == "runs done"} == {"big", "small"}
    # the member's failure is its own section; the page keeps the given order
    assert [f["experiment"] for f in schedule["exc"].failures] == ["cubic"]
    html = (schedule["out"] / "index.html").read_text()
    assert html.index("Experiment &#39;small&#39;") < html.index("Experiment &#39;big&#39;")
    metrics = json.loads((schedule["out"] / "metrics.json").read_text())
    prov = metrics["provenance"]
    assert 0 < prov["paper_wall_time_s"] <= prov["wall_time_s"]
    # two experiments of the user's (not the paper's): their sections, not "the paper's
    # chapters" (issue 20 item 3)
    assert "the experiments&#39; sections were complete after" in html
    assert "the paper&#39;s chapters" not in html


def test_figures_without_curves_are_drawn_once_compared_and_kept_in_order(schedule):
    """The figures that need no theory curve are drawn as soon as the experiment is compared
    (phase "figures: comparisons", before its "figures"); the page keeps one order."""
    metrics = json.loads((schedule["out"] / "metrics.json").read_text())
    phases = {(p["phase"], p["experiment"]): p for p in metrics["provenance"]["phases"]}
    for name in ("small", "big"):
        early, late = phases[("figures: comparisons", name)], phases[("figures", name)]
        assert early["start_s"] + early["seconds"] <= late["start_s"] + 1e-3
        # the curves on a thread of their own, not behind the theory thread's queue
        assert phases[("theory curves", name)]["thread"] == "curves"
    ev = [e[1] for e in schedule["events"] if e[0] == "figure"]
    # per experiment: boundaries, propagator (x2: two v0), budget first, then the curves'
    early_names = ["fig_boundaries", "fig_propagator", "fig_propagator", "fig_budget"]
    late_names = ["fig_prehistory", "fig_stationary", "fig_work_paths", "fig_rate_function"]
    exp_figs = [n for n in ev if n != "fig_deterministic"]
    assert sorted(exp_figs) == sorted(2 * (early_names + late_names))
    html = (schedule["out"] / "index.html").read_text()
    page_order = ["fig_prehistory", "fig_boundaries", "fig_propagator", "fig_propagator",
                  "fig_stationary", "fig_work_paths", "fig_rate_function", "fig_budget"]
    for name in ("small", "big"):
        start = html.index(f"Experiment &#39;{name}&#39;", html.index("</nav>"))
        section = html[start:html.index("<h2", start)]
        caps = [c.split("<")[0] for c in section.split("<figcaption>")[1:]]
        assert caps == page_order


def test_schedule_changes_no_number(schedule):
    """Every comparison of the report is the one analyse() gives on the same runs, computed
    here in this thread from scratch (theory and bandwidth terms included)."""
    from threadpoolctl import threadpool_limits
    metrics = json.loads((schedule["out"] / "metrics.json").read_text())
    want = []
    for exp in (schedule["small"], schedule["big"]):
        # one BLAS thread, as in the report's theory thread (a multi-threaded LAPACK may
        # round differently)
        with threadpool_limits(1):
            a = analyse(_fake_runs(exp, schedule["opts"]), cache=False)
        want += [c.as_dict() for c in a.comparisons]
    assert metrics["comparisons"] == json.loads(json.dumps(want, default=str))


@pytest.mark.parametrize("scheduler, threads", [(None, 1), ("tcp://127.0.0.1:8786", 2)])
def test_one_local_circuit_thread_two_with_a_scheduler(tmp_path, monkeypatch, scheduler, threads):
    """Locally one experiment's runs keep the cores busy; on a Dask cluster (whose workers
    take an experiment's runs one after another) two experiments run at once."""
    seen = {}

    def schedule_(result, opts, hooks, pool, circuit, family, mc=None, page=None, **pools):
        seen.update(circuit=len(circuit.threads), family=len(family.threads))
    monkeypatch.setattr(S, "_schedule", schedule_)
    monkeypatch.setattr(SCH, "usable_cpus", lambda: 2)
    S.run_study([], opts=RunOptions(scheduler=scheduler, progress=False))
    assert seen == {"circuit": threads, "family": SCH.MEMBER_THREADS}


def _members(names):
    return [load_experiment(standard_circuit(n)) for n in names]


def _spy_workers(monkeypatch) -> dict:
    """{pool name: threads} of every Workers the study makes."""
    threads: dict = {}
    real = S.Workers

    def workers(phases, name, n=1, **kw):
        threads[name] = n
        return real(phases, name, n, **kw)
    monkeypatch.setattr(S, "Workers", workers)
    return threads


@pytest.mark.parametrize("cores", [2, 16])
def test_every_deck_of_a_study_goes_to_one_pool_paper_first(monkeypatch, cores):
    """Issue 22, never more ngspice processes than cores: the paper's runs and every member
    get views of the study's one deck pool of `workers` processes (paper's at the first
    priority, members' after), not pools of their own (each member's run started `workers`
    processes beside the others')."""
    monkeypatch.setattr(SCH, "usable_cpus", lambda: cores)
    monkeypatch.setattr(S, "usable_cpus", lambda: cores)
    seen: dict = {}
    lock = threading.Lock()

    def runs(exp, opts, settings=None, on_stationary=None):
        with lock:
            seen[exp.name] = opts.runner().executor
        return _fake_runs(exp, opts)

    def member(exp, opts):
        with lock:
            seen[exp.name] = opts.runner().executor
        raise RuntimeError("member stub")
    monkeypatch.setattr(S, "run_experiment_runs", runs)
    monkeypatch.setattr(S, "analyse", lambda runs, **kw: (_ for _ in ()).throw(
        RuntimeError("not compared here")))
    monkeypatch.setattr(S, "member_task", member)
    result = S.run_study([_exp("small", 6.0, 22)], members=_members(["cubic", "shot"]),
                         opts=RunOptions(quick=True, progress=False))
    pool = result.deck_pool
    assert pool is not None and pool.workers == cores
    assert {v.pool for v in seen.values()} == {pool}
    assert seen["small"].priority == SCH.PAPER_DECKS
    assert seen["cubic"].priority == seen["shot"].priority == SCH.MEMBER_DECKS
    assert SCH.PAPER_DECKS < SCH.MEMBER_DECKS < SCH.SWEEP_DECKS
    # the pool is shut down with the study: nothing more can be queued
    with pytest.raises(RuntimeError, match="shut down"):
        pool.submit(lambda: None)


def test_no_pool_with_a_scheduler(monkeypatch):
    """On a Dask cluster the cluster is the pool: runs keep the runner as it is."""
    seen = {}

    def runs(exp, opts, settings=None, on_stationary=None):
        seen["executor"] = opts.runner().executor
        raise RuntimeError("stub")
    monkeypatch.setattr(S, "run_experiment_runs", runs)
    result = S.run_study([_exp("small", 6.0, 22)],
                         opts=RunOptions(scheduler="tcp://127.0.0.1:8786", progress=False))
    assert result.deck_pool is None and seen == {"executor": None}


@pytest.mark.parametrize("cores", [2, 8, 16])
def test_members_wait_for_the_papers_runs_on_any_machine(monkeypatch, cores):
    """The members start once the paper's circuit runs are done, on MEMBER_THREADS threads,
    whatever the core count: their work beside the decks is Python that takes turns on the GIL
    (measured on 16 cores with the members started at once: their Monte Carlo references
    23-36 s against 2-5 s on 2 cores)."""
    monkeypatch.setattr(SCH, "usable_cpus", lambda: cores)
    monkeypatch.setattr(S, "usable_cpus", lambda: cores)
    events: list = []
    lock = threading.Lock()

    def runs(exp, opts, settings=None, on_stationary=None):
        with lock:
            events.append("runs done")
        raise RuntimeError("stub")

    def member(exp, opts):
        with lock:
            events.append(f"member {exp.name}")
        raise RuntimeError("member stub")
    monkeypatch.setattr(S, "run_experiment_runs", runs)
    monkeypatch.setattr(S, "member_task", member)
    threads = _spy_workers(monkeypatch)
    S.run_study([_exp("small", 6.0, 22)], members=_members(["cubic", "shot", "stribeck"]),
                opts=RunOptions(quick=True, progress=False))
    assert events[0] == "runs done" and len(events) == 4
    assert threads["members"] == SCH.MEMBER_THREADS
    assert threads["circuit"] == 1


@pytest.mark.parametrize("cores", [2, 16])
def test_many_cores_run_the_papers_experiments_at_once_longest_first(monkeypatch, cores):
    """From EXPERIMENTS_AT_ONCE_CORES cores on, a circuit thread per experiment; each
    experiment's decks at its own priority in the pool, longest first, all before the
    members'."""
    monkeypatch.setattr(SCH, "usable_cpus", lambda: cores)
    monkeypatch.setattr(S, "usable_cpus", lambda: cores)
    seen: dict = {}
    lock = threading.Lock()

    def runs(exp, opts, settings=None, on_stationary=None):
        with lock:
            seen[exp.name] = opts.runner().executor.priority
        raise RuntimeError("stub")
    monkeypatch.setattr(S, "run_experiment_runs", runs)
    threads = _spy_workers(monkeypatch)
    S.run_study([_exp("small", 6.0, 22), _exp("big", 12.0, 21), _exp("mid", 9.0, 23)],
                opts=RunOptions(quick=True, progress=False))
    assert threads["circuit"] == (3 if cores >= SCH.EXPERIMENTS_AT_ONCE_CORES else 1)
    assert seen["big"] < seen["mid"] < seen["small"] < SCH.MEMBER_DECKS
    assert seen["big"] == SCH.PAPER_DECKS


def test_members_are_queued_longest_first(monkeypatch):
    """The family members start in the order of their measured cost (issue 22: the spring,
    the longest, queued third, ran alone at the end), whatever order they are given in; the
    result keeps the given order."""
    started: list = []
    monkeypatch.setattr(SCH, "MEMBER_THREADS", 1)
    monkeypatch.setattr(S, "MEMBER_THREADS", 1)
    monkeypatch.setattr(SCH, "usable_cpus", lambda: 2)

    def member(exp, opts):
        started.append(exp.name)
        raise RuntimeError("member stub")
    monkeypatch.setattr(S, "member_task", member)
    names = ["shot", "cubic", "spring", "stribeck"]
    result = S.run_study([], members=[load_experiment(standard_circuit(n)) for n in names],
                         opts=RunOptions(quick=True, progress=False))
    assert started == sorted(names, key=lambda n: -SCH.MEMBER_SECONDS[n])
    assert started[0] == "spring"
    assert [e.name for e in result.members] == names


def test_theory_thread_takes_data_dependent_work_first():
    """A task queued NOW (an experiment's theory curves: its runs are in, its figures wait)
    runs before the circuit-free tasks queued LATER ahead of their need; within a priority,
    in submission order."""
    gate = threading.Event()
    order: list = []
    pool = SCH.Workers(SCH.Phases(), "theory", 1)
    try:
        first = pool.submit("exact theory", "a", lambda: gate.wait(30))
        later = [pool.submit("bandwidth term", n, lambda n=n: order.append(n)) for n in "bc"]
        now = [pool.submit("theory curves", n, lambda n=n: order.append(n), priority=SCH.NOW)
               for n in "xy"]
        gate.set()
        for f in (first, *later, *now):
            f.result(timeout=30)
    finally:
        pool.close()
    assert order == ["x", "y", "b", "c"]


def test_a_phase_records_its_threads_cpu_seconds(monkeypatch):
    """Each phase records its thread's CPU seconds (cpu_s, issue 22 item 4: the job's CPU by
    item) beside its wall time: the thread_time difference over the phase."""
    clock = iter([10.0, 12.5])
    monkeypatch.setattr(SCH.time, "thread_time", lambda: next(clock))
    phases = SCH.Phases(origin=0.0)
    with phases("exact theory", "stick", thread="theory"):
        pass
    (item,) = phases.items
    assert item["cpu_s"] == 2.5
    assert item["phase"] == "exact theory" and item["thread"] == "theory"


def test_the_pages_circuit_work_starts_after_the_paper_runs_not_its_chapters(tmp_path,
                                                                              monkeypatch):
    """The hooks' circuit work (the measurement chapter's sweeps, issue 22) is queued once the
    paper's circuit runs are done, runs beside the comparisons, and its future is handed to
    the page before main_complete, still running: the page waits for it there, in a
    "waiting for" phase of its own."""
    monkeypatch.setenv("ANALOGUE_THEORY_CACHE", str(tmp_path / "theory"))
    events: list = []
    lock = threading.Lock()
    gate = threading.Event()

    def runs(exp, opts, settings=None, on_stationary=None):
        r = _fake_runs(exp, opts)
        with lock:
            events.append("runs done")
        return r

    def sweep():
        with lock:
            events.append("sweep start")
        assert gate.wait(120)       # a hang detector: opened by main_complete
        return 42

    class Hooks(S.StudyHooks):
        handed: dict = {}
        value = None

        def circuit_background(self, result):
            return {"sweep curves": sweep}

        def background_ready(self, result, phase, future):
            with lock:
                events.append(("handed", phase, future.done()))
            self.handed[phase] = future

        def main_complete(self, result):
            with lock:
                events.append("main complete")
            gate.set()
            self.value = self.handed["sweep curves"].result(timeout=120)

    monkeypatch.setattr(S, "run_experiment_runs", runs)
    hooks = Hooks()
    result = S.run_study([_exp("small", 6.0, 22)], opts=RunOptions(quick=True, progress=False),
                         hooks=hooks)
    assert hooks.value == 42
    assert events.index("runs done") < events.index("sweep start")
    assert events.index(("handed", "sweep curves", False)) < events.index("main complete")
    (phase,) = [p for p in result.phases.items if p["phase"] == "sweep curves"]
    assert phase["thread"] == "page circuit"


def test_blas_at_one_thread_for_the_whole_study(monkeypatch):
    """The study's threads (circuit, members, theory, Monte Carlo, main) run beside ngspice:
    BLAS/LAPACK at one thread in every one of them for the whole study (measured on 16 cores:
    a BLAS call per thread started one thread per core), restored after it."""
    from threadpoolctl import threadpool_info

    def blas_threads():
        return {i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"}
    before = blas_threads()
    seen = []

    def runs(exp, opts, settings=None, on_stationary=None):
        seen.append(("runs", blas_threads()))
        raise RuntimeError("stub")

    def member(exp, opts):
        seen.append(("member", blas_threads()))
        raise RuntimeError("stub")
    monkeypatch.setattr(S, "run_experiment_runs", runs)
    monkeypatch.setattr(S, "member_task", member)
    S.run_study([_exp("small", 6.0, 22)], members=_members(["shot"]),
                opts=RunOptions(quick=True, progress=False))
    assert seen and all(t == {1} for _, t in seen), seen
    assert blas_threads() == before


def test_monte_carlo_threads_are_capped(monkeypatch):
    monkeypatch.setattr(SCH, "usable_cpus", lambda: 16)
    pool = SCH.monte_carlo_pool()
    try:
        assert pool._max_workers == SCH.MC_THREADS < 16
    finally:
        pool.shutdown()
    monkeypatch.setattr(SCH, "usable_cpus", lambda: 2)
    pool = SCH.monte_carlo_pool()
    try:
        assert pool._max_workers == min(2, SCH.MC_THREADS)
    finally:
        pool.shutdown()
    monkeypatch.setattr(SCH, "usable_cpus", lambda: 1)
    pool = SCH.monte_carlo_pool()
    try:
        assert pool._max_workers == 1
    finally:
        pool.shutdown()


def test_members_are_handed_to_the_page_as_they_complete(monkeypatch):
    """Each member goes to StudyHooks.member_ready as soon as it is analysed (its figures
    drawn while the others run), in the order they complete; the result keeps the given
    order, and a failed member is recorded, not handed over."""
    monkeypatch.setattr(SCH, "usable_cpus", lambda: 2)
    gate = {"cubic": threading.Event(), "stribeck": threading.Event()}
    events: list = []
    lock = threading.Lock()

    def runs(exp, opts, settings=None, on_stationary=None):
        raise RuntimeError("stub")

    def member(exp, opts):
        if exp.name == "shot":
            raise RuntimeError("member stub")
        if exp.name == "cubic":                      # cubic ends after stribeck is drawn
            assert gate["stribeck"].wait(60)         # (a hang detector: set within seconds)
        with lock:
            events.append(f"done {exp.name}")
        return types.SimpleNamespace(name=exp.name)

    class Hooks(S.StudyHooks):
        def member_ready(self, result, exp, analysis):
            with lock:
                events.append(f"ready {exp.name}")
            assert analysis.name == exp.name
            if exp.name in gate:
                gate[exp.name].set()
    monkeypatch.setattr(S, "run_experiment_runs", runs)
    monkeypatch.setattr(S, "member_task", member)
    result = S.run_study([_exp("small", 6.0, 22)],
                         members=_members(["cubic", "shot", "stribeck"]),
                         opts=RunOptions(quick=True, progress=False), hooks=Hooks())
    assert events.index("ready stribeck") < events.index("done cubic")
    assert [e for e in events if e.startswith("ready")] == ["ready stribeck", "ready cubic"]
    assert list(result.member_analyses) == ["cubic", "stribeck"]
    assert "shot" in result.failed
