"""``Ensemble.provenance``: the meta of a run as a typed object (issue 20), with the dict
access and netCDF attributes that existing callers use unchanged."""
from __future__ import annotations

import hashlib
from collections.abc import Mapping

import numpy as np
import pytest

from analogue import Ensemble, Model
from analogue.ensemble import Provenance
from analogue.netcdf_layout import flat_attrs

MODEL = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)
META = {"source": "circuit", "model": MODEL.as_dict(), "model_effective": MODEL.as_dict(),
        "seed": 7, "deck_seeds": [11, 12], "deck_replicas": [2, 1], "replicas_per_deck": 2,
        "ngspice_version": "42", "deck_sha256": ["aa", "bb"],
        "tolerances": {"reltol": 1e-4, "trtol": 7.0, "method": "trap", "source": "measured"},
        "deck_size": {"replicas_per_deck": 2, "source": "user"}, "t_end": 1.0,
        "sample_dt": 0.5, "noise_dt": 0.01, "circuit": [["theta", 0.001, "s", "time scale"]]}


def _ens(meta) -> Ensemble:
    t = np.array([0.0, 0.5, 1.0])
    return Ensemble(t, np.zeros((3, 3)), np.zeros((3, 3)), meta)


def test_fields_are_typed_and_the_dict_stays() -> None:
    ens = _ens(dict(META))
    p = ens.provenance
    assert isinstance(p, Provenance) and isinstance(p, Mapping)
    assert (p.source, p.seed, p.replicas_per_deck, p.ngspice_version) == ("circuit", 7, 2, "42")
    assert p.deck_seeds == (11, 12) and p.deck_replicas == (2, 1)
    assert p.deck_sha256 == ("aa", "bb")
    assert p.tolerances is not None and p.tolerances["method"] == "trap"
    assert (p.t_end, p.sample_dt, p.noise_dt) == (1.0, 0.5, 0.01)
    assert p.to_model() == MODEL
    assert p.netlist_hash == hashlib.sha256(b"aa bb").hexdigest()
    # every key of meta, as a Mapping; meta itself is still the dict it was
    assert dict(p) == META and p["deck_size"] == META["deck_size"] and len(p) == len(META)
    assert type(ens.meta) is dict and ens.meta["seed"] == 7


def test_attrs_are_the_flat_meta_with_the_netlist_hash() -> None:
    p = Provenance.from_meta(META)
    attrs = p.as_attrs()
    assert attrs == {**flat_attrs(META), "netlist_hash": p.netlist_hash}
    assert attrs["circuit.theta"] == 0.001 and attrs["model.tau_m"] == 1.0


@pytest.mark.parametrize("meta", [{}, {"source": "sde", "seed": 3, "scheme": "euler"},
                                  {"seed": True, "deck_seeds": "x", "t_end": "long"}])
def test_other_producers_and_odd_values_give_empty_fields(meta) -> None:
    p = _ens(meta).provenance
    assert p.deck_seeds == () and p.deck_sha256 == () and p.netlist_hash is None
    assert p.tolerances is None and p.t_end is None
    assert p.seed == {"sde": 3}.get(meta.get("source"))   # a bool is not a seed
    assert p.as_attrs() == flat_attrs(meta)


def test_netcdf_carries_the_netlist_hash(tmp_path) -> None:
    pytest.importorskip("xarray")
    ens = _ens(dict(META))
    ds = ens.to_xarray()
    assert ds.attrs["netlist_hash"] == ens.provenance.netlist_hash
    assert Ensemble.from_xarray(ds).meta == ens.meta   # the exact meta, nothing added
