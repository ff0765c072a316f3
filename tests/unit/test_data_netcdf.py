"""Ensemble <-> xarray.Dataset <-> netCDF file: labelled dims, units, provenance attributes and an
exact round trip of arrays and meta."""
import json
import math

import numpy as np
import pytest

import analogue
from analogue import Ensemble
from analogue.data import flat_attrs, open_ensemble

xr = pytest.importorskip("xarray")


def _ensemble(noise=True, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(51) * 0.02
    v = rng.standard_normal((4, t.size))
    v[1, 7] = np.nan                      # a NaN must survive (no fill-value masking)
    x = np.cumsum(v, axis=1) * 0.02
    x[:, 0] = 0.0
    meta = {"source": "circuit", "model": {"tau_m": 1.0, "delta": 0.7, "a": 0.2, "gamma": 10.0,
                                           "mass": 1.0, "epsilon": 0.0},
            "circuit": [["C", 1e-07, "F", "mass capacitor"], ["R", 1e4, "ohm", "resistor"],
                        ["noise_dt/tau_m", 0.01, "1", "hold time / tau_m"]],
            "seed": 7, "deck_seeds": [11, 12], "deck_sha256": ["ab" * 32, "cd" * 32],
            "ngspice_version": "39", "vntol": None, "allow_bias": False, "ratio": float("nan"),
            "noise_dt": 0.02, "nested": {"list": [1, "a", None]}, "unicode": "γ = 10 ± 1"}
    z = rng.standard_normal((4, 50)) if noise else None
    return Ensemble(t, v, x, meta, z)


def test_to_xarray_dims_coords_units_and_provenance():
    ens = _ensemble()
    ds = ens.to_xarray()
    assert ds["v"].dims == ("replica", "time") and ds["x"].dims == ("replica", "time")
    assert ds["noise"].dims == ("replica", "noise_time")
    assert ds.sizes == {"replica": 4, "time": 51, "noise_time": 50}
    for name in ("time", "replica", "noise_time", "v", "x", "noise"):
        assert ds[name].attrs.get("units"), name
    assert "tau_m" in ds["time"].attrs["units"]
    np.testing.assert_array_equal(ds["noise_time"].values, np.arange(50) * 0.02)
    a = ds.attrs
    assert a["model.tau_m"] == 1.0 and a["model.gamma"] == 10.0
    assert a["circuit.C"] == 1e-07 and a["circuit.C.units"] == "F"
    assert a["circuit.noise_dt_tau_m"] == 0.01          # netCDF-safe name
    assert a["seed"] == 7 and a["deck_seeds"] == [11, 12]
    assert a["ngspice_version"] == "39"
    assert a["deck_sha256"].split() == ["ab" * 32, "cd" * 32]
    assert a["allow_bias"] == 0 and "vntol" not in a and "ratio" not in a
    # every attribute is JSON-safe (strict: no NaN) and netCDF-writable (no None / dict)
    for k, v in a.items():
        json.dumps(v, allow_nan=False)
        assert v is not None and not isinstance(v, dict), k
    # selection by label works as in any xarray dataset
    assert float(ds["v"].sel(time=0.5, method="nearest")[0]) == ens.v[0, 25]


def test_netcdf_round_trip_is_exact(tmp_path):
    ens = _ensemble()
    p = tmp_path / "sub" / "e.nc"
    ens.to_netcdf(p)
    back = open_ensemble(p)
    for name in ("t", "v", "x", "noise"):
        a, b = getattr(ens, name), getattr(back, name)
        assert a.dtype == b.dtype == np.float64
        np.testing.assert_array_equal(a, b)             # bitwise, NaN included
    assert math.isnan(back.meta.pop("ratio")) and math.isnan(ens.meta["ratio"])
    assert back.meta == {k: v for k, v in ens.meta.items() if k != "ratio"}
    assert not list(tmp_path.glob("sub/.*.tmp"))        # nothing half-written left behind
    # the file is plain netCDF: xarray reads it without analogue
    with xr.open_dataset(p, engine="netcdf4") as ds:
        np.testing.assert_array_equal(ds["v"].values, ens.v)
    assert analogue.open_ensemble is open_ensemble


def test_round_trip_without_noise_and_via_xarray(tmp_path):
    ens = _ensemble(noise=False, seed=1)
    assert "noise" not in ens.to_xarray()
    back = Ensemble.from_xarray(ens.to_xarray())
    assert back.noise is None
    np.testing.assert_array_equal(back.v, ens.v)
    ens.to_netcdf(tmp_path / "n.nc")
    assert open_ensemble(tmp_path / "n.nc").noise is None


def test_flat_attrs_of_component_table():
    a = flat_attrs({"circuit": [["theta", 0.001, "s", "x"]], "model": {"a": 1}})
    assert a == {"circuit.theta": 0.001, "circuit.theta.units": "s", "model.a": 1}


def test_bad_inputs(tmp_path):
    with pytest.raises(FileNotFoundError, match="no ensemble file"):
        open_ensemble(tmp_path / "missing.nc")
    (tmp_path / "junk.nc").write_text("not netcdf")
    with pytest.raises(ValueError, match="not a netCDF-4 file"):
        open_ensemble(tmp_path / "junk.nc")
    with pytest.raises(TypeError, match="path"):
        open_ensemble(3)
    plain = xr.Dataset({"v": (("replica", "time"), np.zeros((1, 2)))})
    plain.to_netcdf(tmp_path / "plain.nc", engine="netcdf4")
    with pytest.raises(ValueError, match="not an analogue ensemble"):
        open_ensemble(tmp_path / "plain.nc")
    with pytest.raises(ValueError, match="noise"):
        Ensemble(np.arange(3.0), np.zeros((2, 3)), np.zeros((2, 3)), {}, np.zeros((3, 4)))
    with pytest.raises(TypeError, match="meta"):
        Ensemble(np.arange(3.0), np.zeros((2, 3)), np.zeros((2, 3)), [])
    bad = Ensemble(np.arange(3.0), np.zeros((1, 3)), np.zeros((1, 3)), {"f": object()})
    with pytest.raises(TypeError, match="not JSON data"):
        bad.to_netcdf(tmp_path / "bad.nc")
    assert not (tmp_path / "bad.nc").exists()
