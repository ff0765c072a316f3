"""plots.style.save (layout computed once, shared renderer and mathtext parser, ticks only in
view) writes the same pixels as matplotlib's own constrained-layout savefig."""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.image import imread

from analogue.plots.style import DPI, new_figure, save


def _draw(axes, seed: int) -> None:
    """Log and linear axes, mathtext in titles, legends and tick labels, a suptitle."""
    rng = np.random.default_rng(seed)
    v = np.linspace(-2, 3, 400)
    for j, ax in enumerate(axes[0]):
        f = np.exp(-(v - j) ** 2 / (0.3 + seed)) + 1e-5
        ax.plot(v, f, label=f"$\\tau_m$={j + seed}")
        ax.step(v[::10], f[::10] * rng.uniform(0.8, 1.2, f[::10].size), where="mid")
        ax.set_title(f"t = {j + 1}, $\\gamma$ = {10 * (seed + 1)}", fontsize=10)
        ax.set_ylabel("f(v, t | v0)")
        ax.legend(fontsize=7)
        log = axes[1, j]
        log.plot(v, f)
        log.set_yscale("log")
        log.set_ylim(f.max() * 1e-4, f.max() * 3)
        log.set_xlabel("velocity v (model units)")
    axes[0, 0].figure.suptitle(f"$v_0$ = {seed}: a suptitle", fontsize=10)


def _reference(tmp_path, seed: int):
    """What matplotlib draws with the engine left on (a pre-draw, then the draw)."""
    fig = Figure(figsize=(8.0, 6.4), layout="constrained")
    _draw(fig.subplots(2, 2, squeeze=False), seed)
    fig.savefig(tmp_path / f"ref{seed}.png", dpi=DPI)
    return imread(tmp_path / f"ref{seed}.png")


def test_save_matches_constrained_savefig(tmp_path):
    for seed in (0, 1):     # the second figure reuses the first one's renderer and parser
        fig, axes = new_figure(2, 2, width=4.0, height=3.2, squeeze=False)
        _draw(axes, seed)
        got = imread(save(fig, tmp_path / f"new{seed}.png"))
        ref = _reference(tmp_path, seed)
        assert got.shape == ref.shape
        assert np.array_equal(got, ref), f"seed {seed}: {np.mean(got != ref):.2%} differ"
        assert fig.get_layout_engine() is None     # saved with the layout frozen


def test_save_keeps_every_visible_tick(tmp_path):
    fig, axes = new_figure(1, 1, squeeze=False)
    ax = axes[0, 0]
    ax.plot([1e-3, 10.0], [0.0, 1.0])
    ax.set_xscale("log")
    ax.set_xlim(2e-3, 5.0)
    save(fig, tmp_path / "a.png")
    lo, hi = ax.get_xlim()
    major = ax.xaxis.get_majorticklocs()
    minor = ax.xaxis.get_minorticklocs()
    # every decade and every 2..9 multiple inside the view, and nothing outside it
    assert list(major) == [1e-2, 1e-1, 1.0]
    expected = [m * 10.0 ** e for e in range(-3, 1) for m in range(2, 10)
                if lo <= m * 10.0 ** e <= hi]
    np.testing.assert_allclose(minor, expected, rtol=1e-12)
