"""The report's critical path (issue 22, item 1): longest chains on synthetic timelines whose
answers are worked out by hand, and the report's dependencies."""
import pytest

from analogue.study.critical_path import (critical_path_text, longest_chain,
                                           report_critical_path, report_graph)


def test_a_chain_sums_its_durations():
    nodes = {"a": (1.0, []), "b": (2.5, ["a"]), "c": (0.5, ["b"])}
    length, chain = longest_chain(nodes)
    assert length == pytest.approx(4.0)    # 1 + 2.5 + 0.5
    assert chain == ["a", "b", "c"]


def test_fork_join_takes_the_longer_branch():
    # a (1) forks into b (3) and c (5), joined by d (2): 1 + 5 + 2 = 8
    nodes = {"a": (1.0, []), "b": (3.0, ["a"]), "c": (5.0, ["a"]), "d": (2.0, ["b", "c"])}
    length, chain = longest_chain(nodes)
    assert length == pytest.approx(8.0)
    assert chain == ["a", "c", "d"]


def test_parallel_branches_the_longest_wins():
    # x1 -> x2 = 4 + 4 = 8; y1 -> y2 -> y3 = 3 + 3 + 3 = 9; z = 8.5 alone
    nodes = {"x1": (4.0, []), "x2": (4.0, ["x1"]), "y1": (3.0, []), "y2": (3.0, ["y1"]),
             "y3": (3.0, ["y2"]), "z": (8.5, [])}
    length, chain = longest_chain(nodes)
    assert length == pytest.approx(9.0)
    assert chain == ["y1", "y2", "y3"]


def test_unknown_dependencies_are_ignored_and_empty_graph_is_zero():
    assert longest_chain({"a": (2.0, ["gone"])}) == (2.0, ["a"])
    assert longest_chain({}) == (0.0, [])


def test_cycle_and_negative_duration_are_errors():
    with pytest.raises(ValueError, match="cycle"):
        longest_chain({"a": (1.0, ["b"]), "b": (1.0, ["a"])})
    with pytest.raises(ValueError, match="duration"):
        longest_chain({"a": (-1.0, [])})


def _ph(phase, exp, seconds, thread="main"):
    return {"phase": phase, "experiment": exp, "thread": thread, "start_s": 0.0,
            "seconds": seconds}


def _timeline():
    return [
        _ph("exact theory", "e1", 6.0, "theory"),
        _ph("bandwidth term (held/white Monte Carlo)", "e1", 1.0, "theory"),
        _ph("circuit runs", "e1", 20.0, "circuit"),
        _ph("theory curves", "e1", 3.0, "theory"),
        _ph("waiting for theory", "e1", 50.0),          # not work: left out
        _ph("comparisons", "e1", 2.0),
        _ph("figures", "e1", 1.5),
        _ph("exact theory", "e2", 1.0, "theory"),
        _ph("bandwidth term (held/white Monte Carlo)", "e2", 1.0, "theory"),
        _ph("circuit runs", "e2", 4.0, "circuit"),
        _ph("comparisons", "e2", 1.0),
        _ph("theory curves", "e2", 0.5, "theory"),
        _ph("figures", "e2", 1.0),
        _ph("open question (exact rate functions)", None, 9.0, "theory"),
        _ph("figures: open question", None, 1.0),
        _ph("figures: Fig. 1", None, 0.5),
        _ph("family member (circuit and theory)", "m", 12.0, "members"),
        _ph("waiting for family members", "m", 30.0),
        _ph("figures and page", None, 2.0),
    ]


def test_report_path_without_deck_times_uses_the_phases():
    # e1: runs 20 -> curves 3 (> comparisons 2, which also waits for theory 6 < 20)
    # -> figures 1.5 -> page 2 = 26.5; open question 9 + 1 + 2 = 12; member 12 + 2 = 14
    crit = report_critical_path(_timeline())
    assert crit["critical_path_s"] == pytest.approx(26.5)
    assert [(c["phase"], c["experiment"]) for c in crit["chain"]] == [
        ("circuit runs", "e1"), ("theory curves", "e1"), ("figures", "e1"),
        ("figures and page", None)]


def test_report_path_counts_a_deck_batch_as_its_longest_deck():
    # e1's runs with unlimited cores: 1 s of calibrations + its 4 s longest deck = 5 s; then
    # e1: max(runs 5, theory 6, band 1) + comparisons 2 = 8, max(8, 5 + 3) + figures 1.5
    # + page 2 = 11.5; the open question 12 and the member 14 are now longer: 14
    timing = {"e1": {"before_decks_s": 1.0, "longest_deck_s": 4.0},
              "e2": {"before_decks_s": 0.5, "longest_deck_s": 30.0}}  # capped at its 4 s phase
    crit = report_critical_path(_timeline(), timing)
    assert crit["critical_path_s"] == pytest.approx(14.0)
    assert [c["phase"] for c in crit["chain"]] == ["family member (circuit and theory)",
                                                   "figures and page"]
    without_member = [p for p in _timeline() if p["experiment"] != "m"]
    crit = report_critical_path(without_member, timing)
    assert crit["critical_path_s"] == pytest.approx(12.0)   # open question 9 + 1 + page 2
    # the e1 chain through the exact theory: 6 + 2 + 1.5 + 2 = 11.5 < 12
    timing["e1"]["longest_deck_s"] = 3.0   # runs 4: curves end at 7, comparisons at 8
    slow_theory = [dict(p, seconds=10.0) if p["phase"] == "exact theory"
                   and p["experiment"] == "e1" else p for p in without_member]
    crit = report_critical_path(slow_theory, timing)
    assert crit["critical_path_s"] == pytest.approx(15.5)   # 10 + 2 + 1.5 + 2
    assert [c["phase"] for c in crit["chain"]] == ["exact theory", "comparisons", "figures",
                                                   "figures and page"]


def test_fig1_waits_for_every_circuit_run():
    tl = [_ph("circuit runs", "a", 3.0), _ph("circuit runs", "b", 7.0),
          _ph("figures: Fig. 1", None, 1.0), _ph("figures and page", None, 0.5)]
    crit = report_critical_path(tl)
    assert crit["critical_path_s"] == pytest.approx(8.5)     # 7 + 1 + 0.5
    assert "8.5 s (50% of the wall time 17.0 s)" in critical_path_text(crit, 17.0)


def test_bandwidth_term_counts_its_thread_and_longest_chunk():
    """With unlimited cores the bandwidth term's Monte Carlo chunks run at once: its draw and
    jackknives plus its longest chunk, never more than the phase took."""
    tl = [_ph("bandwidth term (held/white Monte Carlo)", "e", 20.0, "theory"),
          _ph("circuit runs", "e", 5.0, "circuit"), _ph("comparisons", "e", 1.0),
          _ph("figures and page", None, 0.5)]
    assert report_critical_path(tl)["critical_path_s"] == pytest.approx(21.5)
    band = {"e": {"draw_s": 2.0, "jackknife_s": 1.0, "longest_chunk_s": 3.0}}
    crit = report_critical_path(tl, None, band)
    assert crit["critical_path_s"] == pytest.approx(7.5)      # 2 + 1 + 3, + 1 + 0.5
    assert crit["chain"][0]["seconds"] == pytest.approx(6.0)
    band["e"]["longest_chunk_s"] = 30.0                        # capped at the phase's 20 s
    assert report_critical_path(tl, None, band)["critical_path_s"] == pytest.approx(21.5)
    assert report_critical_path(tl, None, {"e": {"draw_s": 1.0}})["critical_path_s"] == \
        pytest.approx(21.5)                                    # incomplete record: the phase


def test_member_counts_its_calibrations_longest_deck_and_analysis():
    """A family member with unlimited cores: its runs' calibrations + their longest deck,
    then its analysis after the runs; never more than the phase, and the whole phase without
    a complete record."""
    tl = [_ph("family member (circuit and theory)", "m", 30.0, "members"),
          _ph("family member (circuit and theory)", "n", 8.0, "members"),
          _ph("figures and page", None, 2.0)]
    assert report_critical_path(tl)["critical_path_s"] == pytest.approx(32.0)   # 30 + 2
    timing = {"m": {"before_decks_s": 1.5, "longest_deck_s": 9.0, "decks_run": 5,
                    "analysis_s": 3.5}}
    crit = report_critical_path(tl, timing)
    # m: 1.5 + 9 + 3.5 = 14, + page 2 = 16 (n, with no record, 8 + 2 = 10)
    assert crit["critical_path_s"] == pytest.approx(16.0)
    assert crit["chain"][0] == {"phase": "family member (circuit and theory)",
                                "experiment": "m", "seconds": 14.0}
    timing["m"]["analysis_s"] = 25.0                          # capped at the phase's 30 s
    assert report_critical_path(tl, timing)["critical_path_s"] == pytest.approx(32.0)
    for incomplete in ({"before_decks_s": 1.0, "longest_deck_s": 1.0},      # no analysis
                       {"longest_deck_s": 1.0, "analysis_s": 1.0}):         # no calibrations
        assert report_critical_path(tl, {"m": incomplete})["critical_path_s"] == \
            pytest.approx(32.0)
    # a paper experiment's record (no analysis_s) leaves a member of the same name whole
    tl2 = [_ph("family member (circuit and theory)", "m", 30.0, "members")]
    assert report_critical_path(tl2, {"m": {"before_decks_s": 0.0, "longest_deck_s": 1.0}}
                                )["critical_path_s"] == pytest.approx(30.0)


def test_member_circuit_free_part_runs_beside_its_runs():
    """A member's theory and Monte Carlo references run beside its circuit runs: the longer
    of the two, then its estimates."""
    tl = [_ph("family member (circuit and theory)", "m", 30.0, "members")]
    timing = {"m": {"before_decks_s": 1.0, "longest_deck_s": 6.0, "reference_s": 4.0,
                    "analysis_s": 2.0}}
    assert report_critical_path(tl, timing)["critical_path_s"] == pytest.approx(9.0)  # 7 + 2
    timing["m"]["reference_s"] = 12.0
    assert report_critical_path(tl, timing)["critical_path_s"] == pytest.approx(14.0)  # 12 + 2


def test_member_runs_each_count_their_own_calibrations_and_longest_deck():
    """A member's runs start at once: a run with nothing to calibrate (the integration
    check) does not wait for another run's calibrations."""
    tl = [_ph("family member (circuit and theory)", "m", 40.0, "members")]
    timing = {"m": {"before_decks_s": 0.5, "longest_deck_s": 15.0, "reference_s": 3.0,
                    "analysis_s": 2.0,
                    "runs": {"check": {"calibration_s": 0.0, "longest_deck_s": 15.0},
                             "release": {"calibration_s": 10.0, "longest_deck_s": 3.0}}}}
    # 0.5 + max(0 + 15, 10 + 3) + 2 = 17.5 (calibrations first for all: 0.5 + 10 + 15 + 2)
    assert report_critical_path(tl, timing)["critical_path_s"] == pytest.approx(17.5)
    timing["m"]["runs"]["release"]["longest_deck_s"] = 9.0          # 10 + 9 = 19 > 15
    assert report_critical_path(tl, timing)["critical_path_s"] == pytest.approx(21.5)


def test_theory_curves_wait_only_for_the_stationary_run():
    """The theory curves need the stationary run alone (they start when it is in): with its
    longest deck recorded they follow the calibrations and that deck, not the checks'."""
    tl = [_ph("circuit runs", "e", 20.0, "circuit"), _ph("theory curves", "e", 5.0, "theory"),
          _ph("comparisons", "e", 1.0), _ph("figures", "e", 2.0),
          _ph("figures and page", None, 0.5)]
    timing = {"e": {"before_decks_s": 3.0, "longest_deck_s": 7.0}}
    # runs 3 + 7 = 10 -> curves 5 -> figures 2 -> page 0.5 = 17.5
    assert report_critical_path(tl, timing)["critical_path_s"] == pytest.approx(17.5)
    timing["e"]["stationary_longest_deck_s"] = 2.0
    crit = report_critical_path(tl, timing)
    # max(stationary 3 + 2 + curves 5 = 10, runs 10 + comparisons 1 = 11) + 2 + 0.5 = 13.5
    assert crit["critical_path_s"] == pytest.approx(13.5)
    assert [c["phase"] for c in crit["chain"]] == ["circuit runs", "comparisons", "figures",
                                                   "figures and page"]
    tl[1] = _ph("theory curves", "e", 9.0, "theory")
    crit = report_critical_path(tl, timing)
    assert crit["critical_path_s"] == pytest.approx(16.5)     # 3 + 2 + 9 + 2 + 0.5
    assert crit["chain"][0] == {"phase": "circuit runs: stationary", "experiment": "e",
                                "seconds": 5.0}


def test_sweep_points_count_their_unlimited_seconds_and_the_curves_wait_for_all():
    """A sweep point records its seconds with unlimited cores (its wall less its waits for a
    free ngspice process, analogue.study.sweep): the path takes those, the longest point, and
    the chapter's sweep-curves phase after every point; without the record, the wall."""
    tl = [dict(_ph("sweep point", "stick a=0", 80.0, "sweep"), unlimited_s=6.0),
          dict(_ph("sweep point", "stick a=0.4", 90.0, "sweep"), unlimited_s=7.5),
          _ph("sweep point", "stick a=0.8", 5.0, "sweep"),           # no record: its wall
          _ph("waiting for the sweep curves", None, 85.0),           # not work
          _ph("What experiments measure (sweep curves)", None, 1.0),
          _ph("figures and page", None, 2.0)]
    crit = report_critical_path(tl)
    assert crit["critical_path_s"] == pytest.approx(7.5 + 1.0 + 2.0)
    assert [(c["phase"], c["experiment"]) for c in crit["chain"]] == [
        ("sweep point", "stick a=0.4"), ("What experiments measure (sweep curves)", None),
        ("figures and page", None)]
    tl[2]["seconds"] = 20.0
    assert report_critical_path(tl)["critical_path_s"] == pytest.approx(23.0)


def test_figures_that_need_no_curves_wait_for_the_comparisons_alone():
    # the figures drawn before the curves (figures: comparisons) hang off the comparisons:
    # runs 2 -> comparisons 1 -> figures: comparisons 4 -> page 1 = 8; the curve figures
    # (runs 2 -> curves 3 -> figures 1 -> page 1 = 7) are not on that chain
    tl = [_ph("circuit runs", "e", 2.0, "circuit"), _ph("theory curves", "e", 3.0, "theory"),
          _ph("comparisons", "e", 1.0), _ph("figures: comparisons", "e", 4.0),
          _ph("figures", "e", 1.0), _ph("figures and page", None, 1.0)]
    crit = report_critical_path(tl)
    assert crit["critical_path_s"] == pytest.approx(8.0)
    assert [c["phase"] for c in crit["chain"]] == ["circuit runs", "comparisons",
                                                   "figures: comparisons", "figures and page"]
    # slower curves: the curve figures' chain 2 + 6 + 1 + 1 = 10 > 8
    tl[1] = _ph("theory curves", "e", 6.0, "theory")
    crit = report_critical_path(tl)
    assert crit["critical_path_s"] == pytest.approx(10.0)
    assert [c["phase"] for c in crit["chain"]] == ["circuit runs", "theory curves", "figures",
                                                   "figures and page"]


def test_a_members_figures_follow_that_member():
    tl = [_ph("family member (circuit and theory)", "m1", 10.0, "members"),
          _ph("family member (circuit and theory)", "m2", 4.0, "members"),
          _ph("figures: family member", "m1", 1.0), _ph("figures: family member", "m2", 3.0),
          _ph("figures and page", None, 0.5)]
    crit = report_critical_path(tl)
    assert crit["critical_path_s"] == pytest.approx(11.5)    # m1 10 + 1 + 0.5 (m2: 7.5)
    assert [(c["phase"], c["experiment"]) for c in crit["chain"]] == [
        ("family member (circuit and theory)", "m1"), ("figures: family member", "m1"),
        ("figures and page", None)]


def test_theory_curves_count_their_worker_processes_by_cpu_not_by_waiting():
    # curves phase 7 s, of which 6 s waiting for workers whose longest took 3.5 CPU-s: with
    # unlimited cores 1 + 3.5 = 4.5 s; runs 2 -> curves 4.5 -> figures 1 -> page 0.5 = 8.0
    tl = [_ph("circuit runs", "e", 2.0, "circuit"), _ph("theory curves", "e", 7.0, "theory"),
          _ph("comparisons", "e", 0.5), _ph("figures", "e", 1.0),
          _ph("figures and page", None, 0.5)]
    assert report_critical_path(tl)["critical_path_s"] == pytest.approx(10.5)   # no record
    rec = {"e": {"process_wait_s": 6.0, "longest_process_s": 3.5}}
    crit = report_critical_path(tl, curves=rec)
    assert crit["critical_path_s"] == pytest.approx(8.0)
    assert crit["chain"][1] == {"phase": "theory curves", "experiment": "e", "seconds": 4.5}
    # never more than the phase itself (a worker slower than the whole phase: its CPU
    # includes a start-up the phase did not wait for)
    rec = {"e": {"process_wait_s": 0.5, "longest_process_s": 9.0}}
    assert report_critical_path(tl, curves=rec)["critical_path_s"] == pytest.approx(10.5)
    assert report_critical_path(tl, curves={"e": {}})["critical_path_s"] == pytest.approx(10.5)


def test_calibrations_count_their_stages_longest_decks_when_recorded():
    # runs: calibrations 6 s of wall on a busy machine, 1.5 s with unlimited cores (each
    # stage's decks at once) + longest deck 4 = 5.5; the stationary node 1.5 + 2 = 3.5
    timing = {"e": {"before_decks_s": 6.0, "calibration_unlimited_s": 1.5,
                    "longest_deck_s": 4.0, "stationary_longest_deck_s": 2.0}}
    tl = [_ph("circuit runs", "e", 20.0, "circuit"), _ph("theory curves", "e", 1.0, "theory"),
          _ph("comparisons", "e", 0.5), _ph("figures", "e", 1.0),
          _ph("figures and page", None, 0.5)]
    crit = report_critical_path(tl, timing)
    assert crit["critical_path_s"] == pytest.approx(5.5 + 0.5 + 1.0 + 0.5)
    nodes = report_graph(tl, timing)
    assert nodes[("circuit runs: stationary", "e")][0] == pytest.approx(3.5)
    # never more than the measured work before the decks
    timing["e"]["calibration_unlimited_s"] = 9.0
    assert report_critical_path(tl, timing)["critical_path_s"] == pytest.approx(12.0)
