"""Parameter sweeps on the circuit (issue 23 item 4, "must show"): a quick sweep of the stick
experiment over ``a`` and over ``gamma`` runs, writes a ``sweep.nc`` that ``xarray.
open_dataset`` reads with one dimension per varied parameter and, for every observable, the
circuit value, its standard error, the exact theory and the budget; every circuit point lies
within its budget (|circuit - theory| <= 3 SE + the systematic terms, the report's rule,
the SE from the replicas).  The CLI writes the same file and the figures, from the run store.

Cost: 5 distinct points (the a = 0.2 and gamma = 10 points are one model, hence one stored
run: :func:`analogue.study.sweep.point_seed`), each a 32 x 50 stationary and a 250 x 8
first-passage run at quick size, plus their tolerance and deck-size calibrations."""
import math

import numpy as np
import pytest
import xarray as xr

import analogue
from analogue.cli import main
from analogue.study.sweep import BUDGET_TERMS, OBSERVABLES

pytestmark = [pytest.mark.requires_ngspice, pytest.mark.slow]

A_GRID = (0.0, 0.4, 3)               # 0, 0.2, 0.4 (stick regime: Delta = 0.7)
GAMMA_GRID = (4.0, 25.0, 3, "log")   # 4, 10, 25


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    return tmp_path_factory.mktemp("sweep-store")


def _sweep(name, grid, store, tmp_path_factory):
    out = tmp_path_factory.mktemp(f"sweep-{name}")
    return analogue.sweep("stick", {name: grid}, quick=True, out=out, store=store,
                          progress=False), out


@pytest.fixture(scope="module")
def over_a(store, tmp_path_factory):
    return _sweep("a", A_GRID, store, tmp_path_factory)


@pytest.fixture(scope="module")
def over_gamma(store, tmp_path_factory):
    return _sweep("gamma", GAMMA_GRID, store, tmp_path_factory)


def _check_file(out, dim, values):
    with xr.open_dataset(out / "sweep.nc") as ds:
        assert set(ds.dims) == {dim, "budget_term", f"{dim}_fine"}
        np.testing.assert_allclose(ds[dim].values, values)
        # the theory curve of the figures passes through the grid's theory values
        fine = ds[f"mean_v_theory_fine_{dim}"]
        np.testing.assert_allclose(fine.sel({f"{dim}_fine": values[0]}, method="nearest"),
                                   ds["mean_v_theory"].values[0], rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(fine.values[-1], ds["mean_v_theory"].values[-1], rtol=1e-9)
        assert list(ds["budget_term"].values) == list(BUDGET_TERMS)
        for obs in OBSERVABLES:
            for suffix in ("", "_stderr", "_theory", "_budget", "_z", "_within_budget"):
                assert ds[obs + suffix].dims == (dim,), obs + suffix
            assert ds[obs + "_budget_terms"].dims == (dim, "budget_term")
        assert ds.attrs["experiment"] == "stick" and ds.attrs["quick"] == 1
        for key in ("fixed_parameters", "seed_rule", "ngspice_version", "date",
                    "mean_work_rate_convention"):
            assert ds.attrs[key], key
        assert not list(out.glob(".*.tmp"))   # nothing half-written left beside it
        return ds.load()


def _within_budget(ds, dim):
    """Every defined comparison within budget; returns the largest |z|."""
    worst = 0.0
    for obs in OBSERVABLES:
        value, se = ds[obs].values, ds[obs + "_stderr"].values
        theory, budget = ds[obs + "_theory"].values, ds[obs + "_budget"].values
        for i, x in enumerate(ds[dim].values):
            if obs == "mean_work_rate" and "a" in ds.dims and ds["a"].values[i] == 0:
                assert value[i] == 0.0 and theory[i] == 0.0   # F = 0: no work at all
                continue
            if not math.isfinite(value[i]):
                # only a censored first passage may be undefined, and then it says so
                assert obs == "first_passage_mean" and ds["first_passage_censored"].values[i] > 0
                continue
            assert se[i] > 0 and budget[i] >= 0
            diff = value[i] - theory[i]
            assert abs(diff) <= 3.0 * se[i] + budget[i], (
                f"{obs} at {dim}={x:g}: circuit {value[i]:.5g} +- {se[i]:.2g}, theory "
                f"{theory[i]:.5g}, budget {budget[i]:.2g} (z = {diff / se[i]:.2f})")
            assert ds[obs + "_within_budget"].values[i] == 1
            worst = max(worst, abs(diff / se[i]))
    return worst


def test_sweep_over_a_writes_the_dataset_and_lies_within_budget(over_a):
    ds, out = over_a
    on_disk = _check_file(out, "a", [0.0, 0.2, 0.4])
    xr.testing.assert_identical(on_disk.drop_attrs(), ds.drop_attrs())
    _within_budget(ds, "a")
    # the drift grows with the force and is odd in it: <v>(a = 0) = 0 exactly in theory
    assert ds["mean_v_theory"].values[0] == pytest.approx(0.0, abs=1e-12)
    assert np.all(np.diff(ds["mean_v_theory"].values) > 0)
    assert np.all(np.diff(ds["mean_v"].values) > 0)
    # budget terms: smoothing signed from exact numerics, the held noise measured
    terms = ds["stick_fraction_budget_terms"]
    assert np.all(terms.sel(budget_term="bandwidth").values > 0)
    assert np.all(ds["first_passage_mean_budget_terms"].sel(budget_term="sampling").values > 0)
    assert np.all(ds["mean_v_budget_terms"].sel(budget_term="sampling").values == 0)


def test_sweep_over_gamma_and_the_shared_point(over_a, over_gamma):
    ds, out = over_gamma
    _check_file(out, "gamma", [4.0, 10.0, 25.0])
    _within_budget(ds, "gamma")
    # the stick experiment at gamma = 10 is its a = 0.2 point: one model, one stored run
    da = over_a[0]
    for obs in OBSERVABLES:   # (to rounding: BLAS sums may differ in the last bit)
        np.testing.assert_allclose(ds[obs].sel(gamma=10.0).item(), da[obs].sel(a=0.2).item(),
                                   rtol=1e-12)
    assert ds["seed_stationary"].sel(gamma=10.0).item() == da["seed_stationary"].sel(a=0.2).item()
    # more noise, more diffusion (theory and circuit)
    assert np.all(np.diff(ds["D_x_theory"].values) < 0)


def test_cli_sweep_writes_the_file_and_figures_from_the_store(cli, store, over_a, tmp_path):
    out = tmp_path / "cli"
    r = cli.invoke(main, ["sweep", "stick", "--vary", "a=0:0.4:3", "--quick", "--out",
                          str(out), "--store", str(store), "--no-progress"])
    assert r.exit_code == 0, r.output
    for name in ("sweep.nc", "mobility.png", "mobility.svg"):
        assert (out / name).stat().st_size > 0
        assert f"wrote {out / name}" in r.output
    with xr.open_dataset(out / "sweep.nc") as ds:
        for obs in OBSERVABLES:   # the same runs (from the store), the same numbers (to the
            # last bit of numpy's SIMD sums)
            np.testing.assert_allclose(ds[obs].values, over_a[0][obs].values, rtol=1e-12)


def test_cli_refuses_bad_grids_before_running(cli, tmp_path):
    for vary, words in (("zeta=0:1:3", "unknown parameter 'zeta'"),
                        ("gamma=-1:10:3", "allowed range of gamma"),
                        ("a=0:1", "NAME=START:STOP:N")):
        r = cli.invoke(main, ["sweep", "stick", "--vary", vary, "--quick", "--out",
                              str(tmp_path / "x")])
        assert r.exit_code == 2, r.output
        assert words in r.output and "--vary" in r.output
        assert not (tmp_path / "x").exists()
    r = cli.invoke(main, ["sweep", "stick", "--quick", "--out", str(tmp_path / "x")])
    assert r.exit_code == 2 and "--vary" in r.output


def test_an_experiment_started_at_rest_has_no_first_passage(tmp_path):
    """Every experiment.v0 = 0: the first passage is NaN throughout (theory, circuit, budget,
    flagged undefined), and nothing else is missing.  A small user experiment (8 replicas
    of 4 tau_m at quick size) to keep it cheap."""
    toml = tmp_path / "rest.toml"
    toml.write_text(TINY)
    ds = analogue.sweep(toml, {"a": [0.1]}, quick=True, out=tmp_path / "out",
                        store=tmp_path / "store", progress=False)
    assert np.isnan(ds["first_passage_mean"].values).all()
    assert np.isnan(ds["first_passage_mean_theory"].values).all()
    assert (ds["first_passage_mean_within_budget"].values == -1).all()
    assert ds["first_passage_censored"].values.tolist() == [0]
    assert math.isnan(ds.attrs["first_passage_v0"])
    for obs in OBSERVABLES[:-1]:
        assert np.isfinite(ds[obs].values).all() and np.isfinite(ds[obs + "_theory"]).all()
    with xr.open_dataset(tmp_path / "out" / "sweep.nc") as on_disk:
        assert set(on_disk.data_vars) == set(ds.data_vars)


TINY = """
name = "rest"
[model]
tau_m = 1.0
delta = 0.7
a = 0.2
gamma = 10.0
[circuit]
time_scale = 1e-3
capacitance = 100e-9
[experiment]
v0 = [0.0]
replicas = 8
t_end = 2.0
sample_dt = 0.01
[report]
stationary_replicas = 8
stationary_t_end = 8.0
stationary_burn_in = 1.0
check_replicas = 4
"""
