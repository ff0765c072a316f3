"""Which store entries belong to which experiment, and keeping the store's size bounded.

The run store (:mod:`analogue.circuit.store`) is content-addressed: an entry's key says
nothing about the experiment it came from.  Whenever an experiment's runs complete
(``analogue run/report/paper/export``, :func:`analogue.load_runs`; a family member's as well
as the paper's model's: both runners are decorated with :func:`indexing_runs`) the keys of
their decks are recorded in an index file per experiment::

    <store>/index/<experiment>.json   {"experiment", "updated", "runs": {"<size>/<role>":
                                       {"keys": [...], "replicas": n, "updated": time}}}

(``<size>`` is ``full`` or ``quick``).  :func:`usage` lists the store by experiment
(``analogue store ls``, ``du``); :func:`prune` deletes entries by experiment, age, total size
(least recently used first) or because no index names them (``analogue store prune``).  An
index only names entries: deleting one is always safe, the next run recomputes what is missing.
"""
from __future__ import annotations

import contextvars
import functools
import json
import logging
import os
import re
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from .. import checks
from .store import RunStore, open_store

__all__ = [
    "INDEX_DIR",
    "StoreUsage",
    "collecting_keys",
    "format_size",
    "indexing_runs",
    "note_keys",
    "parse_size",
    "prune",
    "read_indexes",
    "record_runs",
    "usage",
]

INDEX_DIR = "index"
_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,31}$")
log = logging.getLogger(__name__)

# Store keys used while an experiment's runs are made, including those of runs that are not
# among its named roles (the tolerance calibration of analogue.circuit.tolerances): every
# run_decks call notes its keys into each collector that is open (a context variable, so that
# concurrent threads or tasks do not mix their keys).
_COLLECTORS: contextvars.ContextVar[tuple] = contextvars.ContextVar("analogue_store_keys",
                                                                    default=())


@contextmanager
def collecting_keys():
    """Collect (into the yielded set) the store keys of every deck run or read inside."""
    bag: set = set()
    token = _COLLECTORS.set(_COLLECTORS.get() + (bag,))
    try:
        yield bag
    finally:
        _COLLECTORS.reset(token)


def note_keys(keys) -> None:
    """Called by the runner with the keys of the decks it runs or reads."""
    for bag in _COLLECTORS.get():
        bag.update(keys)


def indexing_runs(fn):
    """Decorator for ``run_experiment_runs(exp, opts, ...)`` and ``member_runs(exp, opts,
    ...)`` (whose results name their runs by role, ``.by_role()``, and say their size,
    ``.quick``): record the runs it returns, and every other store entry it used, in the
    experiment's index.  A failure to write the index
    (read-only store) is a warning: the runs are still returned."""
    @functools.wraps(fn)
    def wrapper(exp, opts, *args, **kwargs):
        with collecting_keys() as used:
            runs = fn(exp, opts, *args, **kwargs)
        try:
            record_runs(exp.name, runs.by_role(), quick=bool(runs.quick), extra_keys=used,
                        store=getattr(opts, "store", None))
        except OSError as exc:
            log.warning("run store index not written: %s", exc)
        return runs
    return wrapper


def _index_dir(store: RunStore) -> Path:
    return store.root / INDEX_DIR


def record_runs(experiment: str, runs: dict, *, quick: bool, store=None,
                extra_keys=()) -> Path | None:
    """Record the store keys of ``runs`` (role -> Ensemble with ``meta["store_keys"]``) as
    experiment ``experiment``'s, and ``extra_keys`` (entries it used besides, e.g. the
    tolerance calibration) under the role ``other``; returns the index file (None when the runs
    were not stored).  Merges with what the index already holds (other roles, the other
    size)."""
    if not isinstance(experiment, str) or not _NAME.fullmatch(experiment):
        raise ValueError(f"experiment must be an experiment name, got {experiment!r}")
    roots = {e.meta.get("store") for e in runs.values()} - {None}
    if store is None:
        if len(roots) != 1:   # not stored, or (never in practice) in two stores
            return None
        store = next(iter(roots))
    st = open_store(store)
    if st is None:
        return None
    path = _index_dir(st) / f"{experiment}.json"
    data = _read(path) or {"experiment": experiment, "runs": {}}
    now = time.time()
    size = "quick" if quick else "full"
    named: set = set()
    for role, ens in runs.items():
        keys = [k for k in ens.meta.get("store_keys", []) if isinstance(k, str)]
        named.update(keys)
        data["runs"][f"{size}/{role}"] = {"keys": keys, "replicas": int(ens.replicas),
                                          "updated": now}
    # accumulated, not replaced: a repeated call may reuse an in-process memo (the tolerance
    # choice) and touch fewer entries than the first one did
    previous = data["runs"].get(f"{size}/other", {}).get("keys", [])
    other = sorted((set(extra_keys) | set(previous)) - named)
    if other:
        data["runs"][f"{size}/other"] = {"keys": other, "replicas": 0, "updated": now}
    data["updated"] = now
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n")
    os.replace(tmp, path)
    return path


def _read(path: Path) -> dict | None:
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or not isinstance(data.get("runs"), dict):
        return None
    return data


def read_indexes(store) -> dict[str, dict]:
    """experiment -> its index data (unreadable index files are skipped)."""
    st = open_store(store)
    d = _index_dir(st)
    out = {}
    if d.is_dir():
        for p in sorted(d.glob("*.json")):
            data = _read(p)
            if data is not None:
                out[p.stem] = data
    return out


@dataclass
class StoreUsage:
    """The store by experiment: sizes in bytes, entry counts, last use (epoch seconds)."""

    root: Path
    experiments: dict = field(default_factory=dict)   # name -> {"entries", "bytes", "updated", "runs"}
    unindexed_entries: int = 0
    unindexed_bytes: int = 0
    total_entries: int = 0
    total_bytes: int = 0
    quarantined: int = 0
    quarantined_bytes: int = 0


def _entry_owners(store: RunStore) -> tuple[dict, dict]:
    """(key -> set of experiments, experiment -> index data)."""
    indexes = read_indexes(store)
    owners: dict = {}
    for name, data in indexes.items():
        for run in data["runs"].values():
            for k in run.get("keys", []):
                owners.setdefault(k, set()).add(name)
    return owners, indexes


def usage(store=None) -> StoreUsage:
    """What the store holds, by experiment (entries shared by two experiments count in both;
    the total counts them once)."""
    st = open_store(store)
    entries = st.entries()
    owners, indexes = _entry_owners(st)
    u = StoreUsage(root=st.root, total_entries=len(entries),
                   total_bytes=sum(e.size for e in entries))
    for name, data in indexes.items():
        u.experiments[name] = {"entries": 0, "bytes": 0, "updated": data.get("updated"),
                               "runs": sorted(data["runs"])}
    for e in entries:
        names = owners.get(e.key)
        if not names:
            u.unindexed_entries += 1
            u.unindexed_bytes += e.size
        for n in names or ():
            u.experiments[n]["entries"] += 1
            u.experiments[n]["bytes"] += e.size
    q = st.quarantined()
    u.quarantined = len(q)
    u.quarantined_bytes = sum(p.stat().st_size for p in q if p.is_file())
    return u


_UNITS = {"": 1, "B": 1, "K": 1e3, "KB": 1e3, "M": 1e6, "MB": 1e6, "G": 1e9, "GB": 1e9,
          "T": 1e12, "TB": 1e12}


def parse_size(text: str) -> int:
    """'500M' -> 500_000_000 (decimal units B, K/KB, M/MB, G/GB, T/TB)."""
    m = re.fullmatch(r"\s*([0-9]*\.?[0-9]+)\s*([A-Za-z]*)\s*", str(text))
    if not m or m.group(2).upper() not in _UNITS:
        raise ValueError(f"size must be a number with an optional unit (K, M, G, T), e.g. "
                         f"500M, got {text!r}")
    return int(float(m.group(1)) * _UNITS[m.group(2).upper()])


def format_size(n: float) -> str:
    for unit in ("B", "kB", "MB", "GB"):
        if abs(n) < 1000 or unit == "GB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1000.0
    return f"{n:.1f} GB"  # pragma: no cover


def prune(store=None, *, experiments=(), unindexed: bool = False,
          older_than_days: float | None = None, max_bytes: int | None = None,
          quarantine: bool = False, dry_run: bool = False) -> dict:
    """Delete store entries; returns ``{"entries": n, "bytes": b, "quarantined": q,
    "tmp": t, "keys": [...]}`` (what was, or with ``dry_run`` would be, deleted).

    - ``experiments``: every entry of these experiments (their index files go too);
    - ``unindexed``: entries no experiment index names (ad-hoc ``simulate`` calls);
    - ``older_than_days``: entries last used (written, or recorded by an index) before then;
    - ``max_bytes``: then the least recently used entries until the store holds at most this;
    - ``quarantine``: empty the quarantine directory.
    At least one criterion is required.  Temporary files of dead writers are always removed.
    """
    if not (experiments or unindexed or older_than_days is not None or max_bytes is not None
            or quarantine):
        raise ValueError("prune needs a criterion: experiments, unindexed, older_than_days, "
                         "max_bytes or quarantine")
    if older_than_days is not None:
        older_than_days = checks.nonnegative("older_than_days", older_than_days)
    if max_bytes is not None:
        checks.nonnegative("max_bytes", max_bytes)
    st = open_store(store)
    owners, indexes = _entry_owners(st)
    unknown = [n for n in experiments if n not in indexes]
    if unknown:
        raise ValueError(f"no index for experiment(s) {', '.join(unknown)} in {st.root} "
                         f"(indexed: {', '.join(indexes) or 'none'})")
    entries = st.entries()
    last_used = {}
    for e in entries:
        t = e.mtime
        for name in owners.get(e.key, ()):
            for run in indexes[name]["runs"].values():
                if e.key in run.get("keys", []):
                    t = max(t, float(run.get("updated") or 0.0))
        last_used[e.key] = t
    doomed: dict = {}
    cutoff = None if older_than_days is None else time.time() - older_than_days * 86400.0
    for e in entries:
        names = owners.get(e.key, set())
        by_experiment = bool(experiments) and bool(names & set(experiments))
        by_index = unindexed and not names
        by_age = cutoff is not None and last_used[e.key] < cutoff
        if by_experiment or by_index or by_age:
            doomed[e.key] = e
    if max_bytes is not None:
        left = [e for e in entries if e.key not in doomed]
        total = sum(e.size for e in left)
        for e in sorted(left, key=lambda e: last_used[e.key]):
            if total <= max_bytes:
                break
            doomed[e.key] = e
            total -= e.size
    q = st.quarantined() if quarantine else []
    out = {"entries": len(doomed), "bytes": sum(e.size for e in doomed.values()),
           "quarantined": len(q), "keys": sorted(doomed), "tmp": 0}
    if dry_run:
        return out
    for key in doomed:
        st.remove(key)
    for p in q:
        if p.is_file():
            p.unlink()
        p.with_suffix(".json").unlink(missing_ok=True)
    for name in experiments:
        (_index_dir(st) / f"{name}.json").unlink(missing_ok=True)
    out["tmp"] = st.clean_tmp()
    return out
