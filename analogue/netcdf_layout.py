"""The layout of an ensemble as labelled data (``xarray.Dataset``, netCDF files): the one home of
the format that :meth:`analogue.Ensemble.to_xarray` and :mod:`analogue.data` (the file-level
functions, :func:`analogue.open_ensemble`) both use.  It reads an ensemble through its fields
only, so it sits below :mod:`analogue.ensemble` and the class does not import its own readers.

Layout of the dataset (and of the file, which is the dataset written by xarray):

- dims ``replica`` and ``time`` (and ``noise_time`` when the driving noise was recorded);
- data variables ``v`` (replica, time) and ``x`` (replica, time), ``noise`` (replica,
  noise_time): the standard normal numbers of each noise hold interval; for a spring member's
  circuit run also ``x_spring`` and ``x_integral`` (replica, time), its ``records``;
- coordinates ``time`` (model time, i.e. units of tau_m when tau_m = 1 as in ``circuits/``),
  ``replica`` (0, 1, ...) and ``noise_time`` (start of each hold interval), each with ``units``
  and ``long_name`` attributes;
- provenance as JSON-safe attributes: the ensemble's ``meta`` flattened to scalars and lists
  (``model.tau_m``, ``circuit.C`` with ``circuit.C.units = "F"``, ``seed``, ``deck_seeds``,
  ``ngspice_version``, ``deck_sha256``, ...) for people and other tools, plus the whole
  ``meta`` as one JSON string (``analogue_meta``) from which :func:`open_ensemble` rebuilds it
  exactly.

The engine is netCDF4-python (the Unidata reference library; its wheels bundle libnetcdf and
HDF5, so nothing else is needed).  h5netcdf would also read these files but needs h5py, which is
one more binary dependency.  Files are netCDF-4 (HDF5) with gzip-compressed variables; float64
arrays are stored bit for bit, so the round trip is exact.  They are written atomically
(temporary file, then rename).
"""
from __future__ import annotations

import json
import math
import os
import re
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from .files import atomic_path

__all__ = ["ENGINE", "FORMAT_VERSION", "META_ATTR", "flat_attrs", "to_dataset",
           "fields_from_dataset", "write_dataset"]

ENGINE = "netcdf4"
FORMAT_VERSION = 1
META_ATTR = "analogue_meta"

TIME_UNITS = "model time (units of tau_m when tau_m = 1)"
VELOCITY_UNITS = "model velocity"
POSITION_UNITS = "model velocity x model time"
_UNITS_NOTE = ("Reduced units of dv/dt = -v/tau_m - Delta sgn(v) + a + xi(t)/m (Baule, Touchette "
               "& Cohen, eq. (1)); the circuit runs theta = circuit.theta seconds per model time "
               "unit and kappa = circuit.kappa volts per unit velocity.")
# Per-replica records of a circuit run kept as data variables (replica, time) when present
# (spring members, :attr:`analogue.Ensemble.records`): the report's analysis reads the spring's
# position from the inductor, so an export carries that very array (issue 20 item 4).
_RECORDS = {
    "x_spring": ("spring position read back from the inductor current (absolute: model.x0 "
                 "at t = 0; x = x_spring - x_spring[:, 0])", POSITION_UNITS),
    "x_integral": ("integral of v over time (what a lossless inductor would hold)",
                   POSITION_UNITS),
}
_NAME_BAD = re.compile(r"[^A-Za-z0-9_.]")


def _json_default(obj):
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"Ensemble.meta holds a {type(obj).__name__}, which is not JSON data")


def _attr_name(key) -> str:
    return _NAME_BAD.sub("_", str(key))


def _flatten(prefix: str, value, out: dict) -> None:
    """Flatten ``value`` into netCDF-writable, JSON-safe attributes under ``prefix``."""
    if value is None:
        return
    if isinstance(value, (bool, int, np.integer)):
        out[prefix] = int(value)
    elif isinstance(value, (float, np.floating)):
        if math.isfinite(float(value)):
            out[prefix] = float(value)
    elif isinstance(value, str):
        out[prefix] = value
    elif isinstance(value, dict):
        for k, v in value.items():
            _flatten(f"{prefix}.{_attr_name(k)}", v, out)
    elif isinstance(value, (list, tuple, np.ndarray)):
        items = list(np.asarray(value).tolist()) if isinstance(value, np.ndarray) else list(value)
        if not items:
            return
        if all(isinstance(i, (int, float)) and not isinstance(i, bool) for i in items):
            if all(math.isfinite(i) for i in items):
                out[prefix] = items
        elif all(isinstance(i, str) for i in items):
            out[prefix] = " ".join(items)
        else:
            out[prefix] = json.dumps(items, default=_json_default)
    else:
        out[prefix] = json.dumps(value, default=_json_default)


def flat_attrs(meta: dict) -> dict:
    """The provenance ``meta`` as flat attributes: str, int, float or lists of numbers.

    The circuit's component table (rows ``(name, value, unit, meaning)``) becomes
    ``circuit.<name> = value`` and ``circuit.<name>.units = unit``; nested dicts become dotted
    names (``model.tau_m``); lists of strings (deck hashes) are joined with spaces; None and
    non-finite numbers are left out (netCDF has no null; the exact meta is in ``analogue_meta``).
    """
    out: dict = {}
    for key, value in meta.items():
        name = _attr_name(key)
        if key == "circuit" and isinstance(value, list) and all(
                isinstance(r, (list, tuple)) and len(r) == 4 for r in value):
            for comp, val, unit, _meaning in value:
                _flatten(f"circuit.{_attr_name(comp)}", val, out)
                out[f"circuit.{_attr_name(comp)}.units"] = str(unit)
            continue
        _flatten(name, value, out)
    return out



class EnsembleFields(Protocol):
    """What the layout reads of an ensemble (:class:`analogue.Ensemble` has all of it)."""

    t: np.ndarray
    v: np.ndarray
    x: np.ndarray
    meta: dict
    noise: np.ndarray | None
    records: dict[str, np.ndarray] | None

    @property
    def replicas(self) -> int: ...


def to_dataset(ens: EnsembleFields, attrs: dict | None = None):
    """An ensemble's arrays and meta as an ``xarray.Dataset`` (see the module docstring).
    ``attrs``: the flat provenance attributes (default :func:`flat_attrs` of ``ens.meta``;
    :meth:`analogue.Ensemble.to_xarray` passes ``ens.provenance.as_attrs()``, which adds
    the ``netlist_hash``)."""
    import xarray as xr

    meta_json = json.dumps(ens.meta, sort_keys=True, default=_json_default)
    n = ens.replicas
    coords = {
        "replica": ("replica", np.arange(n, dtype=np.int64),
                    {"long_name": "replica index", "units": "1"}),
        "time": ("time", ens.t, {"long_name": "time t", "units": TIME_UNITS}),
    }
    data_vars = {
        "v": (("replica", "time"), ens.v, {"long_name": "velocity v", "units": VELOCITY_UNITS}),
        "x": (("replica", "time"), ens.x,
              {"long_name": "position x(t) = integral_0^t v ds", "units": POSITION_UNITS}),
    }
    for name, (long_name, units) in _RECORDS.items():
        rec = (ens.records or {}).get(name)
        if rec is not None and np.shape(rec) == ens.v.shape:
            data_vars[name] = (("replica", "time"), np.asarray(rec, dtype=float),
                               {"long_name": long_name, "units": units})
    if ens.noise is not None:
        h = ens.meta.get("noise_dt")
        n_hold = ens.noise.shape[1]
        if isinstance(h, (int, float)) and not isinstance(h, bool) and h > 0:
            start = np.arange(n_hold) * float(h)
            nattrs = {"long_name": "start of the noise hold interval", "units": TIME_UNITS}
        else:
            start = np.arange(n_hold, dtype=float)
            nattrs = {"long_name": "noise hold interval index", "units": "1"}
        coords["noise_time"] = ("noise_time", start, nattrs)
        data_vars["noise"] = (("replica", "noise_time"), ens.noise, {
            "long_name": "standard normal number driving each hold interval",
            "units": "1",
            "description": "velocity-noise increment over hold k = sqrt(2 h/gamma) noise[:, k], "
                           "h = noise_dt"})
    attrs = {"title": "analogue ensemble of stick-slip trajectories",
             "analogue_format": FORMAT_VERSION,
             "units_note": _UNITS_NOTE,
             **(flat_attrs(ens.meta) if attrs is None else attrs),
             META_ATTR: meta_json}
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)


def fields_from_dataset(ds) -> dict[str, Any]:
    """The keyword arguments of :class:`~analogue.Ensemble` (t, v, x, meta, noise, records) from
    :func:`to_dataset`'s dataset, checked."""
    if META_ATTR not in getattr(ds, "attrs", {}):
        raise ValueError(f"not an analogue ensemble dataset (no {META_ATTR!r} attribute); "
                         "expected the output of Ensemble.to_xarray()")
    for name in ("v", "x"):
        if name not in ds or ds[name].dims != ("replica", "time"):
            raise ValueError(f"dataset variable {name!r} must have dims ('replica', 'time')")
    try:
        meta = json.loads(ds.attrs[META_ATTR])
    except (TypeError, ValueError) as exc:
        raise ValueError(f"attribute {META_ATTR!r} is not JSON ({' '.join(str(exc).split())})"
                         ) from None
    if not isinstance(meta, dict):
        raise ValueError(f"attribute {META_ATTR!r} is JSON {type(meta).__name__}, not the "
                         f"object (dict) an ensemble's meta is")
    records = {name: np.asarray(ds[name].values) for name in _RECORDS
               if name in ds and ds[name].dims == ("replica", "time")}
    noise = None
    if "noise" in ds:
        noise = np.asarray(ds["noise"].transpose("replica", "noise_time").values)
    return {"t": np.asarray(ds["time"].values), "v": np.asarray(ds["v"].values),
            "x": np.asarray(ds["x"].values), "meta": meta, "noise": noise,
            "records": records or None}


def _encoding(ds) -> dict:
    # No fill value: a NaN in the data stays a NaN and nothing else is masked.  gzip level 4
    # with shuffle: measured on a 32 x 2001 stationary circuit run, 888 kB for 1041 kB of
    # float64 (85 %: noise-like mantissas compress poorly; exactness matters more than size).
    enc: dict[str, dict] = {name: {"_FillValue": None}
                            for name in list(ds.coords) + list(ds.data_vars)}
    for name in ds.data_vars:
        enc[name].update(zlib=True, complevel=4, shuffle=True)
    return enc


def write_dataset(ds, path: str | os.PathLike) -> Path:
    """Write :func:`to_dataset`'s dataset to ``path`` (netCDF-4), atomically; return the path."""
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a str or os.PathLike, got {type(path).__name__}")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    # a failure names the file and its cause (netCDF says only "NetCDF: HDF error" on a full
    # disk) and leaves no temporary file (issue 19)
    with atomic_path(path) as tmp:
        ds.to_netcdf(tmp, engine=ENGINE, encoding=_encoding(ds))
    return path
