"""Choice of the Fokker-Planck grid for the exact finite-noise numerics.

:func:`resolved_grid` (stationary observables) resolves the stationary width
``sqrt(tau_m/gamma)`` and epsilon, and two more scales:

* the **kink** of ``exp(-gamma U)`` at ``v = 0``: on either side the density decays on the
  length ``1/(gamma |U'(0+-)|)``, which for large gamma in the stick regime is much shorter
  than the Gaussian width (spacing <= that length / 2 at the default ``points_per_width=40``,
  whenever ``v = 0`` lies inside the covered range);
* the **initial spreading** ``sqrt(2 (t - t0)/gamma)`` at the earliest time ``t_min`` when
  one is given (spacing <= that / 10).

The covered range is where ``gamma (U - U_min) < tail`` (solved exactly; U is convex), joined
with ``v0 +- sqrt(2 tail tau_m/gamma)`` for every start ``v0`` (a transient never spreads more
than the Delta = 0 process, since ``U'' >= 1/tau_m``).

:func:`propagator_grid` (the transition density of :func:`analogue.theory.exact.propagator`)
chooses the spacing from the local scales of the transient instead: the drift per cell on the
path of the mass (which includes the kink), the diffusion length of the earliest time, and
epsilon; and it narrows the range with the detailed-balance bound (see there).
"""
from __future__ import annotations

import math
from collections.abc import Iterable

from scipy import optimize

from .. import checks
from ..model import Model
from .fokker_planck import Grid

__all__ = ["resolved_grid", "stationary_range", "propagator_grid", "PECLET", "DIFFUSION_CELLS",
           "DEEP_START"]


def stationary_range(model: Model, tail: float = 40.0, xtol: float = 1e-14) -> tuple[float, float]:
    """``[lo, hi]`` with ``gamma (U(v) - U_min) = tail`` at both ends (to ``xtol``)."""
    c = model.potential_minimum()
    u_min = float(model.potential(c))
    reach = math.sqrt(2.0 * tail * model.tau_m / model.gamma) * 1.000001

    def excess(v: float) -> float:
        return model.gamma * (float(model.potential(v)) - u_min) - tail

    # U - U_min >= (v - c)^2/(2 tau_m): the Gaussian reach brackets the root on each side.
    lo = optimize.brentq(excess, c - reach, c, xtol=xtol, rtol=1e-12) if excess(c - reach) > 0 else c - reach
    hi = optimize.brentq(excess, c, c + reach, xtol=xtol, rtol=1e-12) if excess(c + reach) > 0 else c + reach
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


#: Largest drift per cell ``gamma |U'| h`` (the cell Peclet number) of the propagator grid on
#: the path of the mass.  A nearest-neighbour scheme with the exact stationary state (detailed
#: balance fixes the ratio of the two rates of a link) moves the mean exactly but spreads at
#: ``D (P/2) coth(P/2) = D (1 + P^2/12)``: 0.5 (the kink length / 2 of :func:`resolved_grid`)
#: inflated the variance of short-time transients by 2 %, 0.08 by 0.05 %.
PECLET = 0.08
#: Nodes per diffusion length ``sqrt(2 t_min/gamma)``: the lattice heat kernel has the excess
#: kurtosis ``h^2/l^2``, i.e. a peak error ``h^2/(8 l^2)`` (5e-4 at 16).
DIFFUSION_CELLS = 16.0
#: Starts with ``gamma (U(v0) - U_min) > DEEP_START`` are beyond the contour route (its
#: amplification ~ half that, limit ~90: :func:`analogue.theory.propagation.contour_nodes`);
#: the hybrid route's expm_multiply phase costs O(n / h^2) per unit time, so for them the grid
#: keeps the spacing of :func:`resolved_grid` (kink length / 2, width / 40, diffusion length /
#: 10; drift per cell up to ~1 at the start): errors up to 1e-2 - 6e-2 of the peak at
#: gamma = 1000 (measured), instead of runs of minutes.
DEEP_START = 180.0
#: The stationary "core" whose drift the grid resolves: ``gamma (U - U_min) <= CORE`` (the
#: density outside is below e^-8 of its peak, where an O(P^2) relative error is < 1e-6).
CORE = 8.0


def _slope(model: Model, v: float, side: float) -> float:
    """``U'(v)`` (one-sided at the kink: ``side`` = +1 from above, -1 from below)."""
    if model.epsilon > 0:
        dry = model.delta * math.tanh(v / model.epsilon)
    else:
        dry = model.delta * (math.copysign(1.0, v) if v != 0 else side)
    return v / model.tau_m + dry - model.a


def _level_set(model: Model, v0: float, tail: float) -> tuple[float, float]:
    """``[L, H]`` where ``gamma (U(v) - U(v0)) <= tail`` (an interval: U is convex)."""
    u0 = float(model.potential(v0))
    reach = math.sqrt(2.0 * tail * model.tau_m / model.gamma) * 1.000001

    def excess(v: float) -> float:
        return model.gamma * (float(model.potential(v)) - u0) - tail

    c = model.potential_minimum()
    out = []
    for end in (min(v0, c) - reach, max(v0, c) + reach):
        start = min(v0, c) if end < v0 else max(v0, c)
        # U - U(v0) >= (v - start)^2/(2 tau_m) beyond the start: the reach brackets the root
        # the range is rounded out to nodes anyway: 1e-6 of the reach is plenty
        out.append(optimize.brentq(excess, end, start, xtol=1e-6 * reach) if excess(end) > 0 else end)
    return out[0], out[1]


def propagator_grid(model: Model, v0: float, t_min: float, h: float | None = None,
                    tail: float = 40.0, max_nodes: int = 400_000) -> Grid:
    """Grid of the transition density from ``v0`` for times ``>= t_min`` (the paper's model).

    **Range**: the stationary range of :func:`stationary_range` joined with the reach of the
    start, ``|v - v0| <= sqrt(2 tail tau_m/gamma)`` (a transient never spreads more than the
    Delta = 0 process, since ``U'' >= 1/tau_m``) *and* ``gamma (U(v) - U(v0)) <= tail``:
    detailed balance gives ``f(v, t | v0) = f(v0, t | v) e^{-gamma (U(v) - U(v0))}``, so beyond
    that level the density is below ``e^-tail`` of a transition density's peak (equality for
    the Ornstein-Uhlenbeck process).  The second bound is what keeps dry friction at large
    tau_m small: at tau_m = 1e5, gamma = 1, Delta = 1 the range is +-41 instead of +-2829.

    **Spacing** (unless ``h`` is given), the smallest of

    * ``PECLET / (gamma G)``, ``G = max |U'|`` over the hull of ``v0`` and the core
      ``gamma (U - U_min) <= CORE`` (U' is monotone, so G is its largest end value; with the
      kink inside it includes ``Delta + |a|``): the drift per cell wherever mass travels;
    * ``sqrt(2 t_min/gamma) / DIFFUSION_CELLS``: the diffusion length of the earliest time;
    * ``epsilon / 8`` for the tanh law;

    (for starts deeper than DEEP_START in the tail: the spacing of :func:`resolved_grid`, see
    there), then shrunk (by less than a factor 2) so that ``v0`` is a node when ``|v0| >= h``: the start
    is then a delta on one node, not split between two, which would add ``theta (1 - theta)
    h^2`` to the initial variance.
    """
    lo, hi = stationary_range(model, tail)
    reach = math.sqrt(2.0 * tail * model.tau_m / model.gamma)
    lv, hv = _level_set(model, v0, tail)
    lo = min(lo, max(v0 - reach, lv))
    hi = max(hi, min(v0 + reach, hv))
    if h is None:
        c_lo, c_hi = stationary_range(model, CORE, xtol=1e-3 * model.velocity_scale)
        p_lo, p_hi = min(c_lo, v0), max(c_hi, v0)
        slopes = [abs(_slope(model, p_lo, -1.0)), abs(_slope(model, p_hi, 1.0))]
        if p_lo <= 0.0 <= p_hi:
            slopes += [abs(_slope(model, 0.0, -1.0)), abs(_slope(model, 0.0, 1.0))]
        u_min = float(model.potential(model.potential_minimum()))
        if model.gamma * (float(model.potential(v0)) - u_min) > DEEP_START:
            h = resolved_grid(model, extra=(v0,), t_min=t_min, max_nodes=2**62).h
        else:
            h = math.inf
            if max(slopes) > 0:
                h = PECLET / (model.gamma * max(slopes))
            h = min(h, math.sqrt(2.0 * t_min / model.gamma) / DIFFUSION_CELLS)
            if model.epsilon > 0:
                h = min(h, model.epsilon / 8.0)
        if abs(v0) >= h:
            h = abs(v0) / math.ceil(abs(v0) / h * (1.0 - 1e-12))
    else:
        h = checks.positive("h", h)
    grid = Grid.span(lo, hi, h)
    if grid.n > max_nodes:
        raise ValueError(f"the grid would need {grid.n} nodes (> {max_nodes}); pass a coarser h "
                         "or a later t_min")
    return grid
