"""Figures of the model family's members ("Beyond the paper").

Every function draws data already computed by :func:`analogue.study.members.analyse_member`
(``MemberAnalysis.figures``): no theory is evaluated here.  Each returns ``(path, caption)`` or
None when the member has no such figure.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..plots.style import new_figure, save
from .figures import budget_axes

__all__ = [
    "fig_member_budget",
    "fig_member_propagator",
    "fig_member_rate_function",
    "fig_member_stationary",
    "fig_spring_series",
    "fig_spring_stationary",
    "member_figures",
]


def fig_member_stationary(a, out: Path):
    d = a.figures.get("stationary")
    if d is None:
        return None
    name = a.exp.name
    fig, ax = new_figure(1, 1, width=6.0, height=3.8)
    s = np.asarray(d["samples"])
    thr = d["threshold"]
    has_atom = d["atom"] > 0
    moving = s[np.abs(s) >= thr] if has_atom else s
    # the exact grid reaches far into the tail: bin and show where the law has its mass
    cum = np.cumsum(d["density"]) / max(float(np.sum(d["density"])), 1e-300)
    lo = float(d["v"][np.searchsorted(cum, 1e-4)])
    hi = float(d["v"][min(np.searchsorted(cum, 1 - 1e-4), cum.size - 1)])
    # a margin of the law's own width (was 0.1 velocity units: a quarter of the shot
    # member's range, invisible for a wide law, wider than a narrow law itself)
    pad = 0.05 * (hi - lo) if hi > lo else 0.1 * max(abs(lo), 1e-3)
    lo, hi = lo - pad, hi + pad
    bins = np.linspace(lo, hi, 61)
    counts, edges = np.histogram(moving, bins=bins)
    width = edges[1] - edges[0]
    ax.stairs(counts / (s.size * width), edges, color="tab:orange", lw=1.2,
              label=f"circuit ({s.size} samples)" + (f", |v| >= {thr:g}" if has_atom else ""))
    ax.plot(d["v"], d["density"], "k-", lw=1.2, label=d.get("reference_label") or (
        "exact (continuous part)" if has_atom else "exact"))
    if "paper_density" in d:
        ax.plot(d["v"], d["paper_density"], "--", color="tab:blue", lw=1.0, label=d["paper_label"])
    if "weak_noise_density" in d:
        ax.plot(d["v"], d["weak_noise_density"], ":", color="tab:green", lw=2.0,
                label="weak noise: exp(-gamma U)/Z (quasi-potential)")
        ax.plot(d["u_minima"], np.zeros(len(d["u_minima"])), "^", color="tab:green", ms=6,
                clip_on=False, label="minima of U (gamma -> inf)")
    if has_atom:
        top = float(np.max(d["density"])) * 1.1
        ax.vlines(0.0, 0.0, top, color="k", lw=3, alpha=0.3)
        ax.annotate(f"atom P(v=0): exact {d['atom']:.3f}\ncircuit |v|<{thr:g}: "
                    f"{d['atom_measured']:.3f}", (0.0, top), xytext=(0.3 * hi, 0.9 * top),
                    fontsize=8, arrowprops={"arrowstyle": "->", "lw": 0.8})
    ax.set_xlim(lo, hi)
    ax.set_xlabel("v")
    ax.set_ylabel("density")
    ax.legend(fontsize=7)
    ax.set_title(f"Stationary law — {name}", fontsize=10)
    path = save(fig, out / f"beyond_stationary_{name}.png")
    cap = (f"{name}: stationary velocity law, circuit histogram after the burn-in against the "
           + (f"{d['reference_label']} histogram (no exact theory for this noise)"
              if d.get("reference_label") else "exact law (family numerics)"))
    if has_atom:
        cap += ("; the object sticks with probability P(v = 0) (grey bar: an atom, not a "
                "density), the histogram shows the moving part only")
    if "paper_density" in d:
        cap += "; dashed: the paper's law with the same kinetic friction Delta"
    if "weak_noise_density" in d:
        mins = ", ".join(f"{x:.3g}" for x in d["u_minima"])
        cap += ("; dotted: the weak-noise law exp(-gamma U)/Z from the quasi-potential U - "
                "U_min, which for a 1-D member with Gaussian noise is exact at every gamma "
                f"(L1 distance to the exact numerics {d['weak_noise_l1']:.1g}); triangles: the "
                f"minima of U (v = {mins}), where the law concentrates as gamma -> inf")
    return path, cap + "."


def _propagator_range(d) -> tuple[float, float]:
    """The v range that holds 99.9 % of every panel's exact continuous mass and 99.9 % of the
    circuit's samples: the theory grid itself reaches far into the tails (to v = 28 for the
    shot member, where the law lives below v ~ 3), which squeezed the curves and the
    histogram into a few bins at the left edge."""
    from scipy.integrate import cumulative_trapezoid
    v = np.asarray(d["v"], dtype=float)
    lo, hi = np.inf, -np.inf
    for f in np.atleast_2d(np.asarray(d["density"], dtype=float)):
        cum = cumulative_trapezoid(np.clip(f, 0.0, None), v, initial=0.0)
        if cum[-1] > 0:
            lo = min(lo, v[np.searchsorted(cum, 5e-4 * cum[-1])])
            hi = max(hi, v[min(np.searchsorted(cum, (1 - 5e-4) * cum[-1]), v.size - 1)])
    samples = np.concatenate([np.ravel(s) for s in d["samples"]]) if len(d["samples"]) else v
    if samples.size:
        lo = min(lo, float(np.quantile(samples, 5e-4)))
        hi = max(hi, float(np.quantile(samples, 1 - 5e-4)))
    if not (np.isfinite(lo) and np.isfinite(hi) and hi > lo):
        return float(v.min()), float(v.max())
    pad = 0.05 * (hi - lo)
    return max(float(v.min()), lo - pad), min(float(v.max()), hi + pad)


def fig_member_propagator(a, out: Path):
    d = a.figures.get("propagator")
    if d is None:
        return None
    name = a.exp.name
    times = d["times"]
    fig, axes = new_figure(1, len(times), width=3.4, height=3.2, squeeze=False)
    lo, hi = _propagator_range(d)
    for i, t in enumerate(times):
        ax = axes[0, i]
        s = np.asarray(d["samples"][i])
        atom = float(d["atom"][i])
        thr = d["threshold"]
        moving = s[np.abs(s) >= thr] if atom > 0 else s
        bins = np.linspace(lo, hi, 31)
        c, e = np.histogram(moving, bins=bins)
        ax.stairs(c / (s.size * (e[1] - e[0])), e, color="tab:orange", label="circuit")
        ax.plot(d["v"], d["density"][i], "k-", lw=1.0, label="exact")
        ax.set_xlim(lo, hi)
        if atom > 0:
            ax.set_title(f"t = {t:g}: P(v=0) exact {atom:.2f}, circuit "
                         f"{np.mean(np.abs(s) < thr):.2f}", fontsize=8)
        else:
            ax.set_title(f"t = {t:g}", fontsize=9)
        ax.set_xlabel("v")
    axes[0, 0].set_ylabel(f"f(v, t | v0 = {d['v0']:g})")
    axes[0, 0].legend(fontsize=7)
    path = save(fig, out / f"beyond_propagator_{name}.png")
    return path, (f"{name}: transition density from v0 = {d['v0']:g} at t = "
                  f"{', '.join(f'{t:g}' for t in times)}, circuit against the exact propagator.")


def fig_member_rate_function(a, out: Path):
    d = a.figures.get("rate_function")
    if d is None:
        return None
    name = a.exp.name
    pure_shot = bool(d.get("pure_shot", False))
    ylab = d.get("ylabel", "I(w)")
    # gamma = inf: J(w) with P_tau(w) ~ exp(-tau J), no 1/gamma (analogue.theory.family)
    div = "tau" if pure_shot else "(tau gamma)"
    fig, ax = new_figure(1, 1, width=5.5, height=3.6)
    ax.plot(d["w"], d["member"], "k.-", ms=3, label=f"exact, {name}")
    if "paper" in d:
        ax.plot(d["w"], d["paper"], "--", color="tab:blue", label=d["paper_label"])
    if "asymptote" in d:
        ax.plot(d["w_asymptote"], d["asymptote"], ":", color="tab:green",
                label=f"large-w form k_pole w - 2 sqrt(rate k_pole w) + c, k_pole = "
                      f"{d['k_pole']:g}")
    if "w_circuit" in d:
        ax.plot(d["w_circuit"], d["rate_circuit"], "o", color="tab:orange", ms=3,
                label=f"circuit, -ln P_tau(w)/{div}, tau = {d['tau']:g}")
    ax.axvline(d["mean"], color="0.6", lw=0.8)
    if d.get("edge") is not None:
        ax.axvline(d["edge"], color="0.3", lw=0.8, ls="--")
    ax.set_xlabel("work rate w")
    ax.set_ylabel(ylab)
    ax.legend(fontsize=7, loc="best")
    ax.set_title(f"Work rate function — {name}", fontsize=10)
    path = save(fig, out / f"beyond_rate_function_{name}.png")
    if pure_shot:
        cap = (f"{name}: exact work rate function J(w) = sup_k [k w - lambda(k)] of pure shot "
               "noise (gamma = inf: P_tau(w) ~ exp(-tau J(w)), no 1/gamma), by the Legendre "
               "transform of the Kolmogorov-Feller SCGF (grey: <w> of the member)")
        if d.get("edge") is not None:
            cap += (f"; the kicks only push up, so w >= F v_edge = {d['edge']:g} (dashed): "
                    f"there J = rate = {d['rate']:g} (no kick in the whole window), +inf below")
        cap += ("; no curve of the paper's model: its I(w) needs Gaussian noise, and there is "
                "none at gamma = inf")
    else:
        cap = (f"{name}: exact work rate function I(w) = sup_k [k w - lambda(k)]/gamma from "
               f"the tilted generator, against the {d.get('paper_label', 'paper')} "
               "(grey: <w> of the member)")
    if "asymptote" in d:
        cap += (f"; dotted: the large-w form k_pole w - 2 sqrt(rate k_pole w) + c of one-sided "
                f"kicks (the SCGF's pole at k_pole = {d['k_pole']:g}), c matched at the largest "
                "w of the grid: J is asymptotically linear with slope k_pole, reached only for "
                "k_pole w >> 1")
    cap += (f"; points: the circuit's finite-tau estimate -ln P_tau(w)/{div} from the "
            "stationary run, shifted to minimum 0 (it approaches the exact curve as tau grows)")
    if a.exp.model.shot is None:
        cap += "; its curvature at <w> is compared in the table as D_x"
    return path, cap + "."


def fig_spring_series(a, out: Path):
    d = a.figures.get("spring_series")
    if d is None:
        return None
    name = a.exp.name
    fig, axes = new_figure(2, 1, width=7.5, height=2.4, squeeze=False)
    t = d["t"]
    for r in range(len(d["x"])):
        axes[0, 0].plot(t, d["x"][r], lw=0.7, alpha=0.8)
        axes[1, 0].plot(t, d["v"][r], lw=0.7, alpha=0.8)
    axes[0, 0].plot(t, d["x_mc_mean"], "k--", lw=1.0, label="Monte Carlo mean")
    axes[0, 0].plot(t, d["x_circ_mean"], "k-", lw=1.0, label="circuit mean")
    band = d["stick_band"]
    axes[0, 0].axhspan(-band, band, color="0.85", zorder=0, label="|spring x - a| < Delta: sticks")
    axes[1, 0].plot(t, d["v_mc_mean"], "k--", lw=1.0)
    for ax in axes[:, 0]:
        ax.axvline(d["burn_in"], color="0.6", lw=0.8)
    axes[0, 0].set_ylabel("x (inductor current)")
    axes[1, 0].set_ylabel("v")
    axes[1, 0].set_xlabel("t")
    axes[0, 0].legend(fontsize=7, loc="upper right")
    path = save(fig, out / f"beyond_spring_series_{name}.png")
    f = a.facts
    return path, (f"{name}: released from x0 = {a.exp.model.x0:g} at rest, {len(d['x'])} "
                  "circuit replicas (colours) and the "
                  "means of circuit and Monte Carlo: stick-slip oscillations. First swing: "
                  f"half period {f['circuit_half_period']:.2f} (circuit) vs "
                  f"{f['mc_half_period']:.2f} (Monte Carlo; pi/sqrt(spring) = "
                  f"{f['omega_undamped_half_period']:.2f} without damping), amplitude "
                  f"{f['circuit_amplitude']:.2f} vs {f['mc_amplitude']:.2f} (Coulomb friction "
                  f"alone takes {f['coulomb_loss']:.2f} off per half swing). Grey line: burn-in.")


def fig_spring_stationary(a, out: Path):
    d = a.figures.get("spring_stationary")
    if d is None:
        return None
    name = a.exp.name
    fig, axes = new_figure(1, 2, width=3.8, height=3.2, squeeze=False)
    for ax, key, lab in ((axes[0, 0], "x", "x"), (axes[0, 1], "v", "v")):
        c, m = np.asarray(d[f"{key}_circ"]), np.asarray(d[f"{key}_mc"])
        lo, hi = np.percentile(np.concatenate([c, m]), [0.5, 99.5])
        bins = np.linspace(lo, hi, 41)
        ax.hist(m, bins=bins, density=True, histtype="step", color="k", label="Monte Carlo")
        ax.hist(c, bins=bins, density=True, histtype="step", color="tab:orange", label="circuit")
        ax.set_xlabel(lab)
    axes[0, 0].legend(fontsize=7)
    path = save(fig, out / f"beyond_spring_stationary_{name}.png")
    return path, (f"{name}: position and velocity after the burn-in, circuit against Monte Carlo "
                  "(the spring's reference: no exact 2-D solver).")


def fig_member_budget(a, out: Path):
    comps = a.comparisons
    if not comps:
        return None
    fig, ax = budget_axes(comps, "reference")
    ax.legend(fontsize=7, loc="lower right")
    ax.set_title(f"Error budget — {a.exp.name}", fontsize=10)
    path = save(fig, out / f"beyond_budget_{a.exp.name}.png")
    return path, (f"{a.exp.name}: error budget per observable; stacked bars are the allowed "
                  "deviation, diamonds the actual |circuit - reference|.")


def member_figures(a) -> list:
    """(what, drawing function) for every figure of a member, in page order."""
    return [("stationary law", fig_member_stationary), ("spring time series", fig_spring_series),
            ("spring stationary", fig_spring_stationary), ("propagator", fig_member_propagator),
            ("rate function", fig_member_rate_function), ("error budget", fig_member_budget)]
