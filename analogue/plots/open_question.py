"""Figures for the paper's open question (Section V): is the jump of I(w) at w = 0 real?

Exact rate functions ``I_gamma(w)`` (:func:`analogue.theory.work_statistics.rate_function`) for
gamma = 10, 100, 1000 against the paper's eq. (64) and the weak-noise limit (the convex envelope,
:func:`analogue.theory.work_statistics.weak_noise_limit_rate_function`), and the fluctuation
relation ``I(-w) - I(w)`` (Fig. 9, eqs. (67)/(68)), for the paper's Fig. 8 parameters
(tau_m = m = Delta = 1, a = 0.5) and a sliding case a = 1.5.

The exact curves go through the on-disk theory cache (:mod:`analogue.theory.cache`; a
repeated report costs nothing) and use the graded mesh of
:func:`analogue.theory.work_statistics.scgf`, whose cost does not grow with gamma: measured
under load (2 cores shared, load ~8), per curve of 21 points at gamma = 100 / 9 points at
gamma = 1000: 2.7-5.3 s / 2.6-3.3 s, against 52-99 s / 119-171 s with the uniform grid; the
whole figure (gamma = 10, 100, 1000; 41/21/17 points; a = 0.5 and 1.5): 17 s cold.  Since
the sweep's eigen-solves are seeded shifted inverse iterations
(:func:`analogue.theory.work_statistics._top_eigenpair`), the data of the quick report
(gamma = 10, 100) cost 0.9 CPU s cold and gamma = 1000 adds 0.5 (3.6-4.1 and 2.2-2.5 s
with LAPACK bisection; load 1.6, benchmarks/bench_theory.py sections 8 and 9).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..model import Model
from ..theory import weak_noise
from ..theory import work_statistics as ws
from ..theory.cache import cached_call
from .style import new_figure, save

__all__ = ["draw_open_question", "open_question_data", "GAMMAS", "CASES"]

GAMMAS = (10.0, 100.0, 1000.0)
# (a, half-range of w, number of w points per gamma)
CASES = ((0.5, 1.2), (1.5, 2.0))
# points per curve (the cost per point no longer grows with gamma, see the module docstring)
_POINTS = {10.0: 41, 100.0: 21, 1000.0: 17}
_COLOURS = {10.0: "tab:blue", 100.0: "tab:orange", 1000.0: "tab:green"}


def open_question_data(a: float, half_range: float, gammas=GAMMAS, points=None, cache=None):
    """Symmetric w grids and exact I_gamma(w) for tau_m = m = Delta = 1 and the given a.
    ``cache``: the theory cache (None: default location, False: compute afresh)."""
    out = {}
    for g in gammas:
        n = (points or _POINTS).get(g, 33)
        w = np.linspace(-half_range, half_range, n)
        model = Model(tau_m=1.0, delta=1.0, a=a, gamma=g, mass=1.0)
        w, rate, _ = cached_call(ws.rate_function_curve, model, w, cache=cache)
        out[g] = (w, rate)
    return out


def draw_open_question(outdir, points=None, gammas=GAMMAS, cache=None,
                       data=None) -> list[Path]:
    """Write ``open_question_rate.png`` and ``open_question_fluctuation.png`` into outdir.

    ``gammas``: noise strengths of the exact curves (default 10, 100, 1000; the gamma = 1000
    curve no longer costs more than the others, so a quick report need not drop it).
    ``points``: optional
    {gamma: number of w points}.  ``cache``: see :func:`open_question_data`.  ``data``:
    optional ``{(a, half_range): open_question_data(...)}`` for :data:`CASES`, computed
    beforehand (the report computes it while ngspice runs); the figure then only draws.

    The paper's I(w) is drawn with the report's one convention at w = 0, the Filippov value
    (:func:`analogue.theory.weak_noise.rate_function`), as in Fig. 8.
    """
    outdir = Path(outdir)
    gammas = tuple(float(g) for g in gammas)
    if not gammas or any(not (g > 0 and np.isfinite(g)) for g in gammas):
        raise ValueError(f"gammas must be a non-empty sequence of finite numbers > 0, got {gammas!r}")
    fig_i, axes_i = new_figure(1, len(CASES), width=5.2, height=3.9)
    fig_f, axes_f = new_figure(1, len(CASES), width=5.2, height=3.9)
    for (a, half), ax_i, ax_f in zip(CASES, np.atleast_1d(axes_i), np.atleast_1d(axes_f)):
        model = Model(tau_m=1.0, delta=1.0, a=a, gamma=10.0)
        fine = np.linspace(-half, half, 2001)
        fine = fine[fine != 0]
        pos = fine[fine > 0]
        curves = (data[(a, half)] if data is not None
                  else open_question_data(a, half, gammas=gammas, points=points, cache=cache))
        for g, (w, I) in curves.items():
            ax_i.plot(w, I, "o-", ms=2.5, lw=1, color=_COLOURS.get(g), label=f"exact, gamma = {g:g}")
            # w grids are symmetric: I(-w) is the reversed array.
            m = w > 0
            ax_f.plot(w[m], I[::-1][m] - I[m], "o-", ms=2.5, lw=1, color=_COLOURS.get(g),
                      label=f"exact, gamma = {g:g}")
        paper = np.asarray(weak_noise.rate_function(model, fine))
        lim = ws.weak_noise_limit_rate_function(model, fine)
        ax_i.plot(fine[fine < 0], paper[fine < 0], "k--", lw=1.2, label="paper eq. (64)")
        ax_i.plot(fine[fine > 0], paper[fine > 0], "k--", lw=1.2)
        ax_i.plot(fine, lim, "r-", lw=1.4, alpha=0.8, label="gamma -> inf: convex envelope")
        ax_i.set_ylim(-0.05, min(2.5, float(np.max(paper)) * 1.05))
        ax_i.set_xlabel("work rate w")
        ax_i.set_ylabel("I(w)  [P ~ exp(-tau gamma I)]")
        ax_i.set_title(f"tau_m = m = Delta = 1, a = {a:g}")
        ax_f.plot(pos, ws.paper_rate_function(model, -pos) - ws.paper_rate_function(model, pos),
                  "k--", lw=1.2, label="paper eq. (67)")
        ax_f.plot(pos, ws.weak_noise_limit_rate_function(model, -pos)
                  - ws.weak_noise_limit_rate_function(model, pos), "r-", lw=1.4, alpha=0.8,
                  label="gamma -> inf: convex envelope")
        ax_f.set_xlabel("work rate w > 0")
        ax_f.set_ylabel("I(-w) - I(w)")
        ax_f.set_title(f"fluctuation relation, a = {a:g}")
        ax_f.set_xlim(0, half)
        for ax in (ax_i, ax_f):
            ax.grid(alpha=0.3)
            ax.legend(fontsize=7)
    return [save(fig_i, outdir / "open_question_rate.png"),
            save(fig_f, outdir / "open_question_fluctuation.png")]


if __name__ == "__main__":  # pragma: no cover
    import sys
    for p in draw_open_question(sys.argv[1] if len(sys.argv) > 1 else "figures"):
        print(p)
