"""Run store: content keys, atomic writes, repeated calls cost nothing, interrupted runs resume."""
from __future__ import annotations

import numpy as np
import pytest

import analogue
from analogue.circuit import ngspice as ng
from analogue.circuit import store as store_mod
from analogue.circuit.store import RunStore, batch_key, open_store
from conftest import STICK_A02

pytestmark = pytest.mark.requires_ngspice

KW = dict(v0=0.4, t_end=1.0, replicas=8, seed=5, replicas_per_deck=2, progress=False)


@pytest.fixture
def counted(monkeypatch):
    """Count (and optionally sabotage) ngspice runs made through the runner."""
    real = ng.run_deck
    state = {"runs": 0, "fail_seed": None}

    def wrapper(text, **kw):
        if state["fail_seed"] is not None and f"seed={state['fail_seed']} " in text:
            raise ng.NgspiceError("simulated crash")
        state["runs"] += 1
        return real(text, **kw)

    monkeypatch.setattr(ng, "run_deck", wrapper)
    return state


# ------------------------------------------------------------------------------ keys
def test_key_depends_on_everything_that_determines_the_numbers():
    t = np.linspace(0, 1, 11)
    k = batch_key("deck\n.end\n", t, "39")
    assert k == batch_key("deck\n.end\n", t.copy(), "39")
    assert len(k) == 64 and int(k, 16) >= 0
    others = {batch_key("deck2\n.end\n", t, "39"), batch_key("deck\n.end\n", t[:-1], "39"),
              batch_key("deck\n.end\n", t * 1.0000001, "39"), batch_key("deck\n.end\n", t, "40"),
              batch_key("deck\n.end\n", t, "39", schema=store_mod.SCHEMA_VERSION + 1)}
    assert k not in others and len(others) == 5


# ----------------------------------------------------------------------------- the store
def test_put_get_roundtrip_and_listing(tmp_path):
    st = RunStore(tmp_path)
    key = batch_key("x\n.end\n", [0.0, 1.0], "39")
    assert st.get(key) is None and key not in st and st.keys() == []
    arrays = {"v": np.arange(6.0).reshape(2, 3), "x": np.ones((2, 3))}
    p = st.put(key, arrays, {"seed": np.int64(3), "note": "ok"})
    assert p.is_file() and p.parent.name == key[:2]
    got, meta = st.get(key)
    np.testing.assert_array_equal(got["v"], arrays["v"])
    np.testing.assert_array_equal(got["x"], arrays["x"])
    assert meta == {"seed": 3, "note": "ok"}
    assert st.keys() == [key] and key in st
    with pytest.raises(ValueError, match="key"):
        st.path("../../etc/passwd")


def test_atomic_write_leaves_no_partial_file(tmp_path, monkeypatch):
    st = RunStore(tmp_path)
    key = batch_key("y\n.end\n", [0.0, 1.0], "39")
    st.put(key, {"v": np.zeros(3)}, {"version": 1})

    def exploding_savez(fh, **arrays):
        fh.write(b"PK\x03\x04 half a zip file")  # a partial write, then the crash
        raise KeyboardInterrupt

    monkeypatch.setattr(store_mod.np, "savez", exploding_savez)
    with pytest.raises(KeyboardInterrupt):
        st.put(key, {"v": np.ones(3)}, {"version": 2})
    other = batch_key("z\n.end\n", [0.0, 1.0], "39")
    with pytest.raises(KeyboardInterrupt):
        st.put(other, {"v": np.ones(3)}, {})
    monkeypatch.undo()
    arrays, meta = st.get(key)  # the old complete entry is untouched
    assert meta == {"version": 1}
    np.testing.assert_array_equal(arrays["v"], np.zeros(3))
    assert other not in st
    leftovers = [p for p in tmp_path.rglob("*") if p.is_file() and p.suffix != ".npz"]
    assert leftovers == []


def test_unreadable_entry_counts_as_missing(tmp_path):
    st = RunStore(tmp_path)
    key = batch_key("w\n.end\n", [0.0], "39")
    st.path(key).parent.mkdir(parents=True)
    st.path(key).write_bytes(b"garbage")
    assert st.get(key) is None


def test_store_location(monkeypatch, tmp_path):
    monkeypatch.setenv("ANALOGUE_STORE", str(tmp_path / "env"))
    assert open_store(None).root == tmp_path / "env"
    assert open_store(tmp_path / "arg").root == tmp_path / "arg"
    assert open_store(False) is None
    monkeypatch.delenv("ANALOGUE_STORE")
    assert open_store(None).root == store_mod.Path.home() / ".cache" / "analogue" / "runs"
    with pytest.raises(ValueError, match="store"):
        open_store(42)


# ------------------------------------------------------------------ through simulate
def test_second_call_runs_no_ngspice(tmp_path, counted):
    first = analogue.simulate(STICK_A02, store=tmp_path, **KW)
    assert counted["runs"] == 4 and first.meta["ran"] == 4 and first.meta["from_store"] == 0
    assert len(RunStore(tmp_path).keys()) == 4
    second = analogue.simulate(STICK_A02, store=tmp_path, **KW)
    assert counted["runs"] == 4  # nothing ran
    assert second.meta["from_store"] == 4 and second.meta["ran"] == 0
    # the wall times of the decks this call ran (the report's critical path): none from the
    # store, while deck_wall_times keeps every deck's (the stored ones' from their run)
    assert len(first.meta["ran_deck_wall_times"]) == 4
    assert all(w > 0 for w in first.meta["ran_deck_wall_times"])
    assert second.meta["ran_deck_wall_times"] == []
    assert len(second.meta["deck_wall_times"]) == 4
    np.testing.assert_array_equal(first.v, second.v)
    np.testing.assert_array_equal(first.x, second.x)
    assert second.meta["store_keys"] == first.meta["store_keys"]
    # another output grid is another result
    analogue.simulate(STICK_A02, store=tmp_path, sample_dt=0.02, **KW)
    assert counted["runs"] == 8


def test_environment_variable_selects_store(tmp_path, monkeypatch, counted):
    monkeypatch.setenv("ANALOGUE_STORE", str(tmp_path / "runs"))
    e = analogue.simulate(STICK_A02, **{**KW, "replicas": 2})
    assert e.meta["store"] == str(tmp_path / "runs") and counted["runs"] == 1
    analogue.simulate(STICK_A02, **{**KW, "replicas": 2})
    assert counted["runs"] == 1


def test_interrupted_run_resumes(tmp_path, counted):
    seeds = analogue.circuit.simulate.deck_seeds(KW["seed"], 4)
    counted["fail_seed"] = seeds[2]
    with pytest.raises(ng.NgspiceError, match="simulated crash"):
        analogue.simulate(STICK_A02, store=tmp_path, workers=1, **KW)
    done = len(RunStore(tmp_path).keys())
    assert 1 <= done <= 3  # decks finished before the crash were kept
    assert not ng._ACTIVE  # no ngspice process of the failed call is left running
    counted["fail_seed"] = None
    before = counted["runs"]
    resumed = analogue.simulate(STICK_A02, store=tmp_path, **KW)
    assert counted["runs"] - before == 4 - done
    assert resumed.meta["from_store"] == done
    fresh = analogue.simulate(STICK_A02, store=False, **KW)
    np.testing.assert_array_equal(resumed.v, fresh.v)
    np.testing.assert_array_equal(resumed.x, fresh.x)


def test_stored_provenance(tmp_path):
    e = analogue.simulate(STICK_A02, store=tmp_path, **{**KW, "replicas": 2})
    (key,) = e.meta["store_keys"]
    arrays, meta = RunStore(tmp_path).get(key)
    np.testing.assert_array_equal(arrays["t"], e.t)
    assert meta["ngspice_version"] == ng.ngspice_version()
    assert meta["schema_version"] == store_mod.SCHEMA_VERSION
    assert f"seed={e.meta['deck_seeds'][0]} " in meta["deck_text"]
    assert batch_key(meta["deck_text"], e.t, meta["ngspice_version"]) == key
