"""How many CPUs this process may use: the default worker count of every local run (issue 22).

``os.cpu_count()`` counts the machine's CPUs, not the ones the process is given: under
``taskset -c 0,1`` on a 16-core machine it says 16 and a job would start 16 ngspice processes
on 2 cores.  :func:`usable_cpus` takes the smallest of

* the CPU affinity mask (``os.sched_getaffinity``; ``taskset``, ``numactl``, batch schedulers),
* the cgroup CPU quota where one is set (``cpu.max`` of cgroup v2, ``cpu.cfs_quota_us`` /
  ``cpu.cfs_period_us`` of cgroup v1; containers started with ``--cpus``), rounded up,
* ``os.cpu_count()``,

and is at least 1.

Processes that run beside ngspice workers (a Dask worker running decks, the report's
Monte Carlo chunk processes) keep OpenMP/BLAS to one thread each (:data:`ONE_THREAD_ENV`,
:func:`limit_worker_threads`): a numpy BLAS call would otherwise start one thread per core
next to the ``workers`` ngspice processes that already fill them.  ngspice itself is linked
against libgomp (Debian/Ubuntu builds); its children get the same variables (measured: the
project's decks start one thread either way, so this only guards models that use OpenMP).
"""
from __future__ import annotations

import math
import os
from pathlib import Path

__all__ = ["ONE_THREAD_ENV", "cgroup_cpu_limit", "limit_worker_threads", "one_thread_env",
           "usable_cpus"]

#: OpenMP, OpenBLAS and MKL thread pools capped at one thread (read when a library starts)
ONE_THREAD_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}

_CGROUP_ROOT = Path("/sys/fs/cgroup")


def _read(path: Path) -> str | None:
    try:
        return path.read_text(encoding="ascii").strip()
    except (OSError, UnicodeDecodeError):
        return None


def _own_cgroup_dirs(root: Path) -> list[Path]:
    """The cgroup directories of this process (v2 unified path and v1 cpu controller), then the
    root itself (inside a container the process's cgroup is usually mounted at the root)."""
    dirs: list[Path] = []
    text = _read(Path("/proc/self/cgroup")) or ""
    for line in text.splitlines():
        parts = line.split(":", 2)
        if len(parts) != 3:
            continue
        _, controllers, rel = parts
        rel = rel.lstrip("/")
        if controllers == "":                      # cgroup v2
            dirs.append(root / rel)
        elif "cpu" in controllers.split(","):      # cgroup v1
            for mount in ("cpu,cpuacct", "cpu", "cpuacct,cpu"):
                dirs.append(root / mount / rel)
                dirs.append(root / mount)
    dirs.append(root)
    return dirs


def cgroup_cpu_limit(root: Path = _CGROUP_ROOT) -> float | None:
    """The cgroup CPU quota in CPUs (``quota / period``), or ``None`` where none is set."""
    for d in _own_cgroup_dirs(root):
        v2 = _read(d / "cpu.max")
        if v2 is not None:
            fields = v2.split()
            if len(fields) == 2 and fields[0] != "max":
                try:
                    quota, period = float(fields[0]), float(fields[1])
                except ValueError:
                    continue
                if quota > 0 and period > 0:
                    return quota / period
            continue
        quota_text = _read(d / "cpu.cfs_quota_us")
        period_text = _read(d / "cpu.cfs_period_us")
        if quota_text is not None and period_text is not None:
            try:
                quota, period = float(quota_text), float(period_text)
            except ValueError:
                continue
            if quota > 0 and period > 0:
                return quota / period
    return None


def usable_cpus() -> int:
    """CPUs this process may run on: affinity mask, cgroup quota and ``os.cpu_count()``, the
    smallest of them, at least 1."""
    counts = [os.cpu_count() or 1]
    getaffinity = getattr(os, "sched_getaffinity", None)
    if getaffinity is not None:
        try:
            counts.append(len(getaffinity(0)))
        except OSError:
            pass
    quota = cgroup_cpu_limit()
    if quota is not None:
        counts.append(math.ceil(quota))
    return max(1, min(counts))


def one_thread_env(env=None) -> dict:
    """``env`` (default: this process's environment) with :data:`ONE_THREAD_ENV` set: the
    environment of a child process that runs beside other workers (ngspice)."""
    return {**(os.environ if env is None else env), **ONE_THREAD_ENV}


def limit_worker_threads() -> None:
    """Initialiser of a worker process that runs beside ngspice workers: OpenMP/BLAS limited
    to one thread, for the libraries already loaded (threadpoolctl, process-wide and kept)
    and, through the environment, for those loaded later and for the process's children."""
    os.environ.update(ONE_THREAD_ENV)
    from threadpoolctl import threadpool_limits
    threadpool_limits(limits=1)
