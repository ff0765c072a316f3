"""Sweep grids and their validation (issue 23 item 4), before any circuit runs: every bad
``vary`` is refused with a message naming the parameter and what is allowed, every point's
model and circuit are built first, and the seeds are a function of the point's model."""
import math

import numpy as np
import pytest

from analogue.circuit.experiments import load_experiment
from analogue.study import sweep as S
from analogue.study.seeds import STREAMS, SeedPlan

STICK = load_experiment("stick")


def test_grid_from_start_stop_n_and_from_values():
    axes = S.parse_vary({"a": (0.0, 0.6, 7), "gamma": [20.0, 10.0]}, STICK.model)
    assert [a.name for a in axes] == ["a", "gamma"]
    np.testing.assert_allclose(axes[0].values, np.linspace(0.0, 0.6, 7))
    assert axes[1].values == (20.0, 10.0)
    (g,) = S.parse_vary({"gamma": (1.0, 100.0, 3, "log")}, STICK.model)
    np.testing.assert_allclose(g.values, [1.0, 10.0, 100.0])
    assert S.parse_vary({"a": (0.3, 0.3, 1)}, STICK.model)[0].values == (0.3,)


@pytest.mark.parametrize("vary, words", [
    ({"zeta": (0, 1, 3)}, ["unknown parameter 'zeta'", "tau_m", "gamma"]),
    ({"epsilon": (0, 1, 3)}, ["unknown parameter 'epsilon'"]),
    ({"delta_s": (0, 1, 3)}, ["unknown parameter 'delta_s'"]),      # stick has no Stribeck law
    ({"a": (0.0, 0.6, 0)}, ["vary a N", "[1, 64]"]),
    ({"a": (0.0, 0.6, 65)}, ["vary a N", "[1, 64]"]),
    ({"a": (0.0, 0.6, 1)}, ["N = 1 needs START == STOP"]),
    ({"a": (0.2, 0.2, 3)}, ["repeats one value"]),
    ({"gamma": (0.0, 10.0, 3)}, ["gamma", "value 0", "allowed range of gamma (> 0)"]),
    ({"delta": (-1.0, 1.0, 3)}, ["delta", "allowed range of delta (>= 0)"]),
    ({"tau_m": (-1.0, 1.0, 3, "log")}, ["log spacing needs START and STOP > 0"]),
    ({"a": (0.0, math.inf, 3)}, ["vary a STOP"]),
    ({"a": [0.1, 0.3, 0.2]}, ["strictly monotone"]),
    ({"a": [0.1, math.nan]}, ["finite"]),
    ({"a": np.zeros((2, 2))}, ["1-D"]),
    ({"a": (0.0, 0.5, 20), "gamma": (1.0, 30.0, 20)}, ["400 grid points", "at most 256"]),
    ({}, ["at least one parameter"]),
])
def test_bad_grids_are_refused_naming_the_parameter(vary, words):
    with pytest.raises(ValueError) as err:
        S.parse_vary(vary, STICK.model)
    for w in words:
        assert w in str(err.value), str(err.value)


def test_wrong_types_are_type_errors():
    with pytest.raises(TypeError, match="mapping"):
        S.parse_vary([("a", (0, 1, 2))], STICK.model)
    with pytest.raises(TypeError, match="vary a"):
        S.parse_vary({"a": "0:1:2"}, STICK.model)


def test_values_the_model_refuses_are_refused_before_any_run():
    # a tau_m beyond the model's velocity limit (1e15): the model's own check, with the point
    # named
    with pytest.raises(ValueError, match=r"point a=1e\+16 of experiment 'stick' is refused: "
                                         r"a=1e\+16 with tau_m=1.0"):
        S.plan_sweep("stick", {"a": [0.2, 1e16]}, quick=True)


def test_spring_and_shot_experiments_are_refused():
    for name in ("spring", "shot"):
        with pytest.raises(ValueError, match="one-dimensional model with Gaussian noise only"):
            S.plan_sweep(name, {"a": (0.1, 0.2, 2)}, quick=True)


def test_the_plan_builds_every_point():
    plan = S.plan_sweep("stick", {"a": (0.0, 0.4, 3), "gamma": [5.0, 10.0]}, quick=True)
    assert plan.shape == (3, 2) and len(plan.models) == 6
    assert plan.models[1].a == 0.0 and plan.models[1].gamma == 10.0   # C order
    assert plan.models[4].a == 0.4 and plan.models[4].gamma == 5.0
    assert plan.fp_v0 == 2.0 and plan.settings.stationary_replicas == 32


def test_cli_grid_text():
    assert S.parse_vary_text(["a=0:0.6:7", "gamma=1:100:3:log"]) == {
        "a": (0.0, 0.6, 7), "gamma": (1.0, 100.0, 3, "log")}
    for bad, word in (("a0:1:2", "expected NAME=START:STOP:N"), ("a=0:1", "expected"),
                      ("a=x:1:2", "must be numbers"), ("a=0:1:2.5", "N an integer"),
                      ("a=0:1:2:lin", "only be 'log'")):
        with pytest.raises(ValueError, match=word):
            S.parse_vary_text([bad])
    with pytest.raises(ValueError, match="given twice"):
        S.parse_vary_text(["a=0:1:2", "a=0:1:3"])


def test_point_seeds_follow_the_model_not_the_index():
    m = STICK.model
    s1 = S.point_seed(11, "sweep_stationary", m.replace(a=0.3))
    assert s1 == S.point_seed(11, "sweep_stationary", m.replace(a=0.3))
    assert 1 <= s1 <= 2**31 - 1
    others = {S.point_seed(11, "sweep_stationary", m.replace(a=0.3000001)),
              S.point_seed(12, "sweep_stationary", m.replace(a=0.3)),
              S.point_seed(11, "sweep_first_passage", m.replace(a=0.3))}
    assert s1 not in others and len(others) == 3
    with pytest.raises(ValueError, match="sweep seed stream"):
        S.point_seed(11, "stationary", m)
    # the report's seed plan neither hands these streams out nor lists them
    assert {"sweep_stationary", "sweep_first_passage", "sweep_band"} <= set(STREAMS)
    assert not any(k.startswith("sweep") for k in SeedPlan(11).all(2))
    with pytest.raises(ValueError, match="point_seed"):
        SeedPlan(11).stream("sweep_band")


def test_point_theory_against_closed_forms():
    """The sweep's theory route at Delta = 0 (Ornstein-Uhlenbeck: <v> = a tau_m, Var v =
    tau_m/gamma, D_x = tau_m^2/gamma) and the work-rate convention F <v>, F = m a."""
    from analogue import Model
    m = Model(tau_m=0.5, delta=0.0, a=0.3, gamma=8.0, mass=2.0)
    th = S.point_theory(m, threshold=0.1, v0=1.0)
    assert th["mean_v"] == pytest.approx(0.15, rel=1e-9)
    assert th["var_v"] == pytest.approx(0.5 / 8.0, rel=1e-7)
    assert th["D_x"] == pytest.approx(0.25 / 8.0, rel=1e-5)
    assert th["mean_work_rate"] == pytest.approx(2.0 * 0.3 * 0.15, rel=1e-9)
    assert th["p_positive"] == pytest.approx(0.5 * math.erfc(-0.15 / math.sqrt(2 * 0.5 / 8.0)),
                                             rel=1e-9)


def test_runner_or_run_keywords_not_both(tmp_path):
    import analogue
    with pytest.raises(TypeError, match="either runner= or the run keywords"):
        S.sweep("stick", {"a": [0.2]}, quick=True, runner=analogue.Runner(store=False),
                workers=1)
    with pytest.raises(TypeError, match="runner must be an analogue.Runner"):
        S.sweep("stick", {"a": [0.2]}, quick=True, runner={"workers": 1})
    with pytest.raises(ValueError, match="not a directory"):
        (tmp_path / "f").write_text("")
        S.sweep("stick", {"a": [0.2]}, quick=True, out=tmp_path / "f")


def test_monte_carlo_pair_runs_on_holds_that_do_not_divide_the_run():
    """At gamma = 50 the circuit's hold is chosen from the model (0.0097, stationary 0.0032),
    which divides neither the stationary length (50) nor t_end (8): the held/white pair of
    the bandwidth term failed there ("t_end=50.0 must be a whole number of noise hold
    times"), after the point's circuit runs.  It now runs on whole holds."""
    from analogue.study.budget import held_noise_pair
    from analogue.study.settings import stationary_noise_dt
    plan = S.plan_sweep("stick", {"gamma": [50.0]}, quick=True)
    hold = stationary_noise_dt(plan.mappings[0].noise_dt, plan.settings)
    t_end = plan.exp.t_end
    assert abs(t_end / hold - round(t_end / hold)) > 1e-6     # the case
    with pytest.raises(ValueError, match="whole number of noise hold"):
        held_noise_pair(plan.mappings[0].model_effective, v0=2.0, t_end=t_end, replicas=2,
                        seed=1, noise_dt=hold, sample_dt=plan.exp.sample_dt)
    t = S._whole_holds(t_end, hold, plan.exp.sample_dt)
    assert t_end - 0.011 < t <= t_end
    held, white = held_noise_pair(plan.mappings[0].model_effective, v0=2.0, t_end=t,
                                  replicas=2, seed=1, noise_dt=hold, sample_dt=plan.exp.sample_dt)
    assert held.v.shape == white.v.shape


def test_first_passage_starts_from_the_first_nonzero_v0():
    # the work experiment starts at v0 = [0, 3]: a path started at rest is there at once
    assert load_experiment("work").v0[0] == 0.0
    assert S.plan_sweep("work", {"a": [0.5]}, quick=True).fp_v0 == 3.0
    assert S.plan_sweep("stick", {"a": [0.5]}, quick=True).fp_v0 == 2.0
    m = STICK.model
    assert math.isnan(S.point_theory(m, threshold=0.03, v0=None)["first_passage_mean"])
    assert S.point_theory(m, threshold=0.03, v0=2.0)["first_passage_mean"] > 0


def test_a_failed_write_leaves_nothing_behind(tmp_path):
    """sweep.nc is written atomically: a writer that fails (here: a variable netCDF cannot
    hold) raises OSError naming the file and leaves neither it nor a temporary file."""
    import xarray as xr
    ds = xr.Dataset({"mean_v": ("a", np.array([0.1, 0.2])),
                     "bad": ("a", np.array([{"x": 1}, {"y": 2}], dtype=object))},
                    coords={"a": [0.0, 0.2]})
    with pytest.raises(OSError, match="sweep.nc"):
        S.write_sweep(ds, tmp_path / "sweep.nc")
    assert list(tmp_path.iterdir()) == []
    good = ds.drop_vars("bad")
    S.write_sweep(good, tmp_path / "sweep.nc")
    with xr.open_dataset(tmp_path / "sweep.nc") as back:
        np.testing.assert_array_equal(back["mean_v"].values, [0.1, 0.2])
    assert [p.name for p in tmp_path.iterdir()] == ["sweep.nc"]


def test_the_deck_view_times_each_threads_batches_and_cancels_its_decks():
    """The sweep's view of its shared deck pool (issue 22): a thread's decks submitted
    together are one batch, counted as its longest deck's own wall time (info["wall_time"],
    not its wait for a free process) over its span; cancel_all cancels what is still queued,
    and the pool itself is not shut down (it is its owner's)."""
    import concurrent.futures as cf
    import threading

    from analogue.study.sweep import _DeckView
    gate, go = threading.Event(), threading.Event()

    def deck(w):
        assert go.wait(30)            # (all three submitted before any ends: one batch)
        return {"info": {"wall_time": w}}
    with cf.ThreadPoolExecutor(max_workers=1) as pool:
        view = _DeckView(pool)
        futs = [view.submit(deck, w) for w in (0.5, 2.0, 1.0)]
        go.set()
        cf.wait(futs)
        (batch,) = view.take(threading.get_ident())
        assert batch[1] == 2.0 and batch[0] >= 0
        assert view.take(threading.get_ident()) == []
        started = threading.Event()
        blocker = view.submit(lambda: started.set() or gate.wait(30))
        assert started.wait(30)
        queued = view.submit(lambda: {"info": {"wall_time": 1.0}})
        view.cancel_all()
        gate.set()
        view.shutdown(wait=True)
        assert queued.cancelled() and blocker.result(timeout=30) is True
        assert pool.submit(lambda: 3).result(timeout=30) == 3    # still the owner's, open


def test_deck_view_counts_a_points_helper_threads_as_the_point():
    """Decks a point's helper threads submit (its calibration's runs at once,
    circuit.tolerances.at_once, which copies the context) join the point's batch: one batch
    counted as its longest deck, taken by the point's thread (before, they were batches of
    threads nobody took, and the point's critical-path seconds held their waits: 79.7 s for
    one sweep point of make paper)."""
    import concurrent.futures as cf
    import threading

    from analogue import Runner
    from analogue.circuit.tolerances import at_once
    from analogue.study.sweep import _POINT, _DeckView
    go = threading.Event()

    def deck(w):
        assert go.wait(30)
        return {"info": {"wall_time": w}}
    with cf.ThreadPoolExecutor(max_workers=2) as pool:
        view = _DeckView(pool)
        token = _POINT.set(threading.get_ident())
        try:
            def run(w):
                f = view.submit(deck, w)
                if w == 3.0:
                    go.set()
                return f.result(timeout=30)
            got = at_once([lambda: run(1.0), lambda: run(3.0)], Runner(executor=view))
        finally:
            _POINT.reset(token)
        assert [g["info"]["wall_time"] for g in got] == [1.0, 3.0]
        batches = view.take(threading.get_ident())
        assert [b[1] for b in batches] in ([3.0], [1.0, 3.0], [3.0, 1.0])
        assert max(b[1] for b in batches) == 3.0
