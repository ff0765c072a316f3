"""The paper job on an empty store (issue 10, item 5): wall time, CPU seconds (this process's
children: the ``analogue paper`` process and its ngspice processes), the phase breakdown
from ``metrics.json`` provenance, and the critical path (issue 22, item 1: the job's wall
time with unlimited cores, its longest chain of dependent phases) as a ratio to the wall
time of the same run.

    .venv/bin/python benchmarks/bench_paper.py            # quick paper
    .venv/bin/python benchmarks/bench_paper.py --full     # the full paper
    .venv/bin/python benchmarks/bench_paper.py --code /path/to/other/checkout   # compare

Each run gets a fresh temporary run store and theory cache (``ANALOGUE_STORE``,
``ANALOGUE_THEORY_CACHE``), so nothing is reused.  ``--code`` may be given several times to
time several checkouts one after the other in one invocation (old and new side by side on a
shared machine); ``--store`` keeps the store of the last run for a reuse check.  The load
average (1 min) before and after each run is printed: on a shared machine a wall time means
little without it.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _children_cpu() -> tuple[float, float]:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime, r.ru_stime


_TICK = os.sysconf("SC_CLK_TCK")


def _proc_stat(path: str) -> list[str] | None:
    """Fields of a /proc stat file after the command name (state first), or None if gone."""
    try:
        with open(path) as f:
            text = f.read()
    except OSError:
        return None
    return text[text.rindex(")") + 2:].split()


def _sample_tree(root: int) -> tuple[float, int, float]:
    """(CPU seconds of ``root`` and its descendants, reaped children included; how many of
    their threads are runnable now; CPU seconds of ``root`` itself, i.e. the Python process
    without its ngspice children)."""
    kids: dict = {}
    for d in os.listdir("/proc"):
        if d.isdigit():
            st = _proc_stat(f"/proc/{d}/stat")
            if st is not None:
                kids.setdefault(int(st[1]), []).append(int(d))
    pids, todo = [], [root]
    while todo:
        p = todo.pop()
        pids.append(p)
        todo.extend(kids.get(p, []))
    cpu, running, own = 0.0, 0, 0.0
    for p in pids:
        st = _proc_stat(f"/proc/{p}/stat")
        if st is None:
            continue
        cpu += sum(int(x) for x in st[11:15]) / _TICK      # utime stime cutime cstime
        if p == root:
            own = sum(int(x) for x in st[11:13]) / _TICK
        try:
            tasks = os.listdir(f"/proc/{p}/task")
        except OSError:
            continue
        for t in tasks:
            ts = _proc_stat(f"/proc/{p}/task/{t}/stat")
            running += ts is not None and ts[0] == "R"
    return cpu, running, own


class _Sampler:
    """Samples the job's process tree every ``every`` s: its CPU seconds and how many of its
    threads are runnable.  On a shared machine the wall time says little; the runnable count
    is the job's own demand, so ``sum(dCPU / clip(runnable, 1, cores))`` over the samples
    estimates the wall time of the same schedule on an idle machine with ``cores`` cores
    (the samples are instants: a rough estimate, good for comparing schedules)."""

    def __init__(self, pid: int, every: float = 0.5):
        import threading
        self.pid, self.every = pid, every
        self.samples: list[tuple[float, float, int, float]] = []
        self.t0 = time.perf_counter()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(self.every):
            cpu, running, own = _sample_tree(self.pid)
            self.samples.append((time.perf_counter() - self.t0, cpu, running, own))

    def stop(self) -> None:
        self._stop.set()
        self._thread.join()

    def summary(self, until: float | None, cores: int | None = None) -> dict:
        """CPU seconds and idle-machine wall estimate up to ``until`` s after the start, on
        ``cores`` cores (default: the cores this process may use)."""
        cores = cores or len(os.sched_getaffinity(0))
        cpu_prev, est, cpu, busy, python = 0.0, 0.0, 0.0, [], 0.0
        t_prev = 0.0
        for t, c, r, own in self.samples:
            if until is not None and t > until:
                break
            dc = max(0.0, c - cpu_prev)
            est += dc / min(max(r, 1), cores)
            cpu, cpu_prev, t_prev, python = c, c, t, own
            busy.append(min(r, cores))
        return {"cpu_s": cpu, "python_cpu_s": python, "idle_estimate_s": est, "until_s": t_prev,
                "cores": cores,
                "mean_runnable": sum(busy) / len(busy) if busy else 0.0}


def _python_path(code: Path) -> str:
    """``code`` first on PYTHONPATH, the caller's entries after it (a machine whose
    dependencies sit on PYTHONPATH, e.g. the devicekit's wheels, keeps them)."""
    rest = os.environ.get("PYTHONPATH", "")
    return str(code) + (os.pathsep + rest if rest else "")


def _analogue_command() -> list[str]:
    """The ``analogue`` console script beside this interpreter (a venv), else the one on PATH
    (a machine where the package is on PYTHONPATH with a launcher, e.g. the devicekit)."""
    exe = Path(sys.executable).with_name("analogue")
    if exe.exists():
        return [str(exe)]
    found = shutil.which("analogue")
    if found is None:
        raise SystemExit("no 'analogue' command beside this Python or on PATH")
    return [found]


def run_paper(code: Path, full: bool, store: Path | None = None, extra: tuple = (),
              save: Path | None = None) -> dict:
    """One ``analogue paper`` run of the checkout ``code`` on an empty store; returns wall,
    CPU and the metrics.json phase breakdown.  ``extra``: more arguments of ``analogue
    paper`` (e.g. ``("--sweeps",)``); ``save``: copy the run's metrics.json there."""
    with tempfile.TemporaryDirectory(prefix="bench-paper-") as tmp:
        st = store if store is not None else Path(tmp) / "store"
        out = Path(tmp) / "report"
        env = dict(os.environ, PYTHONPATH=_python_path(code), ANALOGUE_STORE=str(st),
                   ANALOGUE_THEORY_CACHE=str(st / "theory"))
        cmd = (_analogue_command() + ["paper", "--out", str(out), "--no-progress"]
               + ([] if full else ["--quick"]) + list(extra))
        u0, s0 = _children_cpu()
        load0 = os.getloadavg()[0]
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, env=env, cwd=tmp, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
        sampler = _Sampler(proc.pid)
        stdout, stderr = proc.communicate()
        sampler.stop()
        res = subprocess.CompletedProcess(cmd, proc.returncode, stdout, stderr)
        wall = time.perf_counter() - t0
        u1, s1 = _children_cpu()
        load1 = os.getloadavg()[0]
        if res.returncode != 0:
            tail = "\n".join(res.stderr.splitlines()[-15:])
            raise SystemExit(f"analogue paper failed ({res.returncode}):\n{tail}")
        metrics = json.loads((out / "metrics.json").read_text())
        if store is not None:
            shutil.copy(out / "metrics.json", store / "metrics.json")
        if save is not None:
            save.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(out / "metrics.json", save)
    prov = metrics["provenance"]
    # the report's clock starts after the imports: its times are shifted by the difference
    shift = wall - prov["wall_time_s"]
    paper_at = prov.get("paper_wall_time_s")
    sampled = {"job": sampler.summary(None),
               "paper": sampler.summary(paper_at + shift) if paper_at is not None else None}
    by_thread: dict = {}
    for p in prov["phases"]:
        key = (p["phase"], p.get("thread", "main"))
        by_thread[key] = by_thread.get(key, 0.0) + p["seconds"]
    return {"code": str(code), "args": " ".join(cmd[1:]), "wall_s": wall, "user_s": u1 - u0, "sys_s": s1 - s0,
            "load_1min": (load0, load1), "report_wall_s": prov["wall_time_s"],
            "paper_wall_s": prov.get("paper_wall_time_s"),
            "beyond_wall_s": prov.get("beyond_wall_time_s"),
            "critical_path_s": prov.get("critical_path_s"),
            "critical_path": prov.get("critical_path"),
            "phases": by_thread, "timeline": prov["phases"], "summary": metrics["summary"],
            "sampled": sampled}


def _print(r: dict) -> None:
    cpu = r["user_s"] + r["sys_s"]
    print(f"\n## {r['code']}: analogue {r.get('args', 'paper')}")
    paper = (f", paper's chapters complete at {r['paper_wall_s']:.1f} s"
             if r.get("paper_wall_s") is not None else "")
    print(f"wall {r['wall_s']:.1f} s (report {r['report_wall_s']:.1f} s{paper}), CPU {cpu:.1f} s "
          f"(user {r['user_s']:.1f} + sys {r['sys_s']:.1f}; {cpu / r['wall_s']:.2f} cores), "
          f"load average (1 min) {r['load_1min'][0]:.2f} -> {r['load_1min'][1]:.2f}; "
          f"{r['summary']['comparisons']} comparisons, {r['summary']['within_budget']} within "
          f"budget, {r['summary']['failed_sections']} failed sections")
    if r.get("critical_path_s") is not None:
        # the job with unlimited cores (analogue.study.critical_path: circuit runs as their
        # calibrations plus longest deck), against the same run's wall time
        cp = r["critical_path_s"]
        print(f"critical path (unlimited cores) {cp:.1f} s; report wall {r['report_wall_s']:.1f} s"
              f" (ratio critical path / wall {cp / r['report_wall_s']:.2f}), process wall "
              f"{r['wall_s']:.1f} s (ratio {cp / r['wall_s']:.2f}; the imports are before the "
              f"report's clock)")
        print("chain: " + " -> ".join(
            c["phase"] + (f" ({c['experiment']})" if c["experiment"] else "")
            + f" {c['seconds']:.1f} s" for c in r["critical_path"]))
    for what, smp in r["sampled"].items():
        if smp is not None:
            print(f"sampled ({what}, to {smp['until_s']:.1f} s): CPU {smp['cpu_s']:.1f} s "
                  f"(Python process {smp['python_cpu_s']:.1f}, children: ngspice and "
                  f"theory processes {smp['cpu_s'] - smp['python_cpu_s']:.1f}), "
                  f"mean runnable threads (clipped at {smp['cores']}) "
                  f"{smp['mean_runnable']:.2f}, idle {smp['cores']}-core wall estimate "
                  f"{smp['idle_estimate_s']:.1f} s")
    print("| phase | thread | seconds (sum over experiments) |")
    print("|---|---|---|")
    for (phase, thread), sec in sorted(r["phases"].items(), key=lambda kv: -kv[1]):
        print(f"| {phase} | {thread} | {sec:.1f} |")
    print("timeline (start, end, thread, phase, experiment):")
    for p in sorted(r["timeline"], key=lambda p: p["start_s"]):
        if p["seconds"] >= 0.5:
            print(f"  {p['start_s']:6.1f} {p['start_s'] + p['seconds']:6.1f}  "
                  f"{p.get('thread', 'main'):8s} {p['phase']} ({p['experiment'] or ''})")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--full", action="store_true", help="the full paper (default: --quick)")
    ap.add_argument("--code", type=Path, action="append",
                    help="checkout(s) to time (default: this one); repeat to compare")
    ap.add_argument("--store", type=Path, default=None,
                    help="keep the run store of the (last) run here instead of a temporary one")
    ap.add_argument("--json", type=Path, default=None, help="also write the results here")
    args = ap.parse_args()
    results = []
    for code in args.code or [ROOT]:
        results.append(run_paper(code.resolve(), args.full, args.store))
        _print(results[-1])
    if args.json is not None:
        args.json.write_text(json.dumps(
            [{**r, "phases": [[k[0], k[1], v] for k, v in r["phases"].items()]} for r in results],
            indent=2))


if __name__ == "__main__":
    main()
