"""Run store: cost of the verified read (checksum, bounded parser, finiteness) against a plain
``np.load`` of the same entry, and of the atomic write, for entry sizes the runner produces.

    .venv/bin/python benchmarks/bench_store.py [--repeat 20]
"""
from __future__ import annotations

import argparse
import tempfile
import time

import numpy as np

from analogue.circuit.store import RunStore, batch_key

SIZES = [(16, 801), (16, 10001), (64, 10001)]  # (replicas per deck, time points)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=20)
    n_rep = ap.parse_args().repeat
    rng = np.random.default_rng(0)
    print("| replicas x points | entry [MB] | put [ms] | verified get [ms] | np.load [ms] | ratio |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        st = RunStore(tmp)
        for r, n in SIZES:
            key = batch_key(f"bench {r} {n}\n.end\n", [0.0], "bench")
            arrays = {"v": rng.random((r, n)), "x": rng.random((r, n)),
                      "noise": rng.random((r, n - 1)), "t": np.arange(n) * 0.01}
            t0 = time.perf_counter()
            for _ in range(n_rep):
                st.put(key, arrays, {"deck_text": "x" * 3000})
            put = (time.perf_counter() - t0) / n_rep
            t0 = time.perf_counter()
            for _ in range(n_rep):
                assert st.get(key) is not None
            get = (time.perf_counter() - t0) / n_rep
            t0 = time.perf_counter()
            for _ in range(n_rep):
                with np.load(st.path(key)) as f:
                    {k: np.array(f[k]) for k in f.files}
            plain = (time.perf_counter() - t0) / n_rep
            size = st.path(key).stat().st_size / 1e6
            print(f"| {r} x {n} | {size:.2f} | {put * 1e3:.1f} | {get * 1e3:.1f} | "
                  f"{plain * 1e3:.1f} | {get / plain:.1f} |")


if __name__ == "__main__":
    main()
