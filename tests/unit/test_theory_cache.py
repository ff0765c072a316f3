"""The on-disk theory cache: round trip, key sensitivity, corruption, opt-out."""
import numpy as np
import pytest

from analogue import Model
from analogue.theory import cache as tc

CALLS = []


def _fn(model, w, *, scale=1.0):
    """A pure stand-in for a theory function that counts its calls."""
    CALLS.append(1)
    return scale * model.gamma * np.asarray(w, dtype=float) ** 2


def _pair(model, w):
    CALLS.append(1)
    w = np.asarray(w, dtype=float)
    return w + model.a, w - model.a


@pytest.fixture
def store(tmp_path):
    CALLS.clear()
    return tc.TheoryCache(tmp_path / "theory")


M = Model(tau_m=1.0, delta=1.0, a=0.5, gamma=10.0)


def test_round_trip_returns_identical_arrays_without_recomputing(store):
    w = np.linspace(-1, 1, 7)
    first = tc.cached_call(_fn, M, w, cache=store, scale=2.0)
    second = tc.cached_call(_fn, M, w, cache=store, scale=2.0)
    assert len(CALLS) == 1 and store.hits == 1 and store.misses == 1
    np.testing.assert_array_equal(first, second)
    assert second.dtype == first.dtype and second.shape == first.shape
    a, b = tc.cached_call(_pair, M, w, cache=store), tc.cached_call(_pair, M, w, cache=store)
    assert isinstance(b, tuple) and len(CALLS) == 2
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x, y)


def test_key_changes_with_model_arguments_keywords_and_function(store):
    w = np.linspace(-1, 1, 7)
    keys = {tc.theory_key("f", (M, w), {"scale": 1.0}),
            tc.theory_key("f", (M.replace(gamma=10.000000000000002), w), {"scale": 1.0}),
            tc.theory_key("f", (M, w + 1e-15), {"scale": 1.0}),
            tc.theory_key("f", (M, w), {"scale": 2.0}),
            tc.theory_key("g", (M, w), {"scale": 1.0}),
            tc.theory_key("f", (M, w.astype(np.float32)), {"scale": 1.0})}
    assert len(keys) == 6
    # a list and the equal float array share an entry
    tc.cached_call(_fn, M, [0.0, 0.5], cache=store)
    tc.cached_call(_fn, M, np.array([0.0, 0.5]), cache=store)
    assert len(CALLS) == 1


@pytest.mark.parametrize("damage", ["truncate", "flip", "garbage", "foreign"])
def test_bad_entry_is_ignored_recomputed_and_overwritten(store, damage):
    w = np.linspace(-1, 1, 5)
    good = tc.cached_call(_fn, M, w, cache=store)
    key = tc.theory_key(f"{_fn.__module__}.{_fn.__qualname__}", (M, w), {})
    p = store.path(key)
    data = p.read_bytes()
    if damage == "truncate":
        p.write_bytes(data[: len(data) // 2])
    elif damage == "flip":
        # a readable npz whose array no longer matches the checksum in its meta
        import json
        arrays, meta = store.get(key)
        with open(p, "wb") as fh:
            np.savez(fh, __meta__=np.array(json.dumps(meta)), r0=arrays["r0"] + 1.0)
    elif damage == "garbage":
        p.write_bytes(b"not a zip file at all")
    else:   # an intact entry filed under the wrong key
        other = tc.theory_key("other", (M,), {})
        store.put(other, {"r0": np.zeros(5)}, {"kind": "array", "n": 1})
        p.write_bytes(store.path(other).read_bytes())
    assert store.get(key) is None
    again = tc.cached_call(_fn, M, w, cache=store)
    np.testing.assert_array_equal(again, good)
    assert len(CALLS) == 2
    assert store.get(key) is not None            # rewritten
    assert not list(p.parent.glob("*.tmp"))      # no temporary file left behind


def test_opt_out_and_environment(tmp_path, monkeypatch):
    CALLS.clear()
    w = np.array([0.1])
    tc.cached_call(_fn, M, w, cache=False)
    tc.cached_call(_fn, M, w, cache=False)
    assert len(CALLS) == 2
    monkeypatch.setenv("ANALOGUE_THEORY_CACHE", "off")
    assert tc.open_cache() is None
    monkeypatch.setenv("ANALOGUE_THEORY_CACHE", str(tmp_path / "here"))
    assert tc.open_cache().root == tmp_path / "here"
    monkeypatch.delenv("ANALOGUE_THEORY_CACHE")
    monkeypatch.setenv("ANALOGUE_STORE", str(tmp_path / "runs"))
    assert tc.default_cache_path() == tmp_path / "runs" / "theory"
    with pytest.raises(TypeError, match="cache"):
        tc.open_cache(3.5)


def test_decorator_keeps_the_pure_function_and_adds_cache_keyword(store):
    wrapped = tc.cached(_fn)
    assert wrapped.uncached is _fn and wrapped.__name__ == "_fn"
    w = np.array([0.3, 0.4])
    np.testing.assert_array_equal(wrapped(M, w, cache=store), _fn(M, w))
    wrapped(M, w, cache=store)
    assert store.hits == 1


def test_code_version_is_stable_within_a_process():
    assert tc.code_version() == tc.code_version() and len(tc.code_version()) == 64


def test_named_tuple_results_come_back_as_the_same_type(store):
    from analogue.theory import exact
    first = tc.cached_call(exact.stationary_moments, M, cache=store)
    second = tc.cached_call(exact.stationary_moments, M, cache=store)
    assert store.hits == 1
    assert type(second) is type(first) and second == first
    assert isinstance(second.variance, float)


def test_cached_later_reads_now_computes_elsewhere_and_stores_here(store):
    """cached_later: the cache is read when called; a miss is started with ``submit`` (a
    worker process in a study) and stored by the caller when its result is taken; a hit
    starts nothing."""
    from concurrent.futures import ThreadPoolExecutor
    w = np.linspace(-1, 1, 5)
    submitted = []
    with ThreadPoolExecutor(1) as ex:
        def submit(fn, *a, **k):
            submitted.append(fn)
            return ex.submit(fn, *a, **k)
        get = tc.cached_later(_fn, M, w, cache=store, submit=submit, scale=3.0)
        assert submitted == [_fn] and store.misses == 1
        first = get()
        assert len(CALLS) == 1
        again = tc.cached_later(_fn, M, w, cache=store, submit=submit, scale=3.0)
        assert submitted == [_fn] and store.hits == 1          # a hit starts nothing
        np.testing.assert_array_equal(again(), first)
        # the value stored is the one cached_call would have computed and stored
        np.testing.assert_array_equal(first, 3.0 * M.gamma * w ** 2)
        np.testing.assert_array_equal(tc.cached_call(_fn, M, w, cache=store, scale=3.0), first)
        assert len(CALLS) == 1
        # no cache: submitted each time, nothing stored
        off = tc.cached_later(_fn, M, w, cache=False, submit=submit, scale=3.0)
        np.testing.assert_array_equal(off(), first)
        assert submitted == [_fn, _fn] and len(CALLS) == 2
    # without submit: computed when the function returned is called
    lazy = tc.cached_later(_fn, M, w + 1, cache=store)
    assert len(CALLS) == 2
    lazy()
    assert len(CALLS) == 3
