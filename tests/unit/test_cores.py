"""The default worker count follows the CPUs the process is given (issue 22, item 2)."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from analogue import cores

needs_affinity = pytest.mark.skipif(not hasattr(os, "sched_setaffinity"),
                                    reason="os.sched_setaffinity is Linux-only")


@needs_affinity
def test_child_pinned_to_one_core_counts_one():
    """A child process pinned to one core (as ``taskset -c 0`` would) sees one usable CPU, and
    the report's default worker count is that number, whatever ``os.cpu_count()`` says."""
    one = sorted(os.sched_getaffinity(0))[0]
    code = (
        "import os, sys\n"
        f"os.sched_setaffinity(0, {{{one}}})\n"
        "from analogue import cores\n"
        "from analogue.report import runs\n"
        "print(cores.usable_cpus(), runs.default_workers(), os.cpu_count())\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env={**os.environ, "PYTHONPATH": str(Path(__file__)
                                                                           .parents[2])})
    usable, default, _machine = (int(x) for x in out.stdout.split())
    assert usable == 1
    assert default == 1


@needs_affinity
def test_usable_cpus_never_exceeds_affinity():
    assert 1 <= cores.usable_cpus() <= len(os.sched_getaffinity(0))


def _fake_cgroup(tmp_path: Path, cpu_max: str) -> Path:
    (tmp_path / "cpu.max").write_text(cpu_max + "\n", encoding="ascii")
    return tmp_path


def test_cgroup_v2_quota_in_cpus(tmp_path, monkeypatch):
    monkeypatch.setattr(cores, "_own_cgroup_dirs", lambda root: [root])
    assert cores.cgroup_cpu_limit(_fake_cgroup(tmp_path, "150000 100000")) == pytest.approx(1.5)


def test_cgroup_v2_without_quota(tmp_path, monkeypatch):
    monkeypatch.setattr(cores, "_own_cgroup_dirs", lambda root: [root])
    assert cores.cgroup_cpu_limit(_fake_cgroup(tmp_path, "max 100000")) is None


def test_cgroup_v1_quota(tmp_path, monkeypatch):
    monkeypatch.setattr(cores, "_own_cgroup_dirs", lambda root: [root])
    (tmp_path / "cpu.cfs_quota_us").write_text("-1\n", encoding="ascii")
    (tmp_path / "cpu.cfs_period_us").write_text("100000\n", encoding="ascii")
    assert cores.cgroup_cpu_limit(tmp_path) is None
    (tmp_path / "cpu.cfs_quota_us").write_text("300000\n", encoding="ascii")
    assert cores.cgroup_cpu_limit(tmp_path) == pytest.approx(3.0)


def test_quota_rounds_up_and_caps(monkeypatch):
    monkeypatch.setattr(cores, "cgroup_cpu_limit", lambda root=None: 1.2)
    assert cores.usable_cpus() == min(2, len(os.sched_getaffinity(0))
                                      if hasattr(os, "sched_getaffinity") else 2)


def test_worker_initialiser_leaves_one_blas_thread():
    """A worker process started with :func:`analogue.cores.limit_worker_threads` as its
    initialiser (as the report's Monte Carlo chunk processes are) runs numpy's BLAS on one
    thread and hands ``OMP/OPENBLAS/MKL_NUM_THREADS=1`` to its children, whatever the parent's
    environment says."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    import numpy as np
    from threadpoolctl import threadpool_info

    names = sorted(cores.ONE_THREAD_ENV)
    ctx = multiprocessing.get_context("spawn")
    saved = {k: os.environ.pop(k, None) for k in names}
    try:
        with ProcessPoolExecutor(1, mp_context=ctx,
                                 initializer=cores.limit_worker_threads) as ex:
            ex.submit(np.zeros, 1).result()          # numpy (and its BLAS) loaded there
            info = ex.submit(threadpool_info).result()
            env = [ex.submit(os.getenv, k).result() for k in names]
    finally:
        for k, v in saved.items():
            if v is not None:
                os.environ[k] = v
    blas = [i for i in info if i.get("user_api") == "blas"]
    assert blas, info
    assert all(i["num_threads"] == 1 for i in info), info
    assert env == ["1"] * len(names)


def test_ngspice_children_get_one_thread_env(tmp_path):
    """ngspice (linked against libgomp) is started with OpenMP/BLAS capped at one thread."""
    from analogue.circuit import ngspice as ng
    proc = ng._spawn(["sh", "-c", "echo $OMP_NUM_THREADS,$OPENBLAS_NUM_THREADS,$MKL_NUM_THREADS"],
                     tmp_path, subprocess.PIPE, subprocess.DEVNULL)
    out, _ = proc.communicate(timeout=30)
    assert out.decode().strip() == "1,1,1"


def test_dask_worker_limits_its_threads_once(monkeypatch):
    """run_batch on a Dask worker process limits that process's threads (once); outside a
    worker (local runs: threads of the caller's process) it leaves them alone."""
    import types

    from analogue.circuit import decks as sim   # run_batch's module (simulate re-exports it)
    calls = []
    monkeypatch.setattr(sim, "limit_worker_threads", lambda: calls.append(1))
    monkeypatch.setattr(sim, "_WORKER_LIMITED", False)

    def not_a_worker():
        raise ValueError("No worker found")
    monkeypatch.setitem(sys.modules, "distributed", types.SimpleNamespace(get_worker=not_a_worker))
    sim._limit_dask_worker_threads()
    assert calls == []
    monkeypatch.setitem(sys.modules, "distributed", types.SimpleNamespace(get_worker=object))
    sim._limit_dask_worker_threads()
    sim._limit_dask_worker_threads()
    assert calls == [1]
