"""The paper job on an empty store (issue 10, item 5): wall time, CPU seconds (this process's
children: the ``analogue paper`` process and its ngspice processes) and the phase breakdown
from ``metrics.json`` provenance.

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


def run_paper(code: Path, full: bool, store: Path | None = None) -> dict:
    """One ``analogue paper`` run of the checkout ``code`` on an empty store; returns wall,
    CPU and the metrics.json phase breakdown."""
    exe = Path(sys.executable).with_name("analogue")
    with tempfile.TemporaryDirectory(prefix="bench-paper-") as tmp:
        st = store if store is not None else Path(tmp) / "store"
        out = Path(tmp) / "report"
        env = dict(os.environ, PYTHONPATH=str(code), ANALOGUE_STORE=str(st),
                   ANALOGUE_THEORY_CACHE=str(st / "theory"))
        cmd = [str(exe), "paper", "--out", str(out), "--no-progress"] + ([] if full else ["--quick"])
        u0, s0 = _children_cpu()
        load0 = os.getloadavg()[0]
        t0 = time.perf_counter()
        res = subprocess.run(cmd, env=env, cwd=tmp, capture_output=True, text=True, check=False)
        wall = time.perf_counter() - t0
        u1, s1 = _children_cpu()
        load1 = os.getloadavg()[0]
        if res.returncode != 0:
            tail = "\n".join(res.stderr.splitlines()[-15:])
            raise SystemExit(f"analogue paper failed ({res.returncode}):\n{tail}")
        metrics = json.loads((out / "metrics.json").read_text())
        if store is not None:
            shutil.copy(out / "metrics.json", store / "metrics.json")
    prov = metrics["provenance"]
    by_thread: dict = {}
    for p in prov["phases"]:
        key = (p["phase"], p.get("thread", "main"))
        by_thread[key] = by_thread.get(key, 0.0) + p["seconds"]
    return {"code": str(code), "wall_s": wall, "user_s": u1 - u0, "sys_s": s1 - s0,
            "load_1min": (load0, load1), "report_wall_s": prov["wall_time_s"],
            "phases": by_thread, "summary": metrics["summary"]}


def _print(r: dict) -> None:
    cpu = r["user_s"] + r["sys_s"]
    print(f"\n## {r['code']}")
    print(f"wall {r['wall_s']:.1f} s (report {r['report_wall_s']:.1f} s), CPU {cpu:.1f} s "
          f"(user {r['user_s']:.1f} + sys {r['sys_s']:.1f}; {cpu / r['wall_s']:.2f} cores), "
          f"load average (1 min) {r['load_1min'][0]:.2f} -> {r['load_1min'][1]:.2f}; "
          f"{r['summary']['comparisons']} comparisons, {r['summary']['within_budget']} within "
          f"budget, {r['summary']['failed_sections']} failed sections")
    print("| phase | thread | seconds (sum over experiments) |")
    print("|---|---|---|")
    for (phase, thread), sec in sorted(r["phases"].items(), key=lambda kv: -kv[1]):
        print(f"| {phase} | {thread} | {sec:.1f} |")


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
