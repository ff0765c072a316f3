"""Ensembles of velocity trajectories, whatever produced them (circuit or SDE integrator).

Estimators take an :class:`Ensemble` and never care where it came from, so circuit data and
Monte Carlo data go through exactly the same code.
"""
from __future__ import annotations

import hashlib
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import netcdf_layout
from .model import Model

__all__ = ["Ensemble", "Provenance"]

# provenance keys shown by Ensemble.__repr__ (when present), in this order
_REPR_META = ("source", "seed", "scheme", "noise_dt", "ngspice_version")


def _short(value) -> str:
    """A provenance value in a few characters (numbers with %g, long texts cut)."""
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}={_short(v)}" for k, v in list(value.items())[:3]) + \
            (", ...}" if len(value) > 3 else "}")
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _opt_float(value: Any) -> float | None:
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) \
        else None


def _ints(value: Any) -> tuple[int, ...]:
    return tuple(int(v) for v in value) if isinstance(value, (list, tuple)) else ()


@dataclass(frozen=True)
class Provenance(Mapping):
    """Where an ensemble came from, typed (issue 20): what :func:`analogue.simulate` records
    in ``Ensemble.meta``, as fields.  A read-only view made from ``meta`` (which stays the
    plain, JSON-safe dict it always was, so ``ens.meta["seed"]`` keeps working); as a
    :class:`~collections.abc.Mapping` it also answers every key of that dict
    (``prov["deck_size"]``), and :meth:`as_attrs` gives the flat netCDF attributes
    (:func:`analogue.netcdf_layout.flat_attrs`) that :meth:`Ensemble.to_netcdf` writes.

    Fields: ``source`` ("circuit", "sde", "board", ...), ``model`` (the model's parameters,
    :meth:`Model.as_dict`; :meth:`to_model` rebuilds it) and ``model_effective`` (what the
    circuit realises), ``seed`` and the ``deck_seeds`` and ``deck_replicas`` of the deck
    split (``replicas_per_deck``), ``ngspice_version``, ``deck_sha256`` (one hash per deck
    netlist; :attr:`netlist_hash` names them all), ``tolerances`` and ``deck_size`` (the
    values and how they were chosen), ``t_end``, ``sample_dt``, ``noise_dt``.  Missing
    entries are None or empty (a Monte Carlo ensemble has no decks).
    """

    meta: Mapping[str, Any] = field(repr=False)
    source: str | None = None
    model: Mapping[str, Any] | None = None
    model_effective: Mapping[str, Any] | None = None
    seed: int | None = None
    deck_seeds: tuple[int, ...] = ()
    deck_replicas: tuple[int, ...] = ()
    replicas_per_deck: int | None = None
    ngspice_version: str | None = None
    deck_sha256: tuple[str, ...] = ()
    tolerances: Mapping[str, Any] | None = None
    deck_size: Mapping[str, Any] | None = None
    t_end: float | None = None
    sample_dt: float | None = None
    noise_dt: float | None = None

    @classmethod
    def from_meta(cls, meta: Mapping[str, Any]) -> Provenance:
        """The typed view of an ensemble's ``meta`` (any producer's)."""
        m = meta
        seed = m.get("seed")
        per = m.get("replicas_per_deck")
        ver = m.get("ngspice_version")
        return cls(
            meta=m, source=m.get("source") if isinstance(m.get("source"), str) else None,
            model=m.get("model") if isinstance(m.get("model"), Mapping) else None,
            model_effective=(m.get("model_effective")
                             if isinstance(m.get("model_effective"), Mapping) else None),
            seed=int(seed) if isinstance(seed, int) and not isinstance(seed, bool) else None,
            deck_seeds=_ints(m.get("deck_seeds")), deck_replicas=_ints(m.get("deck_replicas")),
            replicas_per_deck=int(per) if isinstance(per, int) else None,
            ngspice_version=ver if isinstance(ver, str) else None,
            deck_sha256=tuple(str(h) for h in m.get("deck_sha256") or ()),
            tolerances=m.get("tolerances") if isinstance(m.get("tolerances"), Mapping) else None,
            deck_size=m.get("deck_size") if isinstance(m.get("deck_size"), Mapping) else None,
            t_end=_opt_float(m.get("t_end")), sample_dt=_opt_float(m.get("sample_dt")),
            noise_dt=_opt_float(m.get("noise_dt")))

    @property
    def netlist_hash(self) -> str | None:
        """One sha256 over the decks' netlist hashes, in deck order (None without decks):
        two runs with this hash ran the very same netlists."""
        if not self.deck_sha256:
            return None
        return hashlib.sha256(" ".join(self.deck_sha256).encode()).hexdigest()

    def to_model(self) -> Model | None:
        """The :class:`~analogue.Model` the ensemble simulates (None when not recorded)."""
        return Model(**self.model) if self.model is not None else None

    def as_attrs(self) -> dict:
        """Flat netCDF attributes (str, numbers, lists of numbers) of the whole ``meta``,
        with ``netlist_hash`` added when there are decks: what :meth:`Ensemble.to_netcdf`
        writes (:func:`analogue.netcdf_layout.flat_attrs`)."""
        attrs = netcdf_layout.flat_attrs(dict(self.meta))
        if self.netlist_hash is not None:
            attrs.setdefault("netlist_hash", self.netlist_hash)
        return attrs

    def as_dict(self) -> dict:
        """The ``meta`` dict itself (a copy)."""
        return dict(self.meta)

    # Mapping: every key of meta, as before
    def __getitem__(self, key: str) -> Any:
        return self.meta[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self.meta)

    def __len__(self) -> int:
        return len(self.meta)


@dataclass(frozen=True)
class Ensemble:
    """Trajectories on a common time grid, in model units.

    Attributes
    ----------
    t : (n_t,) array
        Times in model time units, starting at the initial time (usually 0).
    v : (replicas, n_t) array
        Velocities in model velocity units.
    x : (replicas, n_t) array
        Positions ``x(t) = integral_0^t v ds`` (x[:, 0] == 0); work ``W = F (x(t+tau) - x(t))``.
        Spring members: the position relative to ``model.x0`` (the position is
        ``model.x0 + x``); a circuit gives the spring's own position, read back from its
        inductor (``records["x_integral"]`` keeps the integral of v, which the inductor's
        series resistance lets creep away: :mod:`analogue.circuit.mapping`).
    meta : dict
        Provenance: model parameters, source ("circuit" / "sde"), seeds, mapping, ngspice
        version, deck hash, ...  JSON-serialisable.
    noise : (replicas, n_hold) array or None
        The standard normal numbers that drove each replica, one per noise hold time
        ``meta["noise_dt"]``, when the producer recorded them (:func:`analogue.simulate`
        attaches them whenever the circuit's decks record their noise).
    records : dict or None
        Per-replica extras of a circuit run, when it has any: ``"x_spring"`` (replicas, n_t) the
        spring position read back from the inductor, ``"x_integral"`` the integral of v (spring
        members), ``"kicks"`` the shot-noise kicks per
        replica (see :func:`analogue.simulate`).  Not compared, and not carried over by
        :meth:`window` / :meth:`concatenate`; netCDF files (:meth:`to_netcdf`) hold
        ``x_spring`` and ``x_integral``, not the kicks.

    ``to_xarray()`` / ``to_netcdf(path)`` give labelled data (dims ``replica``, ``time``);
    :func:`analogue.open_ensemble` reads such a file back, exactly.
    """

    t: np.ndarray
    v: np.ndarray
    x: np.ndarray
    meta: dict = field(default_factory=dict)
    noise: np.ndarray | None = None
    records: dict[str, Any] | None = field(default=None, compare=False, repr=False)

    def __post_init__(self):
        t = np.asarray(self.t, dtype=float)
        v = np.atleast_2d(np.asarray(self.v, dtype=float))
        x = np.atleast_2d(np.asarray(self.x, dtype=float))
        if t.ndim != 1:
            raise ValueError("Ensemble.t must be one-dimensional")
        if v.shape[1] != t.size or x.shape != v.shape:
            raise ValueError(f"Ensemble shapes disagree: t {t.shape}, v {v.shape}, x {x.shape}")
        if t.size > 1 and not np.all(np.diff(t) > 0):
            raise ValueError("Ensemble.t must be strictly increasing")
        if not isinstance(self.meta, dict):
            raise TypeError(f"Ensemble.meta must be a dict, got {type(self.meta).__name__}")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "v", v)
        object.__setattr__(self, "x", x)
        if self.noise is not None:
            z = np.atleast_2d(np.asarray(self.noise, dtype=float))
            if z.ndim != 2 or z.shape[0] != v.shape[0]:
                raise ValueError(f"Ensemble.noise must have shape (replicas, n_hold) = "
                                 f"({v.shape[0]}, n), got {z.shape}")
            object.__setattr__(self, "noise", z)

    def __repr__(self) -> str:
        """One line: shape, time range, model and a few provenance keys.  The dataclass's own
        repr printed every array (about 15 kB for a small circuit run, issue 20 item 6)."""
        meta = self.meta
        t = (f"t=[{self.t[0]:g}, {self.t[-1]:g}] dt={self.dt:g}" if self.t.size > 1
             else f"t=[{self.t[0]:g}]" if self.t.size else "t=[]")
        parts = [f"replicas={self.replicas}", f"n_t={self.t.size}", t]
        model = meta.get("model")
        if isinstance(model, dict):
            keys = [k for k in ("tau_m", "delta", "a", "gamma") if k in model]
            keys += [k for k in ("cubic", "spring", "stribeck", "shot") if model.get(k)]
            parts.append("model(" + ", ".join(f"{k}={_short(model[k])}" for k in keys) + ")")
        parts += [f"{k}={_short(meta[k])}" for k in _REPR_META if k in meta]
        if self.noise is not None:
            parts.append(f"noise={self.noise.shape}")
        hidden = len(set(meta) - set(_REPR_META) - {"model"})
        if hidden:
            parts.append(f"+{hidden} meta keys")
        return "Ensemble(" + ", ".join(parts) + ")"

    @property
    def replicas(self) -> int:
        return self.v.shape[0]

    @property
    def provenance(self) -> Provenance:
        """``meta`` as a typed :class:`Provenance` (model, seeds, ngspice version, netlist
        hash, tolerances, deck split; ``as_attrs()`` for netCDF).  A view made on access:
        ``meta`` stays the dict it is."""
        return Provenance.from_meta(self.meta)

    @property
    def dt(self) -> float:
        """Sample interval (the grid is uniform for every producer in this package)."""
        return float(self.t[1] - self.t[0]) if self.t.size > 1 else float("nan")

    def at(self, time: float) -> np.ndarray:
        """Velocities of all replicas at the grid time nearest ``time``."""
        i = int(np.argmin(np.abs(self.t - time)))
        return self.v[:, i]

    def window(self, t_start: float, t_stop: float | None = None) -> Ensemble:
        """Sub-ensemble on ``t_start <= t <= t_stop`` (positions re-zeroed at the start; the
        recorded noise, on its own hold grid, is not carried over)."""
        hi = self.t[-1] if t_stop is None else t_stop
        sel = (self.t >= t_start - 1e-12) & (self.t <= hi + 1e-12)
        x = self.x[:, sel]
        return Ensemble(self.t[sel], self.v[:, sel], x - x[:, :1], dict(self.meta))

    def concatenate(self, other: Ensemble) -> Ensemble:
        """Pool replicas of two ensembles on the same time grid."""
        if other.t.shape != self.t.shape or not np.allclose(other.t, self.t):
            raise ValueError("cannot pool ensembles on different time grids")
        # A new list: appending to self.meta["pooled"] would change self (and every ensemble
        # sharing that list) as well.
        meta = {**self.meta, "pooled": [*self.meta.get("pooled", []), other.meta]}
        noise = None
        if (self.noise is not None and other.noise is not None
                and self.noise.shape[1] == other.noise.shape[1]):
            noise = np.vstack([self.noise, other.noise])
        return Ensemble(self.t, np.vstack([self.v, other.v]), np.vstack([self.x, other.x]), meta,
                        noise)

    def to_xarray(self):
        """An ``xarray.Dataset``: ``v`` and ``x`` on dims (``replica``, ``time``), the noise
        (when recorded) on (``replica``, ``noise_time``), units on every coordinate and
        variable, provenance as JSON-safe attributes.  See :mod:`analogue.netcdf_layout`."""
        return netcdf_layout.to_dataset(self, self.provenance.as_attrs())

    @classmethod
    def from_xarray(cls, dataset) -> Ensemble:
        """Inverse of :meth:`to_xarray` (exact: arrays and meta)."""
        return cls(**netcdf_layout.fields_from_dataset(dataset))

    def to_netcdf(self, path) -> None:
        """Write a netCDF-4 file that :func:`analogue.open_ensemble`
        reads back exactly; written atomically."""
        netcdf_layout.write_dataset(self.to_xarray(), path)

    def save(self, path) -> None:
        """Write to a compressed ``.npz`` (meta stored as JSON)."""
        import json
        np.savez_compressed(path, t=self.t, v=self.v, x=self.x, meta=json.dumps(self.meta))

    @classmethod
    def load(cls, path) -> Ensemble:
        import json
        with np.load(path, allow_pickle=False) as f:
            return cls(f["t"], f["v"], f["x"], json.loads(str(f["meta"])))
