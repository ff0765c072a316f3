"""Reproduce the noise-source numbers of docs/error-budget.md ("The noise source, and why D_x
rows lean negative").

    python scripts/noise_source_probe.py source [DECKS REPLICAS HOLDS]   # 16 64 32768: ~1 min
    python scripts/noise_source_probe.py dx [SEEDS]                      # 400: ~1 min

``source``: noise-only decks with the stick deck's own ``Vnoise`` line and
:func:`analogue.circuit.decks.deck_seeds` seeds; the periodogram power below several
frequencies (cycles per hold) relative to the sample variance, pooled over replicas, beside
numpy's generator through the same estimator, and the correlations between replicas and decks.
``dx``: Monte Carlo (numpy noise) at the stick experiment's quick stationary size, 32 replicas
x 40 tau_m: the D_x estimate (``window_diffusion``) against exact theory over many seeds.
"""
from __future__ import annotations

import re
import sys

import numpy as np

from analogue import Model
from analogue.circuit import build_deck, map_model
from analogue.circuit.decks import deck_seeds, held_values
from analogue.circuit.ngspice import run_deck
from analogue.estimators.transport import window_diffusion
from analogue.montecarlo import simulate_sde
from analogue.theory.stationary import diffusion_coefficient

STICK = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)
BANDS = (0.0005, 0.002, 0.01, 0.05)


def low_band(z: np.ndarray, band: float) -> tuple[float, float]:
    """Mean and SE over rows of (periodogram bins 1 .. band n) / sample variance."""
    n = z.shape[1]
    p = np.abs(np.fft.rfft(z, axis=1)[:, 1:max(1, int(band * n)) + 1]) ** 2 / n
    r = p.mean(axis=1) / z.var(axis=1)
    return float(r.mean()), float(r.std(ddof=1) / np.sqrt(len(r)))


def source(decks: int, replicas: int, holds: int) -> None:
    deck = build_deck(map_model(STICK), replicas=1, v0=np.zeros(1), t_end=1.0, seed=1, sample_dt=0.01)
    line = next(s for s in deck.text.splitlines() if s.lower().startswith("vnoise "))
    m = re.search(r"trrandom\(2 (\S+) 0 (\S+) 0\)", line)
    if m is None:
        raise SystemExit(f"unexpected noise source: {line}")
    ts, sigma = float(m.group(1)), float(m.group(2))
    out = []
    for seed in deck_seeds(11, decks):
        text = "\n".join(["noise only", ".subckt rep nz", line, "Rload nz 0 1k", ".ends rep",
                          *(f"Xr{i} nz{i} rep" for i in range(replicas)), f".options seed={seed}",
                          ".save " + " ".join(f"v(nz{i})" for i in range(replicas)),
                          f".tran {ts:.12g} {holds * ts:.12g} 0 {ts:.12g} uic", ".end"]) + "\n"
        res = run_deck(text, t_stop=holds * ts)
        rows = res.plot.columns([f"v(nz{i})" for i in range(replicas)])
        out.append(held_values(res.plot["time"], rows, holds * ts, ts) / sigma)
    z = np.stack(out)
    flat = z.reshape(decks * replicas, holds)
    white = np.random.default_rng(5).standard_normal(flat.shape)
    print(f"{decks} decks x {replicas} replicas x {holds} holds; mean {z.mean():+.2e} "
          f"(z {z.mean() * np.sqrt(z.size):+.2f}), variance {z.var():.5f}")
    for band in BANDS:
        (r, se), (rw, sew) = low_band(flat, band), low_band(white, band)
        print(f"  below {band}/hold: ngspice {r:.4f} +- {se:.4f} (z {(r - 1) / se:+.2f}); "
              f"numpy {rw:.4f} +- {sew:.4f}")
    c = (flat - flat.mean(axis=1, keepdims=True)) / flat.std(axis=1, keepdims=True)
    cc = c @ c.T / np.sqrt(holds)
    iu = np.triu_indices(len(c), 1)
    deck = np.repeat(np.arange(decks), replicas)
    same = deck[iu[0]] == deck[iu[1]]
    for name, sel in (("within decks", same), ("between decks", ~same)):
        if sel.any():
            print(f"  correlation x sqrt(n), {name} ({sel.sum()} pairs): mean square "
                  f"{np.mean(cc[iu][sel] ** 2):.3f}, largest {np.max(np.abs(cc[iu][sel])):.2f}")


def dx(seeds: int) -> None:
    d0 = diffusion_coefficient(STICK)
    est = np.array([(d.diffusion, d.stderr) for d in (
        window_diffusion(simulate_sde(STICK, v0="stationary", t_end=40.0, replicas=32, seed=1000 + s,
                                      dt=1 / 300, sample_dt=0.01), burn_in=2.0) for s in range(seeds))])
    r, z = est[:, 0] / d0, (est[:, 0] - d0) / est[:, 1]
    print(f"D_x / exact over {seeds} seeds: mean {r.mean():.4f} +- {r.std(ddof=1) / np.sqrt(seeds):.4f}, "
          f"median {np.median(r):.3f}, spread {r.std(ddof=1):.3f}; corr(D_x, SE) "
          f"{np.corrcoef(est[:, 0], est[:, 1])[0, 1]:.2f}; z mean {z.mean():+.2f} +- "
          f"{z.std(ddof=1) / np.sqrt(seeds):.2f}, sd {z.std(ddof=1):.2f}, negative {np.mean(z < 0):.2f}")


if __name__ == "__main__":
    args = sys.argv[1:]
    if args[:1] == ["source"]:
        source(*(map(int, args[1:4])) if len(args) == 4 else (16, 64, 32768))
    elif args[:1] == ["dx"]:
        dx(int(args[1]) if len(args) > 1 else 400)
    else:
        raise SystemExit(__doc__)
