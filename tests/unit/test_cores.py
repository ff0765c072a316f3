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
