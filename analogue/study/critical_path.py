"""The report job's critical path (issue 22, item 1): the wall time it would take with
unlimited cores, i.e. the longest chain of dependent work, computed from the phase timeline
the report records (``provenance["phases"]``, :class:`analogue.study.schedule.Phases`).

Pure functions over the recorded timeline: :func:`longest_chain` on any dependency graph,
:func:`report_critical_path` with the report's dependencies (as :func:`analogue.study.run.
_schedule` waits on its futures):

- roots (need nothing): an experiment's ``exact theory`` and ``bandwidth term``, the ``open
  question``, its ``circuit runs``, each ``family member`` (its wait for the paper's chapters
  is a choice of schedule on few cores, not a data dependency);
- ``theory curves`` (e) <- ``circuit runs: stationary`` (e): the calibrations and the
  stationary run's longest deck (the curves need that run alone, and start when it is in:
  ``run_experiment_runs(on_stationary=)``); without that record, <- ``circuit runs`` (e);
- ``comparisons`` (e) <- ``circuit runs``, ``exact theory`` and ``bandwidth term`` (e);
- ``figures`` (e) <- ``comparisons`` and ``theory curves`` (e): the figures that draw
  theory curves; ``figures: comparisons`` (e) <- ``comparisons`` (e): the others, drawn
  while the curves compute (a report before that split records ``figures`` alone);
- ``figures: family member`` (m) <- ``family member`` (m): drawn as each member completes;
- ``figures: open question`` <- ``open question``;  ``figures: Fig. 1`` <- every
  ``circuit runs``;
- each ``sweep point`` (the measurement chapter's sweeps) is a root, counted by the seconds
  it records with unlimited cores (``unlimited_s``: its wall less its waits for a free
  ngspice process); the chapter's ``... (sweep curves)`` <- every ``sweep point``;
- ``figures and page`` <- everything else.

The ``waiting for ...`` phases are not work and are left out.  With unlimited cores an
experiment's circuit runs take their work before the decks (tolerance and deck-size
calibrations: where recorded, ``calibration_unlimited_s``, the transition and stationary
runs' calibrations at once, each its tolerance stage's longest deck then its deck-size
stage's, since each stage's decks run at once) plus their longest single deck (``circuit`` timing recorded by
:func:`analogue.study.runs.run_experiment_runs`); without that record, or where it exceeds
the phase, the phase's own duration.  An experiment's bandwidth term likewise takes the seconds its thread spent
drawing the noise and computing the jackknives plus the CPU seconds of its longest Monte
Carlo chunk (:func:`analogue.study.comparisons.bandwidth_terms`; the chunks are independent,
one core each with unlimited cores).  An experiment's theory curves likewise take their
phase less the seconds their thread waited for the work densities' worker processes, plus
the longest of those computations' CPU seconds (:mod:`analogue.study.processes`: a process
has no interpreter lock to share, so with a core of its own it takes its CPU seconds).  A family member counts its parts (the timing record of
:func:`analogue.study.members.analyse_member`): its runs, each its own calibrations then its
longest deck (a run with nothing to calibrate starts its decks at once), or, if longer, its
circuit-free part beside them (theory, Monte Carlo references), then its estimates; without
that record, or where it exceeds the phase, the phase's own duration.  Every duration is a
measured one on the machine that ran the job, so the result is that machine's per-core
speed with unlimited cores, not a prediction for another machine.
"""
from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

#: phases that wait rather than work (excluded from the graph)
WAITING_PREFIX = "waiting for"

CIRCUIT = "circuit runs"
THEORY = "exact theory"
BANDWIDTH = "bandwidth term (held/white Monte Carlo)"
CURVES = "theory curves"
#: an experiment's circuit runs up to its stationary run (a node of its own where the timing
#: says when that run is in: its theory curves start there)
STATIONARY_RUN = "circuit runs: stationary"
COMPARISONS = "comparisons"
FIGURES = "figures"
#: an experiment's figures that need its comparisons alone (drawn while its curves compute)
FIGURES_COMPARED = "figures: comparisons"
MEMBER = "family member (circuit and theory)"
#: a family member's figures, drawn as soon as it is analysed
MEMBER_FIGURES = "figures: family member"
OPEN_QUESTION = "open question (exact rate functions)"
OPEN_QUESTION_FIG = "figures: open question"
FIG1 = "figures: Fig. 1"
PAGE = "figures and page"
SWEEP_POINT = "sweep point"
SWEEP_CURVES_SUFFIX = "(sweep curves)"


def longest_chain(nodes: Mapping) -> tuple[float, list]:
    """``(length, chain)`` of the longest path through a dependency graph.

    ``nodes``: key -> ``(seconds, deps)``, deps an iterable of keys (a key absent from
    ``nodes`` is ignored).  Length is the largest sum of seconds along a chain in which each
    node depends on the one before; ``chain`` lists its keys, first to last.  Raises
    ValueError on a cycle or a negative duration."""
    finish: dict = {}
    best_dep: dict = {}
    state: dict = {}

    def visit(k) -> float:
        if state.get(k) == 2:
            return finish[k]
        if state.get(k) == 1:
            raise ValueError(f"the dependency graph has a cycle through {k!r}")
        state[k] = 1
        seconds, deps = nodes[k]
        if not seconds >= 0:
            raise ValueError(f"phase {k!r} has duration {seconds!r}: must be >= 0")
        start, prev = 0.0, None
        for d in deps:
            if d in nodes and d != k:
                f = visit(d)
                if prev is None or f > start:
                    start, prev = f, d
        finish[k] = start + float(seconds)
        best_dep[k] = prev
        state[k] = 2
        return finish[k]

    if not nodes:
        return 0.0, []
    for k in nodes:
        visit(k)
    end = max(nodes, key=lambda k: finish[k])
    chain = []
    k = end
    while k is not None:
        chain.append(k)
        k = best_dep[k]
    return finish[end], chain[::-1]


def before_decks_s(timing: Mapping) -> float | None:
    """The work before an experiment's decks with unlimited cores: its calibrations'
    ``calibration_unlimited_s`` (each stage's decks at once: its longest) where recorded,
    at most the measured ``before_decks_s``; None without a record."""
    before = timing.get("before_decks_s")
    if before is None:
        return None
    unlimited = timing.get("calibration_unlimited_s")
    return float(before) if unlimited is None else min(float(before), float(unlimited))


def circuit_unlimited_s(phase_seconds: float, timing: Mapping | None) -> float:
    """An experiment's circuit runs with unlimited cores: the work before its decks
    (:func:`before_decks_s`) plus its longest deck run in this job (0 when every deck came
    from the store), at most the phase's measured duration; the phase's duration without a
    timing record."""
    if not timing:
        return phase_seconds
    before = before_decks_s(timing)
    longest = timing.get("longest_deck_s")
    if before is None or longest is None:
        return phase_seconds
    return min(phase_seconds, before + float(longest))


def member_unlimited_s(phase_seconds: float, timing: Mapping | None) -> float:
    """A family member with unlimited cores: its runs (calibrations, then their longest deck:
    :func:`circuit_unlimited_s`; with a record per run (``runs``), the runs at once, each
    its own calibrations then its longest deck) and, beside them from the start, its
    circuit-free part
    (``reference_s``: theory, Monte Carlo references; 0 when not recorded), then its
    estimates (``analysis_s``), at most the phase's measured duration; the phase's duration
    without a complete timing record."""
    if not timing or timing.get("analysis_s") is None:
        return phase_seconds
    runs = circuit_unlimited_s(math.inf, timing)
    if not math.isfinite(runs):
        return phase_seconds
    per_run = timing.get("runs")
    if per_run:
        # its runs at once, each its own calibrations then its longest deck
        runs = float(timing["before_decks_s"]) + max(
            float(r["calibration_s"]) + float(r["longest_deck_s"]) for r in per_run.values())
    parallel = max(runs, float(timing.get("reference_s") or 0.0))
    return min(phase_seconds, parallel + float(timing["analysis_s"]))


def bandwidth_unlimited_s(phase_seconds: float, timing: Mapping | None) -> float:
    """An experiment's bandwidth term with unlimited cores: its thread's own seconds (noise
    draw, jackknives) plus its longest Monte Carlo chunk, at most the phase's measured
    duration; the phase's duration without a timing record."""
    if not timing:
        return phase_seconds
    parts = [timing.get(k) for k in ("draw_s", "jackknife_s", "longest_chunk_s")]
    if any(p is None for p in parts):
        return phase_seconds
    total = 0.0
    for p in parts:
        total += float(p)  # type: ignore[arg-type]  # (None excluded above)
    return min(phase_seconds, total)


def curves_unlimited_s(phase_seconds: float, timing: Mapping | None) -> float:
    """An experiment's theory curves with unlimited cores: the phase less the seconds its
    thread waited for its worker processes, plus the longest worker computation's CPU
    seconds (a core of its own, no interpreter lock shared), at most the phase; the phase
    without a record (curves computed in the thread)."""
    if not timing:
        return phase_seconds
    wait, longest = timing.get("process_wait_s"), timing.get("longest_process_s")
    if wait is None or longest is None:
        return phase_seconds
    return min(phase_seconds, max(0.0, phase_seconds - float(wait)) + float(longest))


def report_graph(phases: Sequence[Mapping], circuit: Mapping | None = None,
                 bandwidth: Mapping | None = None, curves: Mapping | None = None) -> dict:
    """The report's dependency graph (module docstring) from its phase timeline: key
    ``(phase, experiment)`` -> ``(seconds, deps)``.  A phase recorded twice under one key
    (none today) counts its total.  ``circuit``: experiment (or family member) -> its
    circuit timing record (a member's with its ``analysis_s``);
    ``bandwidth``: experiment -> its bandwidth terms' timing record; ``curves``:
    experiment -> its theory curves' record of worker processes."""
    circuit = circuit or {}
    bandwidth = bandwidth or {}
    curves = curves or {}
    secs: dict = {}
    for p in phases:
        if p["phase"].startswith(WAITING_PREFIX):
            continue
        key = (p["phase"], p.get("experiment"))
        # a phase that knows its own seconds with unlimited cores records them (a sweep
        # point: its wall less its waits for a free ngspice process, analogue.study.sweep)
        secs[key] = secs.get(key, 0.0) + float(p.get("unlimited_s", p["seconds"]))
    for key in list(secs):
        if key[0] == CIRCUIT:
            secs[key] = circuit_unlimited_s(secs[key], circuit.get(key[1]))
        elif key[0] == BANDWIDTH:
            secs[key] = bandwidth_unlimited_s(secs[key], bandwidth.get(key[1]))
        elif key[0] == MEMBER:
            secs[key] = member_unlimited_s(secs[key], circuit.get(key[1]))
        elif key[0] == CURVES:
            secs[key] = curves_unlimited_s(secs[key], curves.get(key[1]))
    runs = [k for k in secs if k[0] == CIRCUIT]
    nodes: dict = {}
    # an experiment whose theory curves start with its stationary run (its runs' timing
    # records that run's longest deck): the curves wait for its calibrations and that deck
    stationary = {}
    for key in runs:
        t = circuit.get(key[1]) or {}
        before = before_decks_s(t)
        if t.get("stationary_longest_deck_s") is not None and before is not None:
            stationary[key[1]] = min(secs[key], before + float(t["stationary_longest_deck_s"]))
    for exp, s in stationary.items():
        nodes[(STATIONARY_RUN, exp)] = (s, [])
    for key, s in secs.items():
        phase, exp = key
        if phase == CURVES:
            deps: list = [(STATIONARY_RUN if exp in stationary else CIRCUIT, exp)]
        elif phase == COMPARISONS:
            deps = [(CIRCUIT, exp), (THEORY, exp), (BANDWIDTH, exp)]
        elif phase == FIGURES:
            deps = [(COMPARISONS, exp), (CURVES, exp)]
        elif phase == FIGURES_COMPARED:
            deps = [(COMPARISONS, exp)]
        elif phase == MEMBER_FIGURES:
            deps = [(MEMBER, exp)]
        elif phase == OPEN_QUESTION_FIG:
            deps = [(OPEN_QUESTION, None)]
        elif phase == FIG1:
            deps = runs
        elif phase.endswith(SWEEP_CURVES_SUFFIX):
            deps = [k for k in secs if k[0] == SWEEP_POINT]
        elif phase == PAGE:
            deps = [k for k in secs if k[0] != PAGE]
        else:
            deps = []
        nodes[key] = (s, deps)
    return nodes


def report_critical_path(phases: Sequence[Mapping], circuit: Mapping | None = None,
                         bandwidth: Mapping | None = None,
                         curves: Mapping | None = None) -> dict:
    """``{"critical_path_s": seconds, "chain": [{"phase", "experiment", "seconds"}, ...]}``:
    the report job's wall time with unlimited cores (module docstring), from its recorded
    phases, circuit, bandwidth and theory-curve timings."""
    nodes = report_graph(phases, circuit, bandwidth, curves)
    length, chain = longest_chain(nodes)
    return {"critical_path_s": round(length, 3),
            "chain": [{"phase": k[0], "experiment": k[1], "seconds": round(nodes[k][0], 3)}
                      for k in chain]}


def _step(c: Mapping) -> str:
    where = f" ({c['experiment']})" if c.get("experiment") else ""
    return f"{c['phase']}{where} {c['seconds']:.1f} s"


def critical_path_text(crit: Mapping, wall_s: float) -> str:
    """The page's line: the critical path against the wall time, and its chain."""
    ratio = (f" ({crit['critical_path_s'] / wall_s:.0%} of the wall time {wall_s:.1f} s)"
             if wall_s > 0 else "")
    return f"{crit['critical_path_s']:.1f} s{ratio}: " + " -> ".join(map(_step, crit["chain"]))
