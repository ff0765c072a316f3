"""A spring member's records (the inductor read-back the report's analysis uses as the
position) go into the netCDF file and come back exactly (issue 20 item 4: the export holds
the arrays the report used); the kicks (ragged) do not."""
import numpy as np

import analogue
from analogue.data import ensemble_to_xarray


def test_spring_records_round_trip(tmp_path):
    rng = np.random.default_rng(5)
    t = np.arange(6) * 0.1
    v = rng.normal(size=(3, 6))
    xs = 0.5 + np.cumsum(rng.normal(size=(3, 6)), axis=1)
    ens = analogue.Ensemble(t, v, xs - xs[:, :1], {"source": "circuit"},
                            records={"x_spring": xs, "x_integral": np.cumsum(v, axis=1),
                                     "kicks": [([0.1], [0.2])] * 3})
    ds = ensemble_to_xarray(ens)
    assert ds["x_spring"].dims == ("replica", "time")
    ens.to_netcdf(tmp_path / "e.nc")
    back = analogue.open_ensemble(tmp_path / "e.nc")
    assert set(back.records) == {"x_spring", "x_integral"}
    np.testing.assert_array_equal(back.records["x_spring"], xs)
    np.testing.assert_array_equal(back.records["x_integral"], ens.records["x_integral"])
    # no records: none come back, and the file has no such variable
    plain = analogue.Ensemble(t, v, xs, {})
    assert "x_spring" not in ensemble_to_xarray(plain)
    plain.to_netcdf(tmp_path / "p.nc")
    assert analogue.open_ensemble(tmp_path / "p.nc").records is None
