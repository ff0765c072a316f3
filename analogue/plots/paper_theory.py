"""The paper's theory figures (Figs. 1-9 of Baule, Touchette & Cohen), redrawn from the code.

Every ``fig*`` function draws on Axes it is given (so circuit or Monte Carlo data can be overlaid
later) or, with ``axes=None``, on a new Figure; parameters default to the paper's values and the
Axes are returned.  :func:`draw_all` writes all figures as PNG files;
``python -m analogue.plots.paper_theory OUTDIR`` does the same from the shell.

All quantities are in the reduced model units of :class:`analogue.Model` (velocity, time,
work rate ``w`` in units of ``m`` times velocity squared per time).
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from ..model import Model
from ..theory import weak_noise
from ..theory.weak_noise_work import fluctuation_relation, rate_function, work_optimal_path
# Fig. 5's layout is derived from the experiment's model in the study layer (the experiment
# checks it when its file is loaded); re-exported here, where it was first.
from ..study.figure_layout import FIG5_END_TAUS, FIG5_EXAMPLE_TAUS, FIG5_MARGIN, fig5_layout  # noqa: F401
from .style import KIND_COLOURS, TIME, VELOCITY, new_figure, save

__all__ = ["fig1_deterministic", "fig2_paths_stick", "fig3_paths_slip_up", "fig4_paths_slip_down",
           "fig5_boundaries", "fig5_layout", "fig6_propagator", "fig7_work_paths", "fig8_rate_function",
           "fig9_fluctuation_relation", "draw_all", "main"]

_GAMMA = 10.0  # gamma never enters the weak-noise paths; Model needs a value


def _model(tau_m, delta, a, gamma=_GAMMA, mass=1.0):
    return Model(tau_m=tau_m, delta=delta, a=a, gamma=gamma, mass=mass)


def _axes(axes, nrows, ncols):
    if axes is not None:
        return np.atleast_1d(np.asarray(axes, dtype=object)).ravel()
    _, ax = new_figure(nrows, ncols, squeeze=False)
    return ax.ravel()


def _zero_line(ax):
    ax.axhline(0.0, color="0.6", lw=0.8, zorder=0)


_TIME_LABELS = {"t_cross": "$t^\\times$", "t_a": "$t_a$", "t_b": "$t_b$", "t_1": "$t_1$", "t_2": "$t_2$"}


def _path_panel(ax, model, v0, v, t, title, *, show_attractor=False):
    """One optimal path (weak_noise.optimal_path) with its switching times marked."""
    p = weak_noise.optimal_path(model, v, t, v0, n=800)
    colour = KIND_COLOURS.get(p.kind, "k")
    ax.plot(p.s, p.v, color=colour, lw=2, label=f"{p.kind} path, A = {p.action:.3f}")
    ax.plot([p.s[0], p.s[-1]], [v0, v], "o", color=colour, ms=4)
    for name in ("t_cross", "t_a", "t_b", "t_1", "t_2"):
        x = getattr(p, name)
        if math.isfinite(x):
            ax.axvline(x, color="0.5", ls=":", lw=1)
            ax.annotate(_TIME_LABELS[name], (x, 1.0), xycoords=("data", "axes fraction"),
                        ha="center", va="bottom", fontsize=8, color="0.3")
    if show_attractor and model.attractor != 0:
        ax.axhline(model.attractor, color="k", ls="--", lw=0.8, label="$v_{ss}$")
    _zero_line(ax)
    ax.set_title(title, fontsize=10, pad=14)
    ax.set_xlabel(TIME)
    ax.set_ylabel(VELOCITY)
    ax.legend(fontsize=8, loc="best")
    return p


# ------------------------------------------------------------------------- Fig. 1
def fig1_deterministic(axes=None, tau_m=1.0, delta=0.7, a_values=(0.3, 1.2), v0s=(2.0, -2.0),
                       t_max=4.0):
    """Fig. 1: noise-free motion (eq. (13)): (a) a < Delta sticks at v = 0 in finite time,
    (b) a > Delta relaxes to v_ss = (a - Delta) tau_m (eq. (14)), with a kink at v = 0."""
    axes = _axes(axes, 1, len(a_values))
    s = np.linspace(0.0, t_max, 1001)
    for ax, a, tag in zip(axes, a_values, "abcdef"):
        m = _model(tau_m, delta, a)
        for v0, ls in zip(v0s, ("-", "--")):
            ax.plot(s, m.deterministic(v0, s), "k", ls=ls, lw=1.8, label=f"$v_0$ = {v0:g}")
            t_st = m.stick_time(v0)
            if math.isfinite(t_st) and m.regime == "stick":
                ax.plot([t_st], [0.0], "ko", ms=4)
        if m.attractor != 0:
            ax.axhline(m.attractor, color="k", lw=0.8, ls=":", label=f"$v_{{ss}}$ = {m.attractor:g}")
        _zero_line(ax)
        ax.set_title(f"Fig. 1({tag}): deterministic motion, $\\tau_m$={tau_m:g}, "
                     f"$\\Delta$={delta:g}, a={a:g} ({m.regime})", fontsize=10)
        ax.set_xlabel(TIME)
        ax.set_ylabel(VELOCITY)
        ax.legend(fontsize=8)
    return axes


# ---------------------------------------------------------------------- Figs. 2-4
FIG2_POINTS = (  # (v0, v, t): direct, direct crossing, indirect, indirect crossing
    (1.0, 1.2, 1.0), (1.0, -0.5, 0.8), (1.0, 0.4, 4.0), (1.0, -0.4, 4.0))
FIG3_POINTS = (  # direct, direct crossing, and their long-time versions along v_ss
    (1.5, 1.0, 1.0), (1.5, -0.5, 1.0), (1.5, 1.5, 8.0), (1.5, -0.5, 8.0))
FIG4_POINTS = ((-1.0, -1.5, 0.5), (-1.0, -1.0, 8.0))  # direct, twice crossing


def _paths_figure(axes, model, points, fig_no, caption):
    axes = _axes(axes, 1 if len(points) <= 2 else 2, 2)
    for ax, (v0, v, t), tag in zip(axes, points, "abcd"):
        _path_panel(ax, model, v0, v, t,
                    f"Fig. {fig_no}({tag}): {caption}, $v_0$={v0:g} $\\to$ v={v:g} at t={t:g}",
                    show_attractor=True)
    return axes


def fig2_paths_stick(axes=None, tau_m=1.0, delta=0.7, a=0.3, points=FIG2_POINTS):
    """Fig. 2: optimal paths for a < Delta, v0 > 0: direct, direct crossing (t_x from eq.
    (25)), indirect and indirect crossing (stuck on v = 0 between t_a, t_b; eqs. (31), (32))."""
    return _paths_figure(axes, _model(tau_m, delta, a), points, 2, f"a={a:g} < $\\Delta$={delta:g}")


def fig3_paths_slip_up(axes=None, tau_m=1.0, delta=0.7, a=1.2, points=FIG3_POINTS):
    """Fig. 3: a > Delta, v0 > 0: direct and direct crossing paths, short and long times (the
    long ones follow the attractor v_ss)."""
    return _paths_figure(axes, _model(tau_m, delta, a), points, 3, f"a={a:g} > $\\Delta$={delta:g}")


def fig4_paths_slip_down(axes=None, tau_m=1.0, delta=0.7, a=1.2, points=FIG4_POINTS):
    """Fig. 4: a > Delta, v0 < 0, v < 0: direct path, and for long times the twice crossing path
    (eq. (35)) that visits the attractor."""
    return _paths_figure(axes, _model(tau_m, delta, a), points, 4, f"a={a:g} > $\\Delta$={delta:g}")


# ------------------------------------------------------------------------- Fig. 5
# (the panel's times and ranges: analogue.study.figure_layout.fig5_layout)
def fig5_boundaries(axes=None, tau_m=1.0, delta=0.7, a=0.2, v0s=(2.0, -2.0), t_max=None,
                    t_end=None, margin=None):
    """Fig. 5: boundary lines w^pm (eq. (41)) and u^pm (eq. (45)) for a < Delta; between them the
    optimal path sticks (indirect / indirect crossing), outside it slips.  Example paths to
    final velocities above, between and below the boundaries at t = t_end are overlaid.
    ``t_max``, ``t_end``, ``margin``: None derives each panel's from its model and v0
    (:func:`fig5_layout`); a value given is used for every panel."""
    axes = _axes(axes, 1, len(v0s))
    m = _model(tau_m, delta, a)
    for ax, v0, tag in zip(axes, v0s, "ab"):
        lay = fig5_layout(m, v0)
        t_hi = lay["t_max"] if t_max is None else t_max
        t_ex = lay["t_example"] if t_end is None else t_end
        t = np.linspace(1e-3, t_hi, 800)
        b = weak_noise.boundaries(m, t, v0)
        ax.plot(t, b["w"], "k--", lw=1.3, label="w (indirect/direct)")
        ax.plot(t, b["u"], "k-.", lw=1.3, label="u (indirect crossing/direct crossing)")
        t_a = lay["t_a"]
        ax.axvline(t_a, color="0.5", ls=":", lw=1)
        ax.annotate("$t_a$", (t_a, 1.0), xycoords=("data", "axes fraction"), ha="center",
                    va="bottom", fontsize=8)
        # one path of each kind around the boundaries (the caption's green path: u/2)
        ends = (lay["examples"] if t_end is None and margin is None else
                weak_noise.boundary_examples(m, t_ex, v0, lay["margin"] if margin is None
                                             else margin))
        v_lim = 1.15 * max([abs(v0)] + [abs(x) for x in ends.values()])
        for v_end in ends.values():
            p = weak_noise.optimal_path(m, v_end, t_ex, v0, n=600)
            ax.plot(p.s, p.v, color=KIND_COLOURS.get(p.kind, "k"), lw=1.8, label=f"{p.kind} path")
        _zero_line(ax)
        ax.set_xlim(0.0, t_hi)
        ax.set_ylim(-v_lim, v_lim)
        ax.set_title(f"Fig. 5({tag}): boundaries, $\\tau_m$={tau_m:g}, $\\Delta$={delta:g}, "
                     f"a={a:g}, $v_0$={v0:g}", fontsize=10, pad=14)
        ax.set_xlabel(TIME)
        ax.set_ylabel(VELOCITY)
        ax.legend(fontsize=7, loc="upper left" if v0 < 0 else "lower left")
    return axes


# ------------------------------------------------------------------------- Fig. 6
def fig6_propagator(axes=None, tau_m=1.0, delta=0.7, a=0.2, gamma=10.0, v0=2.0,
                    times=(1.0, 2.2, 3.5, 12.0), v_range=(-1.5, 2.5)):
    """Fig. 6: saddle-point transition probability f(v, t | v0, 0) (eqs. (46), (47)), normalised
    on the grid, at four times; vertical dashed lines at u^+ and w^+ where they exist; the last
    time is compared with the stationary law p_s (eq. (6))."""
    axes = _axes(axes, 2, 2)
    m = _model(tau_m, delta, a, gamma=gamma)
    grid = np.linspace(*v_range, 1401)
    t_a = m.stick_time(v0)
    for ax, t, tag in zip(axes, times, "abcd"):
        f = np.asarray(weak_noise.propagator(m, grid, t, v0))
        ax.plot(grid, f, "k", lw=1.8, label="saddle point f(v,t|$v_0$)")
        b = weak_noise.boundaries(m, np.array([t]), v0)
        for key, ls in (("u", "-."), ("w", "--")):
            x = float(np.asarray(b[key]).ravel()[0])
            if math.isfinite(x) and v_range[0] < x < v_range[1]:
                ax.axvline(x, color="tab:blue", ls=ls, lw=1.2, label=f"{key}$^+$ = {x:.2f}")
        if tag == "d":
            ax.plot(grid, m.stationary_pdf(grid), color="tab:orange", ls=":", lw=2.2,
                    label="stationary $p_s$")
        ax.set_title(f"Fig. 6({tag}): t={t:g} ({'<' if t < t_a else '>'} $t_{{a+}}$={t_a:.2f}), "
                     f"$\\gamma$={gamma:g}, a={a:g}, $\\Delta$={delta:g}, $v_0$={v0:g}", fontsize=9)
        ax.set_xlabel(VELOCITY)
        ax.set_ylabel("probability density (1/model velocity)")
        ax.set_ylim(bottom=0)
        ax.legend(fontsize=7)
    return axes


# ------------------------------------------------------------------------- Fig. 7
FIG7_ENDPOINTS = ((2.0, 1.0), (0.0, 6.0), (8.0, 3.0), (-1.0, 2.0))


def fig7_work_paths(axes=None, tau_m=1.0, mass=1.0, delta=1.0, a=0.5,
                    panels=((2.0, 10.0), (2.0, 30.0), (4.0, 10.0), (4.0, 30.0)),
                    endpoints=FIG7_ENDPOINTS):
    """Fig. 7: paths minimising K = A - beta W at fixed work rate w (eqs. (57), (58),
    (60)); for long tau they sit near tilde v_w = w/(m a) (eq. (63), dashed)."""
    axes = _axes(axes, 2, 2)
    m = _model(tau_m, delta, a, mass=mass)
    colours = ("tab:blue", "tab:red", "tab:green", "tab:purple", "tab:orange")
    for ax, (w, tau), tag in zip(axes, panels, "abcd"):
        for (v0, v), c in zip(endpoints, colours):
            p = work_optimal_path(m, w, tau, v0, v, n=600)
            ax.plot(p.s, p.v, color=c, lw=1.8,
                    label=f"$v_0$={v0:g}, v={v:g} ({p.kind}), A/$\\tau$={p.action / tau:.2f}")
        ax.annotate(f"I(w) = {rate_function(m, w):.2f} (eq. (64))", (0.3, 0.3),
                    xycoords="axes fraction", fontsize=9)
        ax.axhline(w / (mass * a), color="k", ls="--", lw=1, label=f"$\\tilde v_w$ = {w / (mass * a):g}")
        _zero_line(ax)
        ax.set_title(f"Fig. 7({tag}): work-optimal paths, w={w:g}, $\\tau$={tau:g} "
                     f"($\\tau_m$=m=$\\Delta$=1, a={a:g})", fontsize=10)
        ax.set_xlabel(TIME)
        ax.set_ylabel(VELOCITY)
        ax.legend(fontsize=7, loc="lower right")
    return axes


# ---------------------------------------------------------------------- Figs. 8, 9
def _branches(ax, w, y, colour, label, dot_value=None):
    """Plot a function with a jump at w = 0 without joining the two sides."""
    neg, pos = w < 0, w > 0
    ax.plot(w[neg], y[neg], color=colour, lw=1.8, label=label)
    ax.plot(w[pos], y[pos], color=colour, lw=1.8)
    # open circles: one-sided limits; filled: the value at w = 0
    ax.plot([0, 0], [y[neg][-1], y[pos][0]], "o", mfc="white", color=colour, ms=5)
    if dot_value is not None:
        ax.plot([0], [dot_value], "o", color=colour, ms=4)


def fig8_rate_function(axes=None, tau_m=1.0, mass=1.0, delta=1.0, a=0.5,
                       a_values=(0.25, 0.5, 1.0, 1.5), w_max=(1.5, 4.0)):
    """Fig. 8: rate function I(w) of eq. (64): (a) a = 0.5, (b) several a.  The jump at w = 0 is
    a Delta; the filled dot is the value at w = 0 (cheapest way of holding v = 0)."""
    axes = _axes(axes, 1, 2)
    w = np.linspace(-w_max[0], w_max[0], 2001)
    m = _model(tau_m, delta, a, mass=mass)
    _branches(axes[0], w, rate_function(m, w), "k", f"a={a:g}", rate_function(m, 0.0))
    axes[0].annotate(f"jump a$\\Delta$ = {a * delta:g}", (0.0, (delta + a) ** 2 / 4),
                     xytext=(12, 10), textcoords="offset points", fontsize=8)
    w = np.linspace(-w_max[1], w_max[1], 2001)
    cmap = ("tab:blue", "tab:red", "tab:green", "tab:purple", "tab:orange")
    for aa, c in zip(a_values, cmap):
        mm = m.replace(a=aa)
        _branches(axes[1], w, rate_function(mm, w), c, f"a={aa:g}", rate_function(mm, 0.0))
    for ax, tag, txt in zip(axes, "ab", (f"a={a:g}", "various a")):
        ax.set_title(f"Fig. 8({tag}): rate function I(w), eq. (64), $\\tau_m$=m=$\\Delta$=1, {txt}",
                     fontsize=10)
        ax.set_xlabel("work rate w (model units)")
        ax.set_ylabel("I(w) (model units)")
        ax.set_ylim(bottom=0)
        ax.legend(fontsize=8)
    axes[1].set_ylim(0, 8)
    return axes


def fig9_fluctuation_relation(axes=None, tau_m=1.0, mass=1.0, delta=1.0, a=0.5, w_max=4.0):
    """Fig. 9: I(-w) - I(w) (eq. (67)) = w/(m tau_m) + a Delta sgn(w): a jump 2 a Delta at 0;
    the conventional SSFT line w/(m tau_m) (Delta = 0) for comparison."""
    ax = _axes(axes, 1, 1)[0]
    w = np.linspace(-w_max, w_max, 2001)
    m = _model(tau_m, delta, a, mass=mass)
    _branches(ax, w, fluctuation_relation(m, w), "k", "I(-w) - I(w), eq. (67)",
              fluctuation_relation(m, 0.0))
    ax.plot(w, w / (mass * tau_m), color="tab:blue", ls="--", lw=1, label="w/(m $\\tau_m$) ($\\Delta$=0)")
    _zero_line(ax)
    ax.set_title(f"Fig. 9: fluctuation relation, $\\tau_m$=m=$\\Delta$=1, a={a:g} "
                 f"(jump 2a$\\Delta$={2 * a * delta:g})", fontsize=10)
    ax.set_xlabel("work rate w (model units)")
    ax.set_ylabel("I(-w) - I(w) (model units)")
    ax.legend(fontsize=8)
    return np.array([ax], dtype=object)


# --------------------------------------------------------------------------- all
_FIGURES = (
    ("fig1_deterministic", fig1_deterministic, (1, 2)),
    ("fig2_paths_stick", fig2_paths_stick, (2, 2)),
    ("fig3_paths_slip_up", fig3_paths_slip_up, (2, 2)),
    ("fig4_paths_slip_down", fig4_paths_slip_down, (1, 2)),
    ("fig5_boundaries", fig5_boundaries, (1, 2)),
    ("fig6_propagator", fig6_propagator, (2, 2)),
    ("fig7_work_paths", fig7_work_paths, (2, 2)),
    ("fig8_rate_function", fig8_rate_function, (1, 2)),
    ("fig9_fluctuation_relation", fig9_fluctuation_relation, (1, 1)),
)


def draw_all(outdir) -> list[Path]:
    """Draw Figs. 1-9 with the paper's parameters into ``outdir`` (PNG, 120 dpi)."""
    outdir = Path(outdir)
    written = []
    for name, draw, (nrows, ncols) in _FIGURES:
        fig, axes = new_figure(nrows, ncols, width=6.0, height=4.2, squeeze=False)
        draw(axes.ravel())
        written.append(save(fig, outdir / f"{name}.png"))
    return written


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print("usage: python -m analogue.plots.paper_theory OUTDIR", file=sys.stderr)
        return 2
    for p in draw_all(argv[0]):
        print(p)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
