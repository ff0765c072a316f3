"""Fault injection: the simulator returns wrong numbers (issue 19, items 2 and 3).

Route 1, a damaged ngspice: a wrapper around the real ngspice (tests/wrapped_ngspice.py)
answers ``-v`` exactly like it (so a result would be filed under the real store key), runs
the deck and then rewrites a valid raw file: thinned to every 25th point (still reaching
t_stop), every value 1e300 or NaN, the time axis squeezed (halved except the last point), the
vectors renamed.  Route 2, a user's executor whose futures return garbage: NaN or 1e300
arrays, arrays of the wrong shape, a string, None.  Route 3, an entry already in the store
(written before these checks existed) whose values are 1e300.

Every route: one NgspiceError line, nothing stored; then the same call with the real ngspice
on the same store returns exactly what a clean run returns (no later call sees the poison).
"""
from __future__ import annotations

import concurrent.futures as cf
import os
import re

import numpy as np
import pytest

import analogue
import wrapped_ngspice
from analogue.circuit import ngspice as ng
from analogue.circuit.store import RunStore
from conftest import STICK_A02

pytestmark = pytest.mark.requires_ngspice

KW = {"v0": 0.4, "t_end": 1.0, "replicas": 2, "seed": 7, "replicas_per_deck": 1,
      "progress": False, "workers": 1}


@pytest.fixture(scope="module")
def reference():
    return analogue.simulate(STICK_A02, store=False, **KW)


def _same(a, b) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def _clean_rerun_gives(root, ref):
    ens = analogue.simulate(STICK_A02, store=root, **KW)
    assert ens.meta["ran"] == 2 and ens.meta["from_store"] == 0
    assert _same(ens.v, ref.v) and _same(ens.x, ref.x)
    again = analogue.simulate(STICK_A02, store=root, **KW)
    assert again.meta["from_store"] == 2 and _same(again.v, ref.v)


@pytest.mark.parametrize("mode", ["thin", "huge", "nan", "squeeze", "rename"])
def test_a_damaged_ngspice_result_is_refused_and_never_stored(mode, tmp_path, monkeypatch,
                                                               reference):
    path = os.environ["PATH"]
    bindir = tmp_path / "bin"
    wrapped_ngspice.install(bindir, mode)
    monkeypatch.setenv("PATH", f"{bindir}{os.pathsep}{path}")
    root = tmp_path / "store"
    with pytest.raises(ng.NgspiceError) as err:
        analogue.simulate(STICK_A02, store=root, **KW)
    msg = str(err.value)
    assert "\n" not in msg and "Traceback" not in msg
    assert RunStore(root).keys() == []
    monkeypatch.setenv("PATH", path)
    _clean_rerun_gives(root, reference)


def test_a_thinned_time_axis_is_named(tmp_path, monkeypatch):
    bindir = tmp_path / "bin"
    wrapped_ngspice.install(bindir, "thin")
    monkeypatch.setenv("PATH", f"{bindir}{os.pathsep}{os.environ['PATH']}")
    with pytest.raises(ng.NgspiceError, match="max step"):
        analogue.simulate(STICK_A02, store=False, **KW)


def test_renamed_vectors_are_named(tmp_path, monkeypatch):
    bindir = tmp_path / "bin"
    wrapped_ngspice.install(bindir, "rename")
    monkeypatch.setenv("PATH", f"{bindir}{os.pathsep}{os.environ['PATH']}")
    with pytest.raises(ng.NgspiceError, match=r"v\(v0\)"):
        analogue.simulate(STICK_A02, store=False, **KW)


# ------------------------------------------------------------------ a garbage executor
class Garbage(cf.Executor):
    """Runs nothing; every future returns ``make(task)``."""

    def __init__(self, make):
        self.make = make

    def submit(self, fn, /, *args, **kwargs):
        fut: cf.Future = cf.Future()
        fut.set_result(self.make(args[0]))
        return fut


def _arrays(task, value=0.0, shape=None):
    r, n = task.v0.shape[0], task.times.size
    shp = shape or (r, n)
    out = {"v": np.full(shp, value), "x": np.full(shp, value), "info": {"wall_time": 0.0,
           "ngspice_version": analogue.circuit.ngspice.ngspice_version()}}
    if task.noise_names:
        out["noise"] = np.full((r, int(round(task.times[-1] / task.noise_dt))), value)
    return out


GARBAGE = {
    "nan": lambda t: _arrays(t, np.nan),
    "huge": lambda t: _arrays(t, 1e300),
    "wrong-shape": lambda t: _arrays(t, 0.0, shape=(1, 3)),
    "string": lambda t: "hello",
    "none": lambda t: None,
    "missing-x": lambda t: {k: v for k, v in _arrays(t).items() if k != "x"},
    "integers": lambda t: {**_arrays(t), "v": np.zeros((t.v0.shape[0], t.times.size), int)},
}


@pytest.mark.parametrize("case", sorted(GARBAGE))
def test_garbage_from_an_executor_is_refused_and_never_stored(case, tmp_path, reference):
    root = tmp_path / "store"
    with pytest.raises(ng.NgspiceError) as err:
        analogue.simulate(STICK_A02, store=root, executor=Garbage(GARBAGE[case]), **KW)
    msg = str(err.value)
    assert "\n" not in msg and re.match(r"deck [01]: what the executor Garbage returned", msg)
    assert RunStore(root).keys() == []
    _clean_rerun_gives(root, reference)


# ------------------------------------------------------------- an entry already poisoned
def test_a_poisoned_entry_already_in_the_store_is_never_returned(tmp_path, reference):
    root = tmp_path / "store"
    analogue.simulate(STICK_A02, store=root, **KW)
    st = RunStore(root)
    for key in st.keys():
        arrays, meta = st.get(key)
        arrays["v"] = np.full_like(arrays["v"], 1e300)
        st.put(key, arrays, meta)
    ens = analogue.simulate(STICK_A02, store=root, **KW)
    assert ens.meta["ran"] == 2 and _same(ens.v, reference.v)
    assert len(RunStore(root).quarantined()) == 2


# --------------------------------------------- the routes that run decks without simulate()
def test_the_reports_noise_free_run_refuses_huge_values(tmp_path, monkeypatch):
    """Paper Fig. 1's noise-free run (study.runs._noise_free_run) goes through run_decks
    directly: it gets the same physical limits."""
    from analogue.circuit.experiments import load_experiment
    from analogue import Runner
    from analogue.study.runs import _noise_free_run
    exp = load_experiment("stick")
    bindir = tmp_path / "bin"
    wrapped_ngspice.install(bindir, "huge")
    monkeypatch.setenv("PATH", f"{bindir}{os.pathsep}{os.environ['PATH']}")
    root = tmp_path / "store"
    with pytest.raises(ng.NgspiceError, match="physically reach"):
        _noise_free_run(exp, 1, Runner(store=root, workers=1, progress=False))
    assert RunStore(root).keys() == []


def test_a_board_run_refuses_values_beyond_its_rails(tmp_path, monkeypatch):
    from analogue import Model
    from analogue.board.design import design_board
    from analogue.board.netlist import nominal_instance
    from analogue.board.runner import run_board
    design = design_board(Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0), v0=[2.0, -2.0])
    bindir = tmp_path / "bin"
    wrapped_ngspice.install(bindir, "huge")
    monkeypatch.setenv("PATH", f"{bindir}{os.pathsep}{os.environ['PATH']}")
    root = tmp_path / "store"
    with pytest.raises(ng.NgspiceError, match="physically reach"):
        run_board(design, nominal_instance(design), v0=[0.0], t_end=0.5, sample_dt=0.01,
                  seed=1, store=root, workers=1)
    assert RunStore(root).keys() == []
