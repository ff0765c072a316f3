"""Figures of the chapter "What experiments measure" (:mod:`analogue.study.measure`): they only
draw what the analysis computed.  Each function writes one PNG and returns ``(path, caption)``.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..study.measure import MeasureAnalysis
from .style import TIME, new_figure, save

__all__ = ["draw_spectra", "draw_first_passage"]

CIRCUIT = "tab:red"
EXACT = "k"
EXPECTED = "tab:blue"


def draw_spectra(analyses: list[MeasureAnalysis], out: Path):
    """Velocity power spectra, log-log, one panel per experiment: the exact S(omega), the
    exact expectation of the Welch estimate (aliasing, leakage), the circuit's Welch estimate
    with its chi-square band, and the two crossover frequencies."""
    fig, axes = new_figure(1, len(analyses), squeeze=False, width=5.2, height=3.9)
    for ax, a in zip(axes.ravel(), analyses):
        sp, est, m = a.theory.spectrum, a.spectrum, a.theory.model
        k = est.omega > 0
        ax.fill_between(est.omega[k], est.lower[k], est.upper[k], color=CIRCUIT, alpha=0.2,
                        lw=0, label=f"circuit {est.confidence:.0%} band")
        ax.plot(est.omega[k], est.value[k], ".", ms=2.5, color=CIRCUIT,
                label=f"circuit (Welch, {est.n_replicas} replicas)")
        ax.plot(sp.curve_omega, sp.curve, color=EXACT, lw=1.4, label=r"exact $S(\omega)$")
        ax.plot(sp.omega[k], sp.expected[k], "--", color=EXPECTED, lw=1.0,
                label="exact E[Welch] (sampling)")
        w1, w2 = sp.crossovers
        ax.axvline(w1, color="0.4", ls=":", lw=1.0)
        ax.text(w1, 0.95, r"$1/\tau_m$ ", transform=ax.get_xaxis_transform(), fontsize=8,
                color="0.3", ha="right", va="top")
        if math.isfinite(w2):
            ax.axvline(w2, color="tab:green", ls=":", lw=1.0)
            ax.text(w2, 0.95, " sticking rate", transform=ax.get_xaxis_transform(),
                    fontsize=8, color="tab:green", va="top")
        ax.set_xscale("log")
        ax.set_yscale("log")
        lo = float(np.min(est.value[k][est.omega[k] < 100.0 / m.tau_m]))
        ax.set_ylim(0.3 * lo, 4.0 * float(np.max(sp.curve)))
        ax.set_xlim(0.3 * float(est.omega[1]), float(est.omega[-1]))
        ax.set_xlabel(r"angular frequency $\omega$ (model units)")
        ax.set_ylabel(r"$S(\omega)$ (two-sided)")
        ax.set_title(f"{a.experiment} ({m.regime}): a={m.a:g}, $\\Delta$={m.delta:g}, "
                     f"$\\gamma$={m.gamma:g}", fontsize=10)
        ax.legend(fontsize=7, loc="lower left")
    names = "_".join(a.experiment for a in analyses)
    path = save(fig, out / f"spectra_{names}.png")
    return path, ("Velocity power spectra S(omega) (two-sided, angular frequency; S(0) = 2 D_x): "
                  "the circuit's Welch estimate over replicas (points, with its chi-square "
                  "confidence band) against the exact spectrum from the generator's resolvent "
                  "(line) and the exact expectation of the estimator, which adds the "
                  "sampling's aliasing and the window's leakage (dashed). Dotted: the viscous "
                  "crossover 1/tau_m and, in the stick regime, the sticking rate Var v / D_x "
                  "of pure dry friction.")


def draw_first_passage(a: MeasureAnalysis, out: Path):
    """First-passage times to rest from each v0: the circuit's histogram (density, with
    binomial error bars) against the exact density, with the deterministic stick time t_a
    and both means marked."""
    fps = a.theory.first_passage
    fig, axes = new_figure(1, len(fps), squeeze=False, width=4.6, height=3.5)
    for ax, (v0, th) in zip(axes.ravel(), fps.items()):
        est = a.first_passage[v0]
        t_max = float(th.t[-1])
        times = est.times[np.isfinite(est.times)]
        n = est.times.size
        # about 1.5 sqrt(n) bins (12 .. 32): the slip start far from rest has few passages
        n_bins = int(np.clip(1.5 * math.sqrt(max(times.size, 1)), 12, 32))
        edges = np.linspace(0.0, t_max, n_bins + 1)
        counts, _ = np.histogram(times, edges)
        width = np.diff(edges)
        dens = counts / (n * width)
        err = np.sqrt(counts * (1.0 - counts / n)) / (n * width)
        mid = 0.5 * (edges[1:] + edges[:-1])
        ax.errorbar(mid, dens, yerr=err, fmt="o", ms=3, color=CIRCUIT, mfc="none", lw=0.8,
                    label=f"circuit ({n} paths)")
        ax.plot(th.t, th.density, color=EXACT, lw=1.4, label="exact (absorbing FP)")
        if math.isfinite(th.t_a):
            ax.axvline(th.t_a, color="tab:green", ls="--", lw=1.0,
                       label=f"$t_a$ = {th.t_a:.3g} (noise-free)")
        if np.isfinite(est.mean) and th.values.mean_label is not None:
            ax.axvline(th.mean, color=EXACT, ls=":", lw=1.0, label=f"exact mean {th.mean:.3g}")
            ax.axvline(est.mean, color=CIRCUIT, ls=":", lw=1.0,
                       label=f"circuit mean {est.mean:.3g}")
        if th.survival_end > 1e-3:   # (a legend line: free text here overlapped the points)
            ax.plot([], [], " ", label=f"P(T > {th.record:g}) = {th.survival_end:.2f} exact; "
                    f"circuit {est.n_censored}/{n}")
        ax.set_xlim(0.0, t_max)
        ax.set_xlabel("first-passage time T to v = 0 " + f"({TIME.split('(')[1][:-1]})")
        ax.set_ylabel("density")
        ax.set_title(f"{a.experiment}: from v0 = {v0:g}", fontsize=10)
        ax.legend(fontsize=7, loc="upper right")
    path = save(fig, out / f"first_passage_{a.experiment}.png")
    return path, (f"{a.experiment}: time to come to rest (first passage to v = 0) from each "
                  "starting velocity: the circuit's first sign change per path (linear "
                  "interpolation between samples) against the exact density of the "
                  "Fokker-Planck equation with an absorbing boundary at v = 0, with the "
                  "noise-free stick time t_a (eq. (31)) and the means.")
