"""Fault injection: a damaged run store (issue 8, section 3).

A reference run fills a store with four one-replica decks (real ngspice, ~1 s).  Each test
copies that store, damages it (truncation, zero length, bit flips at several places, an entry
filed under another key, NaN or missing arrays, wrong shapes or grid, a deck that is not the
requested one, junk files, a directory where an entry should be, a read-only store) and runs the
same ``simulate`` again.  Exact outcome asserted every time: the arrays are byte-identical to
the reference, only the damaged deck re-ran, one single-line warning per damaged entry, the
damaged file was moved (not deleted) to ``quarantine/``, and the store is whole afterwards.

Read-only stores: the tests run as root, for whom chmod does not make a directory unwritable;
a read-only store is simulated (1) by a regular file where the store directory should be and
(2) by making ``os.replace`` (the store's commit step) raise PermissionError.
"""
from __future__ import annotations

import json
import logging
import os
import shutil
import time
from pathlib import Path

import numpy as np
import pytest

import analogue
from analogue.circuit import store as store_mod
from analogue.circuit.store import RunStore
from conftest import STICK_A02

pytestmark = pytest.mark.requires_ngspice

KW = {"v0": 0.4, "t_end": 1.0, "replicas": 4, "seed": 7, "replicas_per_deck": 1, "progress": False,
      "workers": 2}
LOGGER = "analogue.circuit.store"


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    root = tmp_path_factory.mktemp("ref") / "store"
    ens = analogue.simulate(STICK_A02, store=root, **KW)
    assert ens.meta["ran"] == 4
    return root, ens


@pytest.fixture
def store(reference, tmp_path):
    root, ens = reference
    copy = tmp_path / "store"
    shutil.copytree(root, copy)
    return copy, ens


def _same_bytes(a, b) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def _store_warnings(caplog) -> list[str]:
    return [r.getMessage() for r in caplog.records
            if r.name.startswith("analogue") and r.levelno >= logging.WARNING]


def _rerun(root, caplog, expect_ran, ref):
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="analogue"):
        ens = analogue.simulate(STICK_A02, store=root, **KW)
    assert ens.meta["ran"] == expect_ran and ens.meta["from_store"] == 4 - expect_ran
    assert _same_bytes(ens.v, ref.v) and _same_bytes(ens.x, ref.x) and _same_bytes(ens.t, ref.t)
    return _store_warnings(caplog)


# --------------------------------------------------------------------------- damage cases
def _flip(path: Path, where: float):
    data = bytearray(path.read_bytes())
    i = min(len(data) - 1, int(where * len(data)))
    data[i] ^= 0x10
    path.write_bytes(bytes(data))


def _rewrite(path: Path, key: str, change):
    """Re-file a *well-formed* entry whose content was changed by ``change(arrays, meta)``, via
    the store's own writer (valid checksum): only the semantic checks can catch it."""
    st = RunStore(path.parent.parent)
    arrays, meta = st.get(key)
    change(arrays, meta)
    st.put(key, arrays, meta)


DAMAGE = {
    "truncated": lambda p, k, keys, root: p.write_bytes(p.read_bytes()[: p.stat().st_size // 2]),
    "zero-length": lambda p, k, keys, root: p.write_bytes(b""),
    "bitflip-start": lambda p, k, keys, root: _flip(p, 0.01),
    "bitflip-data": lambda p, k, keys, root: _flip(p, 0.5),
    "bitflip-meta": lambda p, k, keys, root: _flip(p, 0.9),
    "bitflip-directory": lambda p, k, keys, root: _flip(p, 0.995),
    "not-a-zip": lambda p, k, keys, root: p.write_text("hello, I am not an entry\n"),
    "swapped": lambda p, k, keys, root: shutil.copyfile(RunStore(root).path(keys[0]), p),
    "nan": lambda p, k, keys, root: _rewrite(
        p, k, lambda a, m: a["v"].__setitem__((0, 5), np.nan)),
    "inf-x": lambda p, k, keys, root: _rewrite(
        p, k, lambda a, m: a["x"].__setitem__((0, 5), np.inf)),
    "missing-x": lambda p, k, keys, root: _rewrite(p, k, lambda a, m: a.pop("x")),
    "missing-noise": lambda p, k, keys, root: _rewrite(p, k, lambda a, m: a.pop("noise")),
    "wrong-shape": lambda p, k, keys, root: _rewrite(
        p, k, lambda a, m: a.__setitem__("v", a["v"][:, :50])),
    "wrong-grid": lambda p, k, keys, root: _rewrite(
        p, k, lambda a, m: a.__setitem__("t", a["t"] * 2)),
    "other-deck": lambda p, k, keys, root: _rewrite(
        p, k, lambda a, m: m.__setitem__("deck_text", m["deck_text"].replace("seed=", "seed=1"))),
}


@pytest.mark.parametrize("damage", sorted(DAMAGE))
def test_damaged_entry_is_quarantined_and_rerun(store, caplog, damage):
    root, ref = store
    keys = ref.meta["store_keys"]
    victim = keys[1]
    path = RunStore(root).path(victim)
    DAMAGE[damage](path, victim, keys, root)
    damaged = path.read_bytes()
    warnings = _rerun(root, caplog, 1, ref)
    assert len(warnings) == 1, warnings
    (msg,) = warnings
    assert "\n" not in msg and victim[:12] in msg and "quarantine" in msg
    moved = sorted((root / "quarantine").glob(f"{victim}*.npz"))
    assert len(moved) == 1 and moved[0].read_bytes() == damaged  # kept, not deleted
    # the store is whole again and silent
    assert _rerun(root, caplog, 0, ref) == []


def test_directory_in_place_of_an_entry(store, caplog):
    root, ref = store
    victim = ref.meta["store_keys"][2]
    path = RunStore(root).path(victim)
    path.unlink()
    path.mkdir()
    (path / "inside").write_text("x")
    warnings = _rerun(root, caplog, 1, ref)
    assert len(warnings) == 1 and "quarantine" in warnings[0]
    assert (next((root / "quarantine").glob(f"{victim}*.npz")) / "inside").read_text() == "x"
    assert _rerun(root, caplog, 0, ref) == []


def test_several_damaged_entries_each_warn_once(store, caplog):
    root, ref = store
    keys = ref.meta["store_keys"]
    RunStore(root).path(keys[0]).write_bytes(b"")
    _flip(RunStore(root).path(keys[3]), 0.5)
    warnings = _rerun(root, caplog, 2, ref)
    assert len(warnings) == 2
    assert sum(keys[0][:12] in w for w in warnings) == 1
    assert sum(keys[3][:12] in w for w in warnings) == 1


# ----------------------------------------------------------------------------- junk files
def test_junk_files_are_ignored_and_stale_tmp_removed(store, caplog):
    root, ref = store
    keys = ref.meta["store_keys"]
    shard = RunStore(root).path(keys[0]).parent
    junk = [root / "README.txt", root / "zz" / "notes.md", shard / "notakey.npz",
            shard / ("0" * 63 + ".npz"), root / "ab" / ("ab" + "c" * 62 + ".npz.bak")]
    for j in junk:
        j.parent.mkdir(exist_ok=True)
        j.write_bytes(b"junk")
    host = store_mod._host()
    stale_old = shard / f".{keys[0][:12]}.otherhost.1.x.tmp"   # another host, 2 days old
    stale_dead = shard / f".{keys[0][:12]}.{host}.{2**22 + 12345}.x.tmp"  # our host, no such pid
    live = shard / f".{keys[0][:12]}.{host}.{os.getpid()}.x.tmp"         # a writer still at work
    for f in (stale_old, stale_dead, live):
        f.write_bytes(b"partial")
    old = time.time() - 2 * 86400
    os.utime(stale_old, (old, old))
    warnings = _rerun(root, caplog, 0, ref)
    assert warnings == []
    assert all(j.read_bytes() == b"junk" for j in junk)  # not ours: left alone
    assert not stale_old.exists() and not stale_dead.exists()
    assert live.exists()
    assert sorted(RunStore(root).keys()) == sorted(keys)


# ------------------------------------------------------------------------- read-only store
def test_store_path_is_a_file(reference, tmp_path, caplog):
    _, ref = reference
    blocker = tmp_path / "store"
    blocker.write_text("a file where the store directory should be")
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="analogue"):
        ens = analogue.simulate(STICK_A02, store=blocker, **KW)
    assert _same_bytes(ens.v, ref.v) and _same_bytes(ens.x, ref.x)
    assert ens.meta["ran"] == 4
    warnings = _store_warnings(caplog)
    assert len(warnings) == 1 and "\n" not in warnings[0]
    assert "not stored" in warnings[0] and str(blocker) in warnings[0]
    assert blocker.read_text().startswith("a file")


def test_commit_refused_permission(reference, tmp_path, caplog, monkeypatch):
    _, ref = reference
    root = tmp_path / "ro"

    def refuse(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(store_mod.os, "replace", refuse)
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="analogue"):
        ens = analogue.simulate(STICK_A02, store=root, **KW)
    monkeypatch.undo()
    assert _same_bytes(ens.v, ref.v) and _same_bytes(ens.x, ref.x)
    warnings = _store_warnings(caplog)
    assert len(warnings) == 1 and "not stored" in warnings[0] and "Permission denied" in warnings[0]
    assert [p for p in root.rglob("*") if p.is_file()] == []  # no partial or temporary file


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only directories")
def test_read_only_directory(store, caplog):  # pragma: no cover - not run as root
    root, ref = store
    victim = ref.meta["store_keys"][0]
    RunStore(root).path(victim).unlink()
    for d in [root, *root.iterdir()]:
        d.chmod(0o555)
    try:
        warnings = _rerun(root, caplog, 1, ref)
        assert len(warnings) == 1 and "not stored" in warnings[0]
    finally:
        for d in [root, *root.iterdir()]:
            d.chmod(0o755)


# ----------------------------------------------------------------------- sharing, format
@pytest.mark.parametrize("umask,file_mode,dir_mode", [(0o022, 0o644, 0o2755),
                                                     (0o002, 0o664, 0o2775),
                                                     (0o077, 0o640, 0o2750)])
def test_entries_are_group_readable(tmp_path, umask, file_mode, dir_mode):
    old = os.umask(umask)
    try:
        st = RunStore(tmp_path / "shared")
        key = store_mod.batch_key("d\n.end\n", [0.0, 1.0], "39")
        p = st.put(key, {"v": np.zeros(3)}, {})
    finally:
        os.umask(old)
    assert p.stat().st_mode & 0o7777 == file_mode
    assert p.parent.stat().st_mode & 0o7777 == dir_mode
    assert st.root.stat().st_mode & 0o7777 == dir_mode


def test_entry_records_its_key_and_checksum(tmp_path):
    st = RunStore(tmp_path)
    key = store_mod.batch_key("d\n.end\n", [0.0, 1.0], "39")
    st.put(key, {"v": np.arange(3.0)}, {"a": 1})
    import zipfile
    with zipfile.ZipFile(st.path(key)) as zf:
        names = set(zf.namelist())
        assert {"v.npy", "__meta__.npy", "__integrity__.npy"} <= names
    info = st.entries()
    assert [e.key for e in info] == [key] and info[0].size == st.path(key).stat().st_size
    assert st.size_bytes() == info[0].size
    assert store_mod.SCHEMA_VERSION >= 2  # format changed: old entries are never read


def test_get_reports_problems_without_moving_on_check(tmp_path, caplog):
    st = RunStore(tmp_path)
    key = store_mod.batch_key("d\n.end\n", [0.0, 1.0], "39")
    st.put(key, {"v": np.arange(3.0)}, {"a": 1})
    assert st.problem(key) is None
    _flip(st.path(key), 0.5)
    problem = st.problem(key)
    assert problem and "\n" not in problem
    assert st.path(key).exists()  # problem() only looks
    with caplog.at_level(logging.WARNING, logger="analogue"):
        assert st.get(key) is None
    assert not st.path(key).exists() and len(st.quarantined()) == 1
    assert json.loads(st.quarantined()[0].with_suffix(".json").read_text())["key"] == key


def test_entry_of_another_user_not_readable_is_recomputed_not_quarantined(store, caplog,
                                                                         monkeypatch):
    """A private entry written by another user of a shared store is not damage: one warning,
    recomputed, not moved to quarantine.  (Root reads every file, so unreadability is
    simulated by os.access answering False for that one file.)"""
    root, ref = store
    victim = ref.meta["store_keys"][2]
    path = RunStore(root).path(victim)
    real_access = os.access

    def access(p, mode, *a, **kw):
        if Path(p) == path and mode == os.R_OK and not state["replaced"]:
            return False
        return real_access(p, mode, *a, **kw)

    state = {"replaced": False}
    monkeypatch.setattr(store_mod.os, "access", access)
    warnings = _rerun(root, caplog, 1, ref)
    assert len(warnings) == 1 and "not readable by this user" in warnings[0]
    assert not (root / "quarantine").exists()
    state["replaced"] = True
    assert _rerun(root, caplog, 0, ref) == []  # the recomputed entry replaced it
