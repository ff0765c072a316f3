"""Figures of a parameter sweep (:func:`analogue.sweep`): what experiments plot (issue 23).

- **Mobility curve** (``mobility.png``/``.svg``, when ``a`` is varied): the drift ``<v>``
  against the force ``a``, the exact theory as a line (the dataset's fine theory curve,
  ``mean_v_theory_fine_a``) and
  the circuit as points with error bars (stderr; the bar's thin extension adds the
  systematic budget).  Other varied parameters give one curve each.
- **Diffusion against noise strength** (``diffusion.png``/``.svg``, when ``gamma`` is
  varied): ``D_x`` against the noise intensity ``D = 1/gamma`` on log-log axes, theory line
  (``D_x_theory_fine_gamma``) and circuit points, and below it the local exponent
  ``d ln D_x / d ln D`` (:func:`analogue.estimators.scaling.local_exponent`: chord slopes,
  of the fine theory curve as a line, of neighbouring circuit points with first-order
  errors), with the pure dry-friction (3) and viscous (1) limits and the
  exponent Goohpattader, Mettu & Chaudhury (Langmuir 2009) measured, 1.61.

The figures draw the dataset's values only (the local exponent is the estimator's reading of
them).  Files are written atomically.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.ticker import FuncFormatter

from ..estimators.scaling import local_exponent
from ..files import atomic_path
from .style import new_figure, save

__all__ = ["draw_sweep", "mobility_figure", "diffusion_figure", "FORMATS"]

FORMATS = ("png", "svg")
# the exponents marked on the local-exponent panel (analogue.theory.bias_transport)
_LIMITS = ((3.0, "pure dry friction (3)"), (1.0, "viscous (1)"))
_MEASURED = 1.61   # Goohpattader, Mettu & Chaudhury, Langmuir 2009


def _two_five(x: float, _pos=None) -> str:
    """Minor tick labels of a log axis at 2 and 5 times a power of ten only."""
    if not x > 0:
        return ""
    mantissa = x / 10.0 ** np.floor(np.log10(x) + 1e-9)
    return f"{x:g}" if round(mantissa) in (2, 5) and abs(mantissa - round(mantissa)) < 1e-6 else ""


def _curves(ds, axis: str):
    """``(label, selection)`` per combination of the other varied parameters."""
    others = [d for d in ds["mean_v"].dims if d != axis]
    if not others:
        return [("", {})]
    stacked = ds[others[0]].values if len(others) == 1 else None
    if stacked is not None:
        return [(f"{others[0]} = {x:g}", {others[0]: i}) for i, x in enumerate(stacked)]
    out = []
    for idx in np.ndindex(*[ds.sizes[d] for d in others]):
        sel = dict(zip(others, idx))
        label = ", ".join(f"{d} = {float(ds[d].values[i]):g}" for d, i in sel.items())
        out.append((label, sel))
    return out


def _theory_line(ds, obs: str, axis: str, sel: dict):
    """(x, y) of the theory line: the fine curve when the dataset has it, else the grid's."""
    fine = f"{obs}_theory_fine_{axis}"
    if fine in ds:
        return ds[f"{axis}_fine"].values, ds[fine].isel(sel).values
    return ds[axis].values, ds[f"{obs}_theory"].isel(sel).values


def _write(fig, out: Path, stem: str) -> list[Path]:
    paths = [save(fig, out / f"{stem}.png")]
    with atomic_path(out / f"{stem}.svg") as tmp:
        fig.savefig(tmp, format="svg")
    paths.append(out / f"{stem}.svg")
    return paths


def _errorbars(ax, x, ds, obs: str, sel: dict, colour, label: str, scale=None):
    y = ds[obs].isel(sel).values
    se = ds[f"{obs}_stderr"].isel(sel).values
    budget = ds[f"{obs}_budget"].isel(sel).values
    xs = x if scale is None else scale(x)
    ax.errorbar(xs, y, yerr=3 * se + budget, fmt="none", ecolor=colour, elinewidth=0.6,
                alpha=0.5)
    ax.errorbar(xs, y, yerr=se, fmt="o", ms=4, color=colour, capsize=2,
                label=f"circuit{' ' + label if label else ''} (1 SE; thin: 3 SE + budget)")


def mobility_figure(ds, out: str | Path) -> list[Path]:
    """The mobility curve of a sweep over ``a`` (module docstring); returns the files."""
    if "a" not in ds.dims:
        raise ValueError("the mobility curve needs a sweep over a (vary={'a': ...})")
    out = Path(out)
    fig, ax = new_figure(width=5.4, height=3.8)
    a = ds["a"].values
    for k, (label, sel) in enumerate(_curves(ds, "a")):
        colour = f"C{k % 10}"
        x, y = _theory_line(ds, "mean_v", "a", sel)
        ax.plot(x, y, "-", color=colour, lw=1.2,
                label=f"exact theory{' ' + label if label else ''}")
        _errorbars(ax, a, ds, "mean_v", sel, colour, label)
    ax.axhline(0.0, color="0.7", lw=0.6)
    ax.set_xlabel("force a = F/m (model units)")
    ax.set_ylabel("drift <v> (model velocity)")
    ax.set_title(f"{ds.attrs.get('experiment', '')}: drift against force"
                 f"{' (quick)' if ds.attrs.get('quick') else ''}", fontsize=10)
    ax.legend(fontsize=7, frameon=False)
    return _write(fig, out, "mobility")


def diffusion_figure(ds, out: str | Path) -> list[Path]:
    """D_x against the noise intensity 1/gamma with its local exponent (module docstring)."""
    if "gamma" not in ds.dims:
        raise ValueError("the diffusion figure needs a sweep over gamma (vary={'gamma': ...})")
    if ds.sizes["gamma"] < 2:
        raise ValueError("the diffusion figure needs at least 2 values of gamma")
    out = Path(out)
    fig, (ax, bx) = new_figure(2, 1, width=5.4, height=3.0)
    noise = 1.0 / ds["gamma"].values
    order = np.argsort(noise)
    for k, (label, sel) in enumerate(_curves(ds, "gamma")):
        colour = f"C{k % 10}"
        g, th = _theory_line(ds, "D_x", "gamma", sel)
        fine = np.argsort(1.0 / g)
        ax.plot(1.0 / g[fine], th[fine], "-", color=colour, lw=1.2,
                label=f"exact theory{' ' + label if label else ''}")
        _errorbars(ax, noise, ds, "D_x", sel, colour, label)
        ok = np.isfinite(th[fine]) & (th[fine] > 0)
        xm, e, _ = local_exponent((1.0 / g[fine])[ok], th[fine][ok])
        bx.plot(xm, e, "-", color=colour, lw=1.2)
        y = ds["D_x"].isel(sel).values[order]
        se = ds["D_x_stderr"].isel(sel).values[order]
        ok = np.isfinite(y) & (y > 0)
        if ok.sum() >= 2:
            xm, e, e_se = local_exponent(noise[order][ok], y[ok], se[ok])
            bx.errorbar(xm, e, yerr=e_se, fmt="o", ms=4, color=colour, capsize=2)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("noise intensity D = 1/gamma (model units)")
    ax.set_ylabel("D_x")
    ax.set_title(f"{ds.attrs.get('experiment', '')}: diffusion against noise strength"
                 f"{' (quick)' if ds.attrs.get('quick') else ''}", fontsize=10)
    ax.legend(fontsize=7, frameon=False)
    for value, text in _LIMITS:
        bx.axhline(value, color="0.6", lw=0.6, ls="--")
        bx.annotate(text, (noise.min(), value), fontsize=6, color="0.4",
                    xytext=(2, 2), textcoords="offset points")
    bx.axhline(_MEASURED, color="tab:red", lw=0.6, ls=":")
    bx.annotate("measured 1.61 (Goohpattader et al. 2009)", (noise.min(), _MEASURED),
                fontsize=6, color="tab:red", xytext=(2, 2), textcoords="offset points")
    bx.set_xscale("log")
    for axis in (ax.xaxis, bx.xaxis):   # minor labels of a short log range overlap: 2 and 5
        axis.set_minor_formatter(FuncFormatter(_two_five))
    bx.set_xlabel("noise intensity D = 1/gamma (model units)")
    bx.set_ylabel("local exponent d ln D_x / d ln D")
    return _write(fig, out, "diffusion")


def draw_sweep(ds, out: str | Path) -> list[Path]:
    """Every figure the sweep's axes allow (mobility: ``a`` varied; diffusion: ``gamma``
    varied with >= 2 values), written to ``out``; returns the files (empty if none)."""
    out = Path(out)
    paths: list[Path] = []
    if "a" in ds.dims:
        paths += mobility_figure(ds, out)
    if "gamma" in ds.dims and ds.sizes["gamma"] >= 2:
        paths += diffusion_figure(ds, out)
    return paths
