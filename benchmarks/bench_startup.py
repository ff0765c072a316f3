"""Start-up time of `import analogue` and `analogue --help`, as ratios to `import numpy`
measured side by side in the same run (issue 22, item 3: goals <= 2x and <= 3x).

    python benchmarks/bench_startup.py [--repeats 15]

Each command runs in a fresh interpreter, interleaved (numpy, analogue, help, numpy, ...) so
that machine load affects all three alike; the medians and their ratios are printed.
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
COMMANDS = {
    "import numpy": [sys.executable, "-c", "import numpy"],
    "import analogue": [sys.executable, "-c", "import analogue"],
    "analogue --help": [sys.executable, "-c",
                        "import sys; from analogue.cli import main; sys.argv=['analogue','--help']; main()"],
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=15)
    args = ap.parse_args()
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    times: dict[str, list[float]] = {k: [] for k in COMMANDS}
    for _ in range(args.repeats):
        for name, cmd in COMMANDS.items():
            t0 = time.perf_counter()
            subprocess.run(cmd, env=env, stdout=subprocess.DEVNULL, check=True)
            times[name].append(time.perf_counter() - t0)
    base = statistics.median(times["import numpy"])
    print(f"{'command':<18} {'median s':>9} {'min s':>7} {'ratio to numpy':>15}")
    for name, ts in times.items():
        med = statistics.median(ts)
        print(f"{name:<18} {med:9.3f} {min(ts):7.3f} {med / base:15.2f}")
    print(f"(load average at the end: {os.getloadavg()[0]:.1f}; {args.repeats} repeats each)")


if __name__ == "__main__":
    main()
