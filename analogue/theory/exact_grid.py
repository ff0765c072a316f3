"""Choice of the Fokker-Planck grid for the exact finite-noise numerics.

:func:`resolved_grid` resolves the stationary width ``sqrt(tau_m/gamma)`` and epsilon.  For
the propagator and the stationary dynamics two more scales matter, so it also resolves

* the **kink** of ``exp(-gamma U)`` at ``v = 0``: on either side the density decays on the
  length ``1/(gamma |U'(0+-)|)``, which for large gamma in the stick regime is much shorter
  than the Gaussian width (spacing <= that length / 2 at the default ``points_per_width=40``,
  whenever ``v = 0`` lies inside the covered range; with the log-linear interpolation of
  :func:`analogue.theory.exact.propagator` exponential profiles are then reproduced exactly);
* the **initial spreading** ``sqrt(2 (t - t0)/gamma)`` of the propagator at the earliest
  requested time (spacing <= that / 10).

The covered range is where ``gamma (U - U_min) < tail`` (solved exactly; U is convex), joined
with ``v0 +- sqrt(2 tail tau_m/gamma)`` for every start ``v0`` (a transient never spreads more
than the Delta = 0 process, since ``U'' >= 1/tau_m``).
"""
from __future__ import annotations

import math
from collections.abc import Iterable

from scipy import optimize

from .. import checks
from ..model import Model
from .fokker_planck import Grid

__all__ = ["resolved_grid", "stationary_range"]


def stationary_range(model: Model, tail: float = 40.0) -> tuple[float, float]:
    """``[lo, hi]`` with ``gamma (U(v) - U_min) = tail`` at both ends."""
    c = model.potential_minimum()
    u_min = float(model.potential(c))
    reach = math.sqrt(2.0 * tail * model.tau_m / model.gamma) * 1.000001

    def excess(v: float) -> float:
        return model.gamma * (float(model.potential(v)) - u_min) - tail

    # U - U_min >= (v - c)^2/(2 tau_m): the Gaussian reach brackets the root on each side.
    lo = optimize.brentq(excess, c - reach, c, xtol=1e-14, rtol=1e-12) if excess(c - reach) > 0 else c - reach
    hi = optimize.brentq(excess, c, c + reach, xtol=1e-14, rtol=1e-12) if excess(c + reach) > 0 else c + reach
    return lo, hi


def resolved_grid(model: Model, extra: Iterable[float] = (), h: float | None = None, t_min: float | None = None,
                  tail: float = 40.0, points_per_width: float = 40.0,
                  max_nodes: int = 400_000) -> Grid:
    """Grid covering the stationary law and the starts ``extra`` (see module docstring).

    ``h`` fixes the spacing (only the range is automatic); ``t_min`` is the shortest
    propagation time, whose spreading the spacing must resolve.
    """
    width = model.velocity_scale
    lo, hi = stationary_range(model, tail)
    reach = math.sqrt(2.0 * tail * model.tau_m / model.gamma)
    for e in extra:
        lo = min(lo, float(e) - reach)
        hi = max(hi, float(e) + reach)
    if h is None:
        h = width / points_per_width
        if model.epsilon > 0:
            h = min(h, model.epsilon / 8.0)
        if lo < 0.0 < hi and model.delta > 0:
            kink = 1.0 / (model.gamma * (model.delta + abs(model.a)))
            h = min(h, kink * 20.0 / points_per_width)
        if t_min is not None and t_min > 0:
            h = min(h, math.sqrt(2.0 * t_min / model.gamma) / 10.0)
    else:
        h = checks.positive("h", h)
    grid = Grid.span(lo, hi, h)
    if grid.n > max_nodes:
        # said in terms of the inputs that reach it: a huge gamma (or a tiny epsilon or t_min)
        # makes the spacing fine, far starts make the range wide
        raise ValueError(
            f"the grid would need {grid.n} nodes (> {max_nodes}) for the model tau_m="
            f"{model.tau_m:.6g}, delta={model.delta:.6g}, a={model.a:.6g}, gamma={model.gamma:.6g}, "
            f"epsilon={model.epsilon:.6g}: velocities [{lo:.6g}, {hi:.6g}] at spacing h={h:.3g}; "
            "a smaller gamma, a coarser h or a smaller range of starts fits")
    return grid
