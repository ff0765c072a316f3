"""Ensembles as labelled data: ``xarray.Dataset`` and netCDF files, the file-level functions.

The layout (dims, units, provenance attributes; see :mod:`analogue.netcdf_layout`) is written
and read by :meth:`analogue.Ensemble.to_xarray` / :meth:`~analogue.Ensemble.from_xarray`; this
module adds the checked file-level entry points (:func:`open_ensemble`, :func:`write_netcdf`)
and keeps the names it has always exported.  It depends on :class:`~analogue.Ensemble`, not the
reverse.

The engine is netCDF4-python (the Unidata reference library; its wheels bundle libnetcdf and
HDF5, so nothing else is needed).  h5netcdf would also read these files but needs h5py, which is
one more binary dependency.  Files are netCDF-4 (HDF5) with gzip-compressed variables; float64
arrays are stored bit for bit, so the round trip is exact.  They are written atomically
(temporary file, then rename).
"""
from __future__ import annotations

import os
from pathlib import Path

from .ensemble import Ensemble
from .netcdf_layout import (ENGINE, FORMAT_VERSION, META_ATTR, POSITION_UNITS, TIME_UNITS,
                            VELOCITY_UNITS, flat_attrs, write_dataset)

__all__ = [
    "ENGINE",
    "FORMAT_VERSION",
    "ensemble_from_xarray",
    "ensemble_to_xarray",
    "flat_attrs",
    "open_ensemble",
    "write_netcdf",
]
# also importable from here, as before: META_ATTR and the units strings
_REEXPORTED = (META_ATTR, TIME_UNITS, VELOCITY_UNITS, POSITION_UNITS)


def ensemble_to_xarray(ens: Ensemble):
    """The :class:`~analogue.Ensemble` as an ``xarray.Dataset`` (:meth:`Ensemble.to_xarray`)."""
    return ens.to_xarray()


def ensemble_from_xarray(ds) -> Ensemble:
    """Rebuild the :class:`~analogue.Ensemble` from :func:`ensemble_to_xarray`'s dataset."""
    return Ensemble.from_xarray(ds)


def write_netcdf(ens: Ensemble, path) -> Path:
    """Write ``ens`` to ``path`` (netCDF-4), atomically; return the path."""
    if not isinstance(ens, Ensemble):
        raise TypeError(f"expected an analogue.Ensemble, got {type(ens).__name__}")
    return write_dataset(ens.to_xarray(), path)


def open_ensemble(path) -> Ensemble:
    """Read a file written by :meth:`Ensemble.to_netcdf` (or ``analogue export``), exactly."""
    import xarray as xr

    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a str or os.PathLike, got {type(path).__name__}")
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no ensemble file at {path}")
    try:
        with xr.open_dataset(path, engine=ENGINE, decode_times=False) as ds:
            ds.load()
            return ensemble_from_xarray(ds)
    except OSError as exc:
        raise ValueError(f"{path}: not a netCDF-4 file ({exc})") from None
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None
