"""Exact finite-noise numerics for the one-dimensional members of the model family.

Members (see :mod:`analogue.model`): cubic viscous friction, the Stribeck law, Poissonian shot
noise (with or without Gaussian noise).  The spring (a two-dimensional state) has no exact
solver here: :func:`analogue.montecarlo.simulate_sde` is its reference.

Methods
-------
* Gaussian noise only (``model.is_gradient``): ``p_s = exp(-gamma U)/Z`` stays exact
  (1-D, additive noise), so mean, variance, P(v > 0), <sgn v> are quadratures of the exact law,
  split at 0 and at the local minima of U (Stribeck can make U double-welled).
* With shot noise: the stationary solution of the Kolmogorov-Feller generator of
  :mod:`analogue.theory.kolmogorov_feller` (a bordered sparse solve), with the atom at v = 0
  (``p_zero``, the probability to be stuck) as its own state when gamma = inf.  The upwind drift
  is first order, so moments are Richardson-extrapolated over (h, h/2).
* Green-Kubo diffusion ``D_x = int_0^inf C(t) dt`` from the Poisson equation
  ``L g = -(v - <v>) p_s`` of the same generator (bordered solve), Richardson-extrapolated.
* Propagator: the generator evolved from a unit mass at v0 (Crank-Nicolson); the density of
  the continuous part is interpolated linearly on each side of 0, the atom returned
  separately.  Pure shot noise: the unkicked mass rides the noise-free path (a moving atom)
  and the once-kicked mass, which jumps at that front, is a quadrature along the flow
  (:func:`_once_kicked`); the grids carry only the mass kicked twice or more.
* Work large deviations: SCGF = principal eigenvalue of the tilted generator ``L + k F diag(v)``
  (Perron root of a Metzler matrix, by shifted inverse iteration on the banded form; for
  Gaussian-only members the Scharfetter-Gummel generator is symmetrisable and a symmetric
  tridiagonal solver is used), Richardson over (h, h/2); rate function by a Legendre transform
  (concave maximisation in k over :func:`scgf_domain`).  With one-sided kicks the SCGF has a
  pole at ``k F tau_m mean = 1`` (two-sided: poles at +-1); for ``k F > 0`` (two-sided: any
  k) it is computed after the exponential change of measure of the kicks
  (:func:`_kick_transform`, :func:`_two_sided_transform`), whose grid follows the tilted law out to
  the pole (the tilted generator on a fixed grid has spurious top-of-grid modes ~ e^{-c v}
  there), and the rate function is asymptotically linear (:func:`rate_function_asymptote`).
  Checked against the OU-shot closed forms ``lambda(k) = k F a tau + rate (1/(1 - k F tau
  mean) - 1)`` and ``J(w) = (sqrt(B) - sqrt(rate))^2`` up to ``1 - k/k_pole = 1e-3``.  Scaling: ``I(w) = (1/gamma) sup_k [k w - lambda(k)]``
  as in the paper when gamma is finite; with gamma = inf (pure shot noise) the rate function
  is ``J(w) = sup_k [k w - lambda(k)]`` with ``P_tau(w) ~ exp(-tau J(w))``.
"""
from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import NamedTuple, cast

import numpy as np
from numpy.typing import ArrayLike
from scipy import integrate, optimize, sparse
from scipy.linalg import eigh_tridiagonal
from scipy.sparse.linalg import splu

from .. import checks
from ..model import Model, ShotNoise
from .flow_table import flow_table
from .fokker_planck import Grid, symmetric_generator
from .kolmogorov_feller import (Kicks, ShotGrid, _gaussian_range, _grid_range, default_spacing,
                                has_atom, shot_generator, stable_zeros)
from .moments import StationaryMoments


_Solve = Callable[[np.ndarray], np.ndarray]   # b -> x of a factorised linear system

__all__ = ["is_member", "stationary_law", "stationary_moments", "propagator", "propagator_atom",
           "scgf", "rate_function", "check_one_dimensional", "unkicked", "sample_stationary",
           "autocorrelation", "scgf_domain", "rate_function_asymptote", "work_edge"]


def is_member(model: Model) -> bool:
    """True for the extensions this module handles (anything but the paper's model)."""
    return not model.is_paper


def check_one_dimensional(model: Model) -> None:
    checks.instance("model", model, Model, description="an analogue.Model")
    if model.dimension == 2:
        raise ValueError("spring > 0: the state (x, v) is two-dimensional and has no exact solver "
                         "here; use analogue.montecarlo.simulate_sde as the reference")
    if model.noise_kind.exact_solver is None:
        raise ValueError(f"noise kind {model.noise_kind.kind!r} has no exact solver here (the "
                         "Fokker-Planck and Kolmogorov-Feller solvers take white Gaussian noise "
                         "and kicks); use analogue.montecarlo.simulate_sde as the reference")
    if not model.is_noisy:
        raise ValueError("the model is noise-free (gamma = inf and shot = None): no stationary law "
                         "or propagator; set a finite gamma or shot noise")


# ----------------------------------------------------------------------- stationary law
def _factor(M: sparse.spmatrix, extra_dense: Iterable[int] = ()) -> _Solve:
    """Sparse LU of a nearly banded matrix whose few dense rows (folds of the jump kernel at the
    grid ends, a normalisation row) would fill any ordering in: those states are moved to the
    end by a symmetric permutation (diagonal stays diagonal), then LU in the natural order with
    diagonal pivots (the matrices here are M-matrix-like, diagonally dominant by columns), so
    the fill is confined to the last rows.  Returns ``solve(b)``."""
    M = sparse.csr_matrix(M)
    n = M.shape[0]
    dense = set(np.flatnonzero(np.diff(M.indptr) > 24).tolist()) | set(extra_dense)
    if not dense:
        lu = splu(M.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0)
        solve_lu: _Solve = lu.solve
        return solve_lu
    last = np.array(sorted(dense), dtype=int)
    perm = np.r_[np.setdiff1d(np.arange(n), last), last]
    P = M[perm][:, perm].tocsc()
    lu = splu(P, permc_spec="NATURAL", diag_pivot_thresh=0.0)

    def solve(b: np.ndarray) -> np.ndarray:
        out = np.empty_like(b, dtype=float)
        out[perm] = lu.solve(np.asarray(b, dtype=float)[perm])
        return out
    return solve


def _anchor(model: Model, g: ShotGrid) -> int:
    """A recurrent state (one that carries stationary mass): the stuck state when there is an
    atom, else the state nearest the noise-free attractor of the mean force (``a`` plus the
    mean kick force ``rate mean`` for one-sided kicks): states below the support of one-sided
    kicks are transient and must not be anchored."""
    noise = model.noise_kind
    if noise.one_sided and noise.pure_kicks:
        # one-sided kicks only push up, and the flow from above ends at the highest sliding
        # attractor v*: [v*, inf) is the recurrent class, everything below it (the stuck state
        # included) transient (Stribeck, tau_m = 5, Delta = 0.3, delta_s = 1, v_s = 0.2,
        # a = 0.6: anchored at S the solve gave weights of -2e12 on h/6).  Anchor the bulk:
        # the highest zero of the mean-force drift f + rate mean (> v*); not the cell next
        # to v*, where the density vanishes like (v - v*)^(rate tau_m - 1) (rate tau_m = 10:
        # that cell's weight was 1e-12 of the peak, and the solve failed)
        zs = stable_zeros(model)
        if zs.size and zs.max() > 0.0:
            bulk = stable_zeros(model.replace(a=model.a + noise.mean_force, shot=None,
                                              gamma=math.inf))
            cells = g.v[:-1] if g.atom else g.v
            if bulk.size and bulk.max() > zs.max():
                return int(np.argmin(np.abs(cells - bulk.max())))
            return int(np.flatnonzero(cells > zs.max())[0])
    if g.atom:
        return g.n - 1
    a_eff = model.a + model.noise_kind.mean_force
    target = model.replace(a=a_eff, shot=None, gamma=math.inf).attractor
    return int(np.argmin(np.abs(g.v - target)))


def _solve_singular(model: Model, g: ShotGrid, rhs: np.ndarray, value: float) -> np.ndarray:
    """A solution of ``L x = rhs`` (``sum rhs = 0``) with ``x_j = value`` at the anchor j.  In
    the banded form ``N L`` any single row is redundant (the left null vector ``N^{-T} 1`` is
    positive), so row and column j are removed: the rest is a nonsingular M-matrix-like
    system, factorised by :func:`_factor` with diagonal pivots (no normalisation row, whose
    last pivot cancels)."""
    n = g.n
    j = _anchor(model, g)
    A = g.banded_L().tocsc()
    top = rhs if g.premultiplier is None else g.premultiplier @ rhs
    top = np.asarray(top, dtype=float) - value * A[:, j].toarray().ravel()
    keep = np.r_[0:j, j + 1:n]
    B = A[keep][:, keep]
    x = np.empty(n)
    x[j] = value
    x[keep] = _factor(B)(top[keep])
    if not np.all(np.isfinite(x)):
        raise RuntimeError("the stationary/Poisson solve failed (non-finite solution)")
    return x


def _solve_stationary(g: ShotGrid, model: Model) -> np.ndarray:
    p = _solve_singular(model, g, np.zeros(g.n), 1.0)
    if p.min() < -1e-9 * p.max():
        raise RuntimeError(f"stationary solve gave negative weights ({p.min():.3g}): the anchor "
                           "state is not recurrent")
    p = np.clip(p, 0.0, None)
    out: np.ndarray = p / p.sum()
    return out


def stationary_law(model: Model,
                   h: float | None = None) -> tuple[np.ndarray, np.ndarray, float]:
    """``(v, density, p_zero)``: the stationary law of a 1-D member, continuous density at the
    velocities ``v`` and the atom ``p_zero = P(v = 0)``, as accurate as
    :func:`stationary_moments` (one routine, :func:`_law`, gives both).  ``h`` is the grid
    spacing (default :func:`kolmogorov_feller.default_spacing`).

    * Gaussian noise only: ``exp(-gamma U(v))/Z`` at the nodes ``v`` of spacing h, with Z the
      quadrature that gives the moments (the law is exact; the density carries Z's ~1e-10).
      The Scharfetter-Gummel grid's own normalisation (a Riemann sum across the cusp at 0)
      was off by 7e-3 of the peak (Stribeck, tau_m = 1, Delta = 0.5, delta_s = 0.9,
      v_s = 0.3, a = 0.3, gamma = 200).
    * Pure shot noise (cells of width h, upwind, first order): the cell masses of the grids h
      and h/2 (its cells summed into the cells of h; v = 0 is an edge of both)
      Richardson-extrapolated, ``2 P(h/2) - P(h)``, and so is the atom; ``density = P/h`` at
      the cell centres.  The atom, P(v > 0), P(v < 0) and <sgn v> of this law are those of
      :func:`stationary_moments` (the same sums); its mean and variance (each cell read as
      uniform) agree with the moments' two-grid Richardson to O(h^2): 2e-6 to 7e-5 on the
      test members, 4e-4 (3e-3 standard deviations) where the density is singular at an
      attractor (rate tau_m < 1), whose location inside its cell the cell mass does not
      carry.  Against the closed form ``p_zero`` and ``C e^{-v/mean} (1 + v/(b tau_m))^{rate
      tau_m - 1}`` (Delta = 0.7, a = 0.2, rate 2, mean 0.3, default h): atom 0.342436
      (single grid 0.337605, exact 0.342466), cell averages within 7e-5 of the peak (single
      grid 7.1e-3), the cell next to v = 0 included.
    * Shot + Gaussian noise (nodes, second order): the nodal densities of h and h/2 at the
      nodes of h, ``(4 p(h/2) - p(h))/3``; the moments are Richardson-extrapolated from the
      same two grids (they agree with this law's node sums to O(h^2)).
    """
    check_one_dimensional(model)
    if h is None:
        h = default_spacing(model)
    law = _law(model, h)
    return law.v, law.density, law.atom


@dataclass(frozen=True)
class _Law:
    """A stationary law on a uniform grid: ``density`` at ``v`` (cell centres when ``cells``,
    read as uniform in each cell of width h; else nodes), the atom at 0, and ``moments``
    [mean, second moment, P(v>0), P(v<0), <sgn v>, P(v=0), D_x] Richardson-extrapolated from
    the same two grids (None for Gaussian-only members, whose moments are quadratures)."""

    v: np.ndarray
    density: np.ndarray
    atom: float
    h: float
    cells: bool
    moments: np.ndarray | None = None


def _grid_solution(model: Model, h: float) -> tuple[ShotGrid, np.ndarray]:
    g = shot_generator(model, h)
    return g, _solve_stationary(g, model)


def _law(model: Model, h: float) -> _Law:
    """The stationary law of :func:`stationary_law` and the moments of
    :func:`stationary_moments` from the same grids h and h/2 (the route: the noise's exact
    solver, ``model.noise.exact_solver``)."""
    return _ROUTES[model.noise_kind.exact_solver].law(model, h)  # type: ignore[index]


def _law_fokker_planck(model: Model, h: float) -> _Law:
    v = Grid.span(*_grid_range(model), h).v  # the nodes of the Scharfetter-Gummel grid
    return _Law(v, _gradient_density(model, v), 0.0, h, False)


def _law_kolmogorov_feller(model: Model, h: float) -> _Law:
    (gc, pc), (gf, pf) = _grid_solution(model, h), _grid_solution(model, h / 2.0)
    mc, mf = _moments_of(model, gc, pc), _moments_of(model, gf, pf)
    if gc.nodal:  # second order; fine node 2j is coarse node j (v = 0 a node of both)
        idx = np.rint(gc.v / (h / 2.0)).astype(int) - int(np.rint(gf.v[0] / (h / 2.0)))
        inside = (idx >= 0) & (idx < gf.n)
        fine = np.where(inside, pf[np.clip(idx, 0, gf.n - 1)] / (h / 2.0), 0.0)
        dens = (4.0 * fine - pc / h) / 3.0
        return _Law(gc.v, dens, 0.0, h, False, (4.0 * mf - mc) / 3.0)
    # first order: the fine cells summed into the coarse ones (v = 0 an edge of both)
    nc, nf = gc.n_cells, gf.n_cells
    first_edge = gc.v[0] - 0.5 * h
    parent = np.clip(np.floor((gf.v[:nf] - first_edge) / h).astype(int), 0, nc - 1)
    agg = np.bincount(parent, weights=pf[:nf], minlength=nc)
    mass = 2.0 * agg - pc[:nc]
    atom = 2.0 * pf[-1] - pc[-1] if gc.atom else 0.0
    return _Law(gc.v[:nc], mass / h, float(atom), h, True, 2.0 * mf - mc)


def _gradient_density(model: Model, v: np.ndarray) -> np.ndarray:
    """``exp(-gamma U(v))/Z`` with Z from the quadrature of the moments: exact U for the sgn
    law; for epsilon > 0 the law of :func:`_gradient_smooth_law` (Simpson on a grid of at most
    epsilon/20), its logarithm interpolated by a cubic spline (linear interpolation of the
    density was 4.7e-6 of the peak off at gamma = 200, epsilon = 0.02)."""
    if model.epsilon > 0:
        from scipy.interpolate import CubicSpline
        vs, logw = _gradient_smooth_log_law(model)
        ok = np.isfinite(logw)
        inside = (v >= vs[ok][0]) & (v <= vs[ok][-1])
        dens: np.ndarray = np.zeros(np.shape(v))
        dens[inside] = np.exp(CubicSpline(vs[ok], logw[ok])(v[inside]))
        return dens
    u0, z = _gradient_quadrature(model, normaliser=True)[5:7]
    out: np.ndarray = np.exp(-(model.gamma * model.potential(v) - u0)) / z
    return out


def _grid_moments(model: Model, h: float) -> np.ndarray:
    """[mean, second moment, P(v>0), P(v<0), <sgn v>, P(v=0), D_x] on one grid."""
    return _moments_of(model, *_grid_solution(model, h))


def _moments_of(model: Model, g: ShotGrid, p: np.ndarray) -> np.ndarray:
    """:func:`_grid_moments` of the stationary vector ``p`` of the grid ``g``."""
    h = g.h
    v = g.v
    cells = p[:-1] if g.atom else p
    vc = v[:-1] if g.atom else v
    atom = p[-1] if g.atom else 0.0
    mean = float(np.dot(vc, cells))
    # cells carry a uniform density (width h): + h^2/12 to the second moment; nodes do not
    second = float(np.dot(vc * vc, cells)) + (0.0 if g.nodal else h * h / 12.0 * cells.sum())
    if g.nodal:  # the node v = 0 stands for [-h/2, h/2]: half of it on each side
        zero = np.isclose(vc, 0.0, atol=1e-12 * h)
        pp = float(cells[vc > 0].sum() + 0.5 * cells[zero].sum())
        pm = float(cells[vc < 0].sum() + 0.5 * cells[zero].sum())
        sign = float(np.dot(np.sign(vc), cells))
    else:
        pp, pm = float(cells[vc > 0].sum()), float(cells[vc < 0].sum())
        sign = pp - pm
    return np.array([mean, second, pp, pm, sign, atom, _green_kubo(model, g, p)])


def _green_kubo(model: Model, g: ShotGrid, p: np.ndarray) -> float:
    """``D_x = sum dv g`` with ``L g = -dv p``, ``dv = v - <v>`` (g is fixed up to ``+ c p``,
    which ``dv . p = 0`` ignores)."""
    dv = g.v - float(np.dot(g.v, p))
    gk = _solve_singular(model, g, -(dv * p), 0.0)
    return float(np.dot(dv, gk))


def _gradient_smooth_law(model: Model) -> tuple[np.ndarray, np.ndarray]:
    """``(v, exp(-gamma U)/Z)`` for a smooth law (epsilon > 0) on the Simpson grid of
    :func:`_gradient_smooth_moments` (v = 0 a node when the range straddles it)."""
    lo, hi = _gaussian_range(model)
    h = min(model.epsilon / 20.0, model.velocity_scale / 400.0,
            model.friction.velocity_length / 100.0)
    def nodes(a: float, b: float) -> np.ndarray:
        n = int(min(2_000_000, 2 * math.ceil((b - a) / (2 * h))))
        return np.linspace(a, b, max(n, 2) + 1)
    if lo < 0.0 < hi:  # v = 0 a node, so that P(v > 0) is a Simpson sum of a smooth integrand
        v = np.concatenate([nodes(lo, 0.0), nodes(0.0, hi)[1:]])
    else:
        v = nodes(lo, hi)
    u = integrate.cumulative_simpson(-model.drift(v), x=v, initial=0.0)
    w = np.exp(-model.gamma * (u - u.min()))
    return v, w / integrate.simpson(w, x=v)


def _gradient_smooth_log_law(model: Model) -> tuple[np.ndarray, np.ndarray]:
    """``(v, ln p)`` of :func:`_gradient_smooth_law` (for interpolation: ln p is smooth)."""
    v, w = _gradient_smooth_law(model)
    with np.errstate(divide="ignore"):
        return v, np.log(w)


def _gradient_smooth_moments(model: Model) -> np.ndarray:
    """[mean, second, P(v>0), P(v<0), <tanh(v/eps)>] of exp(-gamma U)/Z for a smooth law
    (epsilon > 0): U by cumulative Simpson of the drift (U' = -drift) and the moments by
    Simpson on a uniform grid resolving epsilon/20, the width/400 and the Stribeck length/100
    (fourth order; the per-point quadrature of the tanh-Stribeck U took ~10 s)."""
    v, w = _gradient_smooth_law(model)
    hits = np.flatnonzero(v == 0.0)
    i0 = int(hits[0]) if hits.size else (0 if v[0] >= 0 else v.size - 1)
    m1 = integrate.simpson(w * v, x=v)
    m2 = integrate.simpson(w * v * v, x=v)
    pp = integrate.simpson(w[i0:], x=v[i0:]) if i0 < v.size - 1 else 0.0
    sign = integrate.simpson(w * np.tanh(v / model.epsilon), x=v)
    return np.array([m1, m2, pp, 1.0 - pp, sign])


def _gradient_quadrature(model: Model, normaliser: bool = False) -> np.ndarray:
    """[mean, second, P(v>0), P(v<0), <sgn v>] of exp(-gamma U)/Z by quadrature; with
    ``normaliser`` also ``[gamma U0, Z]`` (``Z = int exp(-(gamma U - gamma U0))``)."""
    r = model._support_bound(50.0)
    grid = np.linspace(-r, r, 4001)
    u = model.gamma * model.potential(grid)
    u0 = float(u.min())
    # breakpoints: 0 and the local minima of U (peaks of the law), plus their widths
    mins = [float(grid[i]) for i in range(1, grid.size - 1) if u[i] <= u[i - 1] and u[i] <= u[i + 1]]
    w = model.velocity_scale
    pts = sorted({0.0, *mins, *(m + s * w for m in mins for s in (-3, 3))})
    out = []
    for lo, hi in ((-r, 0.0), (0.0, r)):
        ps = [p for p in pts if lo < p < hi]

        def f(v: float) -> np.ndarray:
            e = math.exp(-(model.gamma * float(model.potential(v)) - u0))
            return np.array([e, e * v, e * v * v])

        val, _ = integrate.quad_vec(f, lo, hi, points=ps or None, epsabs=0.0, epsrel=1e-12,
                                    limit=2000)
        out.append(val)
    (zm, m1m, m2m), (zp, m1p, m2p) = out
    z = zm + zp
    if model.epsilon > 0:
        sign, _ = integrate.quad(lambda v: math.tanh(v / model.epsilon)
                                 * math.exp(-(model.gamma * float(model.potential(v)) - u0)),
                                 -r, r, points=pts, limit=2000, epsabs=0, epsrel=1e-12)
        sign /= z
    else:
        sign = (zp - zm) / z
    res = [(m1m + m1p) / z, (m2m + m2p) / z, zp / z, zm / z, sign]
    return np.array(res + ([u0, z] if normaliser else []))


def stationary_moments(model: Model, h: float | None = None) -> StationaryMoments:
    """Exact stationary moments of a 1-D member (module docstring) as
    :class:`analogue.theory.stationary.StationaryMoments`, with ``p_zero = P(v = 0)`` (the atom:
    the probability of being stuck, > 0 only for pure shot noise in the stick regime).

    Accuracy: Gaussian-only moments are quadratures (~1e-10), D_x Richardson over the
    Scharfetter-Gummel grids (h, h/2).  Pure shot noise: the moments of the Richardson law of
    :func:`stationary_law` (cells of h and h/2, first-order upwind), so law and moments are
    one; shot + Gaussian: Richardson over the nodal grids (h, h/2).  Tests check them against
    closed forms (Gamma law, the ODE reduction) to 2e-4 and against exact Monte Carlo.
    """
    check_one_dimensional(model)
    if h is None:
        h = default_spacing(model)
    mean, second, pp, pm, sign, atom, diff = _ROUTES[
        model.noise_kind.exact_solver].moments(model, h)  # type: ignore[index]
    return StationaryMoments(mean=float(mean), variance=float(second - mean * mean),
                             p_positive=float(pp), p_negative=float(pm), mean_sign=float(sign),
                             diffusion=float(diff), drift=float(mean), p_zero=float(atom))


def _moments_fokker_planck(model: Model, h: float) -> tuple[float, ...]:
    quad = (_gradient_quadrature(model) if model.epsilon == 0
            else _gradient_smooth_moments(model))
    mean, second, pp, pm, sign = quad
    # SG is second order: Richardson (4 f - c)/3 for the diffusion
    gc, gf = _grid_solution(model, h), _grid_solution(model, h / 2.0)
    diff = (4.0 * _green_kubo(model, *gf) - _green_kubo(model, *gc)) / 3.0
    return mean, second, pp, pm, sign, 0.0, diff


def _moments_kolmogorov_feller(model: Model, h: float) -> tuple[float, ...]:
    ext = _law(model, h).moments
    assert ext is not None
    return tuple(ext)


# --------------------------------------------------------------------------- propagator
def _evolve(g: ShotGrid, p0: np.ndarray, times: np.ndarray, tau: float,
            source: Callable[[float], np.ndarray] | None = None) -> np.ndarray:
    """``p(t)`` of ``dp/dt = L p + s(t)`` at each of ``times`` by Crank-Nicolson on the banded
    form ``N dp/dt = (N L) p + N s`` (one sparse LU per step size; every step is a cheap banded
    solve), started with two implicit-Euler half steps (Rannacher) so that the stiff
    components of an initial delta are damped, not left oscillating.  Step
    ``min(t_max/400, tau_m/100)``: time error O(dt^2), below the space error (tests compare
    with the OU-shot closed form and with ``expm_multiply`` on a small grid)."""
    A = g.banded_L().tocsc()
    n = g.n
    N = g.premultiplier if g.premultiplier is not None else sparse.identity(n, format="csc")
    t_max = float(times.max())
    dt = min(t_max / 400.0, tau / 100.0)
    cache: dict[tuple[str, float], _Solve] = {}
    zero = np.zeros(n)

    def src(t: float) -> np.ndarray:
        return zero if source is None else source(t)

    def lu(kind: str, step: float) -> _Solve:
        key = (kind, round(step / dt, 12))
        if key not in cache:
            M = (N - step * A) if kind == "be" else (N - 0.5 * step * A)
            # N - c A is M-matrix-like and diagonally dominant: diagonal pivots are stable,
            # and the ordering of _factor keeps the LU nearly banded (12 ms -> ~0.1 ms per
            # solve at 1500 states)
            cache[key] = _factor(M)
        return cache[key]

    order = np.argsort(times, kind="stable")
    out = np.empty((times.size, n))
    p, t_now, started = p0.astype(float), 0.0, False
    for k in order:
        target = float(times[k])
        while t_now < target - 1e-14 * t_max:
            step = min(dt, target - t_now)
            if not started:
                half = 0.5 * step
                for j in range(2):
                    p = lu("be", half)(N @ (p + half * src(t_now + (j + 1) * half)))
                started = True
            else:
                rhs = N @ (p + 0.5 * step * (src(t_now) + src(t_now + step))) + 0.5 * step * (A @ p)
                p = lu("cn", step)(rhs)
            t_now += step
        out[k] = p
    return out


def unkicked(model: Model, t: ArrayLike, v0: float) -> tuple[np.ndarray, np.ndarray]:
    """Pure shot noise: the mass ``e^{-rate t}`` not yet kicked sits on the noise-free path
    ``v_det(t)`` (an atom that moves; at 0 once the path sticks).  Returns ``(v_det, mass)``."""
    if model.shot is None:
        raise ValueError("unkicked needs a shot-noise model (shot is None)")
    t = np.atleast_1d(np.asarray(t, dtype=float))
    return np.asarray(model.deterministic(float(v0), t)), np.exp(-model.shot.rate * t)


def _propagate(model: Model, v0: float, times: np.ndarray, h: float | None,
               once: bool = False) -> tuple[ShotGrid, np.ndarray, np.ndarray | None]:
    """Grid, state probabilities at ``times`` and (pure shot noise with ``once``) the grid's
    own once-kicked part of them.  With gamma = inf and shot noise the unkicked mass
    (:func:`unkicked`) is kept out of the grid: the grid carries only the mass kicked at least
    once, fed by the exact source ``rate e^{-rate t} landing(v_det(t))``; this avoids smearing
    a moving delta with the upwind scheme.  The once-kicked part is the same source evolved
    without further kicks (``dp1/dt = (drift - rate) p1 + source``): the caller replaces it by
    :func:`_once_kicked`, its exact density, whose jump at the front the grid smears."""
    g = shot_generator(model, h, v0s=(v0,))
    if not model.noise_kind.pure_kicks:
        out = _evolve(g, g.initial(float(v0)), times, model.tau_m)
        return g, np.clip(out, 0.0, None), None
    lam = model.noise_kind.shot.rate
    # the noise-free path once on a fine time grid (one ODE solve for the smooth law), then
    # interpolated: the source is evaluated at every half step
    tg = np.linspace(0.0, float(times.max()), 20001)
    vg = np.asarray(model.deterministic(float(v0), tg))

    memo: dict[float, np.ndarray] = {}  # both evolutions below step through the same times

    def source(t: float) -> np.ndarray:
        if t not in memo:
            vd = float(np.interp(t, tg, vg))
            memo[t] = lam * math.exp(-lam * t) * g.landing(vd)
        return memo[t]
    out = _evolve(g, np.zeros(g.n), times, model.tau_m, source)
    p1 = None
    if once:
        drift_only = dataclasses.replace(g, base=(g.base - lam * sparse.identity(g.n)).tocsc(),
                                         shot=None, kicks=None, col_s=None)
        p1 = _evolve(drift_only, np.zeros(g.n), times, model.tau_m, source)
    return g, out, p1


def _once_kicked(model: Model, v: np.ndarray, times: np.ndarray, v0: float,
                 span: tuple[float, float], nodes: int = 16) -> np.ndarray:
    """Density (times x points) of the mass kicked exactly once, pure shot noise (gamma = inf),
    by quadrature over the kick time s:

        p1(v, t) = rate e^{-rate t} / |f(v)| int_0^t rho(u_s - v_det(s)) |f(u_s)| ds,

    ``u_s`` the velocity that the noise-free flow takes to v in the time t - s (it is kicked
    from ``v_det(s)`` to ``u_s``, then flows to v; ``|du_s/dv| = f(u_s)/f(v)``, Liouville),
    rho the kick-size density, ``e^{-rate t}`` no kick before s nor after.  Flows and inverse
    flows from :class:`analogue.theory.flow_table.FlowTable` (~1e-9).  Gauss-Legendre on
    4 panels of ``nodes`` points between the breakpoints 0, the time v_det reaches v = 0,
    the time u_s leaves it (slip) and t, where the integrand is smooth (16 against 32 nodes,
    on the grid's span: 6e-15 of the peak one-sided and Stribeck, 1e-10 two-sided slip, 2e-7
    cubic; against the OU-shot closed form 8e-10).  This part carries the jump of the density at the front
    v_det(t) (one-sided kicks: from 0 below to its value above) exactly.  A point at v = 0
    is read on the side v > 0 (as :func:`_on_grid` reads it)."""
    shot = model.shot
    assert shot is not None
    lo, hi = span
    tab = flow_table(model, min(lo, v0), max(hi, v0))
    scale = hi - lo
    v = np.where(v == 0.0, 1e-300, np.clip(v, tab.lo, tab.hi))
    fv = np.asarray(model.drift(v), dtype=float)
    # at a zero of the drift (a sliding attractor) the ratio f(u)/f(v) is 0/0: read beside it
    v = np.where(np.abs(fv) < 1e-12, v + 1e-9 * scale, v)
    fv = np.abs(np.asarray(model.drift(v), dtype=float))
    x, wts = np.polynomial.legendre.leggauss(nodes)
    # 4 panels of [0, 1]: nodes and weights (the weights sum to 1)
    starts = np.arange(4) / 4.0
    xs = (starts[:, None] + 0.125 * (x[None, :] + 1.0)).ravel()
    ws = np.tile(0.125 * wts, 4)
    t_kink = tab.time_to_kink(float(v0))
    since = tab.time_from_kink(v)
    kicks = Kicks.of(shot)
    out = np.zeros((times.size, v.size))
    for i, t in enumerate(times):
        bp = np.stack([np.zeros_like(v), np.full_like(v, min(t_kink, t)),
                       np.clip(t - since, 0.0, t), np.full_like(v, t)], axis=1)
        bp[:, 1:3].sort(axis=1)
        total = np.zeros(v.size)
        for k in range(3):
            a, b = bp[:, k], bp[:, k + 1]
            s = a[:, None] + (b - a)[:, None] * xs[None, :]
            u, ok = tab.backward(np.broadcast_to(v[:, None], s.shape), t - s)
            vd = tab.flow(np.full(s.size, float(v0)), s.ravel())[0].reshape(s.shape)
            z = np.where(ok, u - vd, 0.0)
            rho = np.zeros(s.shape)
            for w, sgn, mean in kicks.dirs():
                zz = sgn * z
                rho += np.where(ok & (zz > 0), w / mean * np.exp(-np.maximum(zz, 0.0) / mean), 0.0)
            fu = np.abs(np.asarray(model.drift(np.where(ok, u, 1.0)), dtype=float))
            total += (b - a) * np.sum(rho * fu * ws[None, :], axis=1)
        out[i] = shot.rate * math.exp(-shot.rate * t) * total / fv
    return out


def _times(t: ArrayLike, t0: float) -> tuple[np.ndarray, np.ndarray]:
    t_arr = np.asarray(t, dtype=float)
    if t_arr.ndim > 1:
        raise ValueError(f"t must be a number or a 1-D array, got shape {t_arr.shape}")
    el = np.atleast_1d(t_arr) - float(t0)
    if el.size == 0 or not np.all(np.isfinite(el)) or np.any(el <= 0):
        raise ValueError("t must be finite and > t0 (at t = t0 the density is a delta)")
    return t_arr, el


def _pure_shot(model: Model) -> bool:
    return model.noise_kind.pure_kicks


def _on_grid(model: Model, flat: np.ndarray, el: np.ndarray, v0: float, h: float,
             once: bool = False) -> tuple[np.ndarray, np.ndarray, ShotGrid]:
    """(density at ``flat`` (times x points), atom (times), grid) on one grid; with ``once``
    (pure shot noise) the density without the grid's once-kicked part."""
    g, probs, p1 = _propagate(model, float(v0), el, h, once)
    if p1 is not None:
        probs = probs - p1  # the mass kicked twice or more (its atom: all of the grid's)
    dens, atom = g.weights_to_density(probs)
    centres = g.v[:-1] if g.atom else g.v
    out = np.zeros((el.size, flat.size))
    for i in range(el.size):
        if g.nodal:
            out[i] = np.interp(flat, centres, dens[i], left=0.0, right=0.0)
            continue
        # cells: interpolate on each side of the edge v = 0 separately (kink / atom there)
        neg, pos = centres < 0, centres > 0
        lo = np.interp(flat, centres[neg], dens[i][neg], left=0.0, right=dens[i][neg][-1])
        hi = np.interp(flat, centres[pos], dens[i][pos], left=dens[i][pos][0], right=0.0)
        out[i] = np.where(flat < 0, lo, hi)
        out[i][(flat < centres[0] - g.h / 2) | (flat > centres[-1] + g.h / 2)] = 0.0
    return out, np.asarray(atom, dtype=float), g


def _richardson_pair(model: Model, flat: np.ndarray, el: np.ndarray, v0: float,
                     h: float | None, density: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Density at ``flat`` and atom, grids h and h/2 Richardson-combined.  Pure shot noise
    with ``density``: the grids carry the mass kicked twice or more, whose density is
    continuous at the front, and :func:`_once_kicked` adds the rest exactly."""
    if h is None:
        h = default_spacing(model)
    once = density and _pure_shot(model)
    fc, ac, g = _on_grid(model, flat, el, v0, h, once)
    ff, af, _ = _on_grid(model, flat, el, v0, h / 2.0, once)
    w = 2.0 ** (2.0 if math.isfinite(model.gamma) else 1.0)
    dens = (w * ff - fc) / (w - 1.0)
    if once:
        centres = g.v[:-1] if g.atom else g.v
        span = (float(centres[0] - g.h / 2), float(centres[-1] + g.h / 2))
        inside = (flat >= span[0]) & (flat <= span[1])
        dens[:, inside] += _once_kicked(model, flat[inside], el, v0, span)
        if model.noise_kind.one_sided:
            # kicks only push up and the flow keeps the order of velocities: every kicked
            # path lies above the unkicked one, so nothing is below the front (the grid's
            # twice-kicked part leaked 7e-4 of density into the bin of 0.02 below it)
            front = np.asarray(model.deterministic(float(v0), el))
            dens[flat[None, :] < front[:, None]] = 0.0
    return dens, (w * af - ac) / (w - 1.0)


def propagator(model: Model, v: ArrayLike, t: ArrayLike, v0: float, t0: float = 0.0, *,
               h: float | None = None) -> np.ndarray:
    """Density of the continuous part of ``f(v, t | v0, t0)`` for a 1-D member (the atom at 0,
    present for pure shot noise, is :func:`propagator_atom`; with pure shot noise the mass
    ``e^{-rate t}`` never kicked is a moving atom on the noise-free path, :func:`unkicked`,
    and not in this density).  Shapes as :func:`analogue.theory.exact.propagator`.  Grids h
    and h/2 Richardson-combined (first-order cells for pure shot noise, second-order nodes
    with Gaussian noise); time by Crank-Nicolson (:func:`_evolve`).  Negative round-off after
    extrapolation is clipped.

    Pure shot noise: the density jumps at the front ``v_det(t)`` of the unkicked paths (with
    one-sided kicks it is 0 below the front and positive above; two-sided kicks give a jump
    or a kink there).  The mass kicked exactly once carries that jump and is computed by
    quadrature along the flow (:func:`_once_kicked`, ~1e-9); the grids carry only the mass
    kicked twice or more, continuous at the front.  Against event-driven Monte Carlo (exact
    between kicks, 10^6 replicas, bins of 0.02 beside the front at t = 0.3, circuits/shot.toml
    from v0 = 1; also two-sided, Stribeck and cubic members): |z| <= 2.3 in every bin,
    density exactly 0 below the front with one-sided kicks (the grid alone: 0.16 there, z
    -56 and +38 on either side of the front; cubic -84 and +66).  Elsewhere the twice-kicked
    part carries the first-order grid error, Richardson-combined.
    """
    check_one_dimensional(model)
    v = np.asarray(v, dtype=float)
    if not np.all(np.isfinite(v)):
        raise ValueError("v must be finite")
    t_arr, el = _times(t, t0)
    dens, _ = _richardson_pair(model, v.ravel(), el, v0, h)
    out = np.clip(dens, 0.0, None).reshape((el.size,) + v.shape)
    res: np.ndarray = out[0] if t_arr.ndim == 0 else out
    return res


def propagator_atom(model: Model, t: ArrayLike, v0: float, t0: float = 0.0, *,
                    h: float | None = None) -> float | np.ndarray:
    """``P(v(t) = 0 | v0, t0)``: the mass of the atom at 0 (0 unless pure shot noise in the
    stick regime); grids h and h/2 Richardson-combined."""
    check_one_dimensional(model)
    t_arr, el = _times(t, t0)
    _, atom = _richardson_pair(model, np.zeros(1), el, v0, h, density=False)
    if model.noise_kind.pure_kicks:
        vd, mass = unkicked(model, el, v0)
        atom = atom + np.where(vd == 0.0, mass, 0.0)
    atom = np.clip(atom, 0.0, 1.0)  # Richardson round-off near 0
    return float(atom[0]) if t_arr.ndim == 0 else atom


def autocorrelation(model: Model, lags: ArrayLike, h: float | None = None) -> np.ndarray:
    """Connected stationary velocity autocorrelation ``C(t) = sum_i (v_i - m) [e^{L t}
    ((v - m) p_s)]_i`` of a 1-D member at ``|lags|`` (the same generator and Crank-Nicolson
    evolution as :func:`propagator`; grids h and h/2 Richardson-combined).  ``C(0)`` is the
    grid variance."""
    check_one_dimensional(model)
    lags = np.asarray(lags, dtype=float)
    if not np.all(np.isfinite(lags)):
        raise ValueError("lags must be finite")
    flat = np.abs(lags.ravel())
    if h is None:
        h = default_spacing(model)
    vals = []
    for hh in (h, h / 2.0):
        g = shot_generator(model, hh)
        p = _solve_stationary(g, model)
        dv = g.v - np.dot(g.v, p)
        out = np.full(flat.size, float(np.dot(dv * dv, p)))
        pos = flat > 0
        if pos.any():
            y = _evolve(g, dv * p, flat[pos], model.tau_m)
            out[pos] = y @ dv
        vals.append(out)
    w = 2.0 ** (2.0 if math.isfinite(model.gamma) else 1.0)
    out_c: np.ndarray = ((w * vals[1] - vals[0]) / (w - 1.0)).reshape(lags.shape)
    return out_c


# ------------------------------------------------------------------ work large deviations
def _force(model: Model) -> float:
    if model.force == 0:
        raise ValueError("a must be != 0: for a == 0 the work W = m a int v vanishes identically")
    return model.force


def _principal(g: ShotGrid, pot: np.ndarray, guess: float, scale: float) -> float:
    """Perron root of the Metzler matrix ``L + diag(pot)`` (``pot = k F v``: the tilted
    generator) by inverse iteration with a shift ``sigma`` above it: for real
    sigma > lambda_max every other eigenvalue is farther from sigma
    (|sigma - lambda_2| >= sigma - Re lambda_2 > sigma - lambda_max), so the iteration
    converges to the Perron root; ``(sigma - L_k)^{-1}`` is applied through the banded form
    ``N (sigma - L_k)`` (one sparse LU).

    The root is bracketed: L conserves mass (columns sum to 0), so it is at most ``max pot``,
    and at least the largest diagonal entry, ``>= max(pot + diag(base) - rate)``.  The shift
    starts at ``min(guess + scale, max pot)`` (just above), is raised when the limit is not a
    nonnegative vector below sigma, and moved towards the estimate when 300 iterations do not
    converge (a shift far above the root converges slowly: circuits/shot.toml at k = -1000
    started 6500 above it and returned -11.4, below the bound -rate = -1)."""
    n = g.n
    N = g.premultiplier if g.premultiplier is not None else sparse.identity(n, format="csc")
    NLk = (g.banded_L() + N @ sparse.diags(pot)).tocsc()
    rate = g._kicks.rate if (g.shot is not None or g.kicks is not None) else 0.0
    upper = float(pot.max())
    lower = float(np.max(pot + g.base.diagonal() - rate))
    # the shift's least distance above the root: the solves near singularity carry round-off
    # ~2e-8 (a constant potential on 1.8e5 states: the root is max pot exactly, the estimate
    # came out 2.6e-8 above it), so 1e-6 of the scale, not less
    tiny = 1e-6 * max(1.0, abs(upper), upper - lower)
    sigma = max(min(guess + scale, upper + tiny), lower + tiny)
    for _ in range(24):
        solve = _factor(sigma * N - NLk)
        x = np.ones(n) / n
        lam, converged = sigma, False
        for _ in range(300):
            y = solve(N @ x)
            ratio = y.sum() / x.sum()
            lam_new = sigma - 1.0 / ratio
            x = y / y.sum()
            if abs(lam_new - lam) <= 1e-13 * max(1.0, abs(lam_new), scale):
                lam, converged = lam_new, True
                break
            lam = lam_new
        valid = lower - tiny <= lam < sigma and x.min() >= -1e-10 * x.max()
        if converged and valid:
            return float(lam)
        if valid:  # slow: the shift is far above the root; move it towards the estimate
            sigma = max(lam + 0.1 * (sigma - lam), lower + tiny)
        else:  # the shift is below the root: raise it (never above the bound)
            sigma = min(sigma + max(4.0 * (sigma - lower), scale), upper + tiny)
    raise RuntimeError(f"inverse iteration for the SCGF (shift {guess:g}) did not converge")


def _principal_gradient(model: Model, h: float, k: float, F: float) -> float:
    # the tilted ground state sits near tau_m (2 k F tau_m/gamma + a): widen by that shift
    lo, hi = _gaussian_range(model)
    shift = 4.0 * abs(k * F) * model.tau_m ** 2 / model.gamma
    grid = Grid.span(lo - shift, hi + shift, h)
    diag, off, _ = symmetric_generator(model, grid)
    lam = eigh_tridiagonal(diag + k * F * grid.v, off, select="i",
                           select_range=(grid.n - 1, grid.n - 1), eigvals_only=True)
    return float(lam[0])


def scgf_domain(model: Model) -> tuple[float, float]:
    """The open interval ``(k_lo, k_hi)`` of k where the SCGF is finite (+inf outside).

    With shot noise and no cubic term a kick z adds ``tau_m z`` (up to terms growing at most
    like ln z) to ``int v``, so ``E exp(k W)`` involves the kicks' moment generating function
    ``M(c) = E e^{c z}`` at ``c = k F tau_m``: ``1/(1 - c mean)`` one-sided, ``1/(1 - c^2
    mean^2)`` two-sided, finite only for ``c mean < 1`` (and ``|c| mean < 1``).  Exactly: with
    ``phi = e^{c v} psi`` the tilted adjoint generator becomes a generator with kicks of rate
    ``rate M(c)`` plus the potential ``rate (M(c) - 1) + c (f(v) + v/tau_m) + c^2/gamma``
    (:func:`_kick_transform`), and ``f + v/tau_m = a - Delta(v) sgn v`` is bounded, so
    ``lambda(k) = rate (M(c) - 1) + O(1)`` diverges at the pole ``c mean = 1``: the SCGF is
    steep there, and the rate function is finite for every w, convex and asymptotically linear
    with slope ``k_pole = 1/(F tau_m mean)`` (:func:`rate_function_asymptote`).
    With ``cubic > 0`` a kick's displacement ``int v dv/|f(v)|`` is bounded, and the domain is
    the whole line; Gaussian-only members have the whole line too."""
    check_one_dimensional(model)
    F = _force(model)
    if model.friction.bounded_kick_displacement:
        return -math.inf, math.inf
    return model.noise_kind.work_domain(F * model.tau_m)


def _kick_transform(model: Model, c: float) -> tuple[Model, float]:
    """The exponential change of measure of the kicks at ``c = k F tau_m`` (one-sided,
    ``0 < c mean < 1``): ``phi(v) = e^{c v} psi(v)`` turns ``(L^dagger + k F v) phi = lambda phi``
    into ``(L'^dagger + V) psi = lambda psi``, L' the generator of the same member with kicks of
    rate ``rate/u`` and mean ``mean/u`` (``u = 1 - c mean``; the tilted jump law
    ``rho(z) e^{c z}/M(c)`` is again exponential), drift ``f + 2c/gamma``, and the potential
    ``V = rate (1/u - 1) + c (f(v) + v/tau_m) + c^2/gamma`` (``k F = c/tau_m``; V = rate (1/u - 1)
    in the stuck state, where f = 0 and v = 0).  Returns (the member of L', the constant
    ``rate (1/u - 1) + c^2/gamma``).  The transformed law lives where the tilted one does (out
    to ``~ tau_m rate mean/u^2``), and its default grid scales with ``mean/u``: the grid
    follows the pole instead of truncating the tilted law's tail (which made the grid's
    lambda(k) non-convex near the pole: 5.11, 4.97, 5.99 for k w - lambda at k = 7, 7.5, 8 for
    circuits/shot.toml, w = 1)."""
    shot = model.shot
    assert shot is not None and not shot.two_sided
    u = 1.0 - c * shot.mean
    const = shot.rate * (1.0 / u - 1.0)
    changes: dict[str, object] = {"shot": ShotNoise(shot.rate / u, shot.mean / u)}
    if math.isfinite(model.gamma):
        changes["a"] = model.a + 2.0 * c / model.gamma
        const += c * c / model.gamma
    return model.replace(**changes), const


def _two_sided_transform(model: Model, c: float) -> tuple[Model, Kicks, float]:
    """:func:`_kick_transform` for two-sided kicks (``|c| mean < 1``): the tilted jump law
    ``rho(z) e^{c z}/M(c)``, ``M(c) = 1/((1 - c mean)(1 + c mean))``, is up with probability
    ``(1 + c mean)/2`` and mean ``mean/(1 - c mean)``, down with ``(1 - c mean)/2`` and mean
    ``mean/(1 + c mean)``, at rate ``rate M(c)``; constant ``rate (M(c) - 1) + c^2/gamma``."""
    shot = model.shot
    assert shot is not None and shot.two_sided
    up, down = 1.0 - c * shot.mean, 1.0 + c * shot.mean
    M = 1.0 / (up * down)
    kicks = Kicks(shot.rate * M, 0.5 * down, shot.mean / up, 0.5 * up, shot.mean / down)
    const = shot.rate * (M - 1.0)
    tm = model
    if math.isfinite(model.gamma):
        tm = model.replace(a=model.a + 2.0 * c / model.gamma)
        const += c * c / model.gamma
    return tm, kicks, const


def _potential(model: Model, g: ShotGrid, c: float, const: float) -> np.ndarray:
    """``V`` of :func:`_kick_transform` on the states of ``g`` (model: the original member)."""
    pot = const + c * (model.drift(g.v) + g.v / model.tau_m)
    if g.atom:
        pot[-1] = const  # stuck: f = 0, v = 0
    return np.asarray(pot, dtype=float)


def _recurrent_only(model: Model, g: ShotGrid, pot: np.ndarray) -> np.ndarray:
    """``pot`` with the transient states pushed far below: with one-sided pure shot noise the
    states below ``v_edge`` (:func:`work_edge`) are transient, and since nothing flows back to
    them the tilted generator is block triangular, its spectrum the union of the two blocks'.
    The SCGF (from any recurrent start) is the recurrent block's Perron root, but the
    transient block's can be larger (Delta = 0, a tau_m = 0.5, k F = -300: cells below 0.5
    carry k F v ~ 0 against lambda = -152), so that block is moved out of the way."""
    edge = work_edge(model)
    if edge is None:
        return pot
    v_edge = edge / _force(model)
    cells = g.v[:-1] if g.atom else g.v
    transient = np.r_[cells + 0.5 * g.h <= v_edge + 1e-9 * g.h, [v_edge > 0]] if g.atom \
        else cells + 0.5 * g.h <= v_edge + 1e-9 * g.h
    if not transient.any():
        return pot
    spread = float(np.abs(pot).max()) + 10.0 * float(np.abs(g.base.diagonal()).max())
    out: np.ndarray = np.where(transient, float(pot.min()) - spread - 1.0, pot)
    return out


class _Scgf:
    """lambda(k) of one member on the grids h and h/2 (built once), Richardson-combined.
    With one-sided kicks and ``k F > 0`` on the grids of the kick-transformed member
    (:func:`_kick_transform`, built per k); beyond the pole ``+inf``."""

    def __init__(self, model: Model, h: float):
        self.model, self.h = model, h
        self.F = _force(model)
        self.domain = scgf_domain(model)
        self.kicks = model.noise_kind.exact_solver == "kolmogorov-feller"
        if self.kicks:
            self.fine = (shot_generator(model, h), shot_generator(model, h / 2.0))
            self.order = 2.0 if math.isfinite(model.gamma) else 1.0
            mom = _grid_moments(model, h)
            self.mean_w = self.F * mom[0]
            self.curv = self.F**2 * max(mom[6], 0.0)
            self.sd = math.sqrt(max(mom[1] - mom[0] ** 2, 0.0))

    def __call__(self, k: float) -> float:
        model, h, F = self.model, self.h, self.F
        if not self.domain[0] < k < self.domain[1]:
            return math.inf
        if not self.kicks:
            a = _principal_gradient(model, h, k, F)
            b = _principal_gradient(model, h / 2.0, k, F)
            return (4.0 * b - a) / 3.0
        w: float = 2.0**self.order
        c = k * F * model.tau_m
        # the change of measure for every k it is valid for but pure one-sided shot noise at
        # k F < 0, whose transformed kicks shrink to nothing (mean/u, u -> inf): that side
        # keeps the tilted generator with the transient states moved away
        noise = model.noise_kind
        if (not model.friction.bounded_kick_displacement and c != 0
                and (c > 0 or not (noise.one_sided and noise.pure_kicks))):
            return self._transformed(c, w)
        # start the shift from the Gaussian approximation k <w> + k^2 F^2 D_x (a wrong start
        # only costs retries: :func:`_principal` checks what it converged to)
        guess = k * self.mean_w + k * k * self.curv
        scale = 0.1 * abs(guess) + 0.1 * (abs(k * F) * self.sd + 1.0 / model.tau_m)
        a, b = (_principal(g, _recurrent_only(model, g, k * F * g.v), guess, scale)
                for g in self.fine)
        return (w * b - a) / (w - 1.0)

    def _transformed(self, c: float, w: float) -> float:
        model = self.model
        kicks: Kicks | None = None
        if not model.noise_kind.one_sided:  # (kicks here: two-sided)
            tm, kicks, const = _two_sided_transform(model, c)
            # symmetric stand-ins: the smaller mean sets the spacing, the larger the range,
            # widened by the transformed kicks' mean force
            means = (kicks.mean_up, kicks.mean_down)
            spacing = tm.replace(shot=ShotNoise(kicks.rate, min(means), True))
            lo, hi = _grid_range(tm.replace(shot=ShotNoise(kicks.rate, max(means), True)))
            shift = model.tau_m * kicks.rate * (kicks.w_up * kicks.mean_up
                                                - kicks.w_down * kicks.mean_down)
            lo, hi = lo + min(shift, 0.0), hi + max(shift, 0.0)
        else:
            tm, const = _kick_transform(model, c)
            spacing = tm
            lo, hi = _grid_range(tm)
        # the transformed member's default spacing (it grows with mean/u, as the law's width
        # does), refined as the caller refined h.  Aligned with the attractor (as the default
        # grid is) unless that would refine it more than twofold: near the pole the spacing
        # grows past |v*| (Delta = 0, a tau_m = 0.5, 1/u = 1000: 12 -> 0.5, 1.5e6 states), and
        # the transformed law lives far above v* there
        raw, aligned = default_spacing(spacing, align=False), default_spacing(spacing)
        ht = (aligned if aligned >= 0.5 * raw else raw) * self.h / default_spacing(model)
        # one-sided: the law reaches ~tau_m rate mean/u^2, the spacing grows like mean/u: the
        # states grow like 25 rate tau_m/u (two-sided: the down kicks keep the spacing near
        # mean/50, the states grow like 1/u^2).  Beyond 1.5e5 states the spacing is coarsened:
        # one-sided, the transformed law then lives so far above v = 0 that
        # lambda - rate (1/u - 1) = c (a - Delta) to 1e-8 already at u = 0.2 (circuits/shot.toml)
        ht = max(ht, (hi - lo) / 150_000.0)
        vals = []
        for hh in (ht, ht / 2.0):
            g = shot_generator(tm, hh, kicks=kicks, span=(lo, hi))
            pot = _recurrent_only(model, g, _potential(model, g, c, const))
            # lambda <= max V (L is a generator); start just above it
            top, spread = float(pot.max()), float(pot.max() - pot.min())
            vals.append(_principal(g, pot, top, 1e-3 * spread + 0.1 / model.tau_m))
        return (w * vals[1] - vals[0]) / (w - 1.0)


def rate_function_asymptote(model: Model) -> tuple[float, float]:
    """``(k_pole, rate)`` of the large-w branch of the rate function with one-sided kicks
    (cubic = 0): near the pole ``lambda(k) = rate k_pole/(k_pole - k) + O(1)``, so
    ``J(w) = k_pole w - 2 sqrt(rate k_pole w) + O(1)`` as ``k_pole w -> +inf``: asymptotically
    linear with slope ``k_pole = 1/(F tau_m mean)``, the pole of :func:`scgf_domain` (no exactly
    linear branch: lambda is steep, +inf at the pole, so the Legendre maximiser is interior for
    every w).  For Delta = 0 exactly ``J(w) = (sqrt(B) - sqrt(rate))^2``,
    ``B = (w - F a tau_m) k_pole`` (pure shot noise)."""
    check_one_dimensional(model)
    noise = model.noise_kind
    if not noise.one_sided or model.friction.bounded_kick_displacement:
        raise ValueError("rate_function_asymptote needs one-sided shot noise and cubic = 0 "
                         "(otherwise the SCGF has no pole)")
    return 1.0 / (_force(model) * model.tau_m * noise.shot.mean), noise.shot.rate


def _scgf_one(model: Model, k: float, h: float) -> float:
    return _Scgf(model, h)(k)


def scgf(model: Model, k: ArrayLike, *, h: float | None = None) -> np.ndarray:
    """SCGF ``lambda(k) = lim (1/tau) ln E exp(k W_tau)`` of a 1-D member (vectorised in k)."""
    check_one_dimensional(model)
    _force(model)
    k = np.asarray(k, dtype=float)
    if not np.all(np.isfinite(k)):
        raise ValueError("k must be finite")
    if h is None:
        h = default_spacing(model)
    solver = _Scgf(model, h)
    return np.array([solver(float(kk)) for kk in k.ravel()]).reshape(k.shape)


def work_edge(model: Model) -> float | None:
    """The edge ``F v_edge`` of the work rate's support with one-sided pure shot noise, None
    otherwise.  Kicks only push up and the flow from above ends at the highest attractor
    ``v_edge`` (a sliding zero of the drift, or the stuck state 0), so the recurrent velocities
    are ``>= v_edge`` and ``W/tau`` lies on one side of ``F v_edge``.  At the edge
    ``lambda(k) - k F v_edge -> -rate`` as ``k F -> -inf`` (``E e^{c z} -> 0``), so the rate
    function there is ``rate`` (no kick at all), and +inf beyond (Delta = 0: the closed form
    ``(sqrt(B) - sqrt(rate))^2`` at ``B = 0``)."""
    check_one_dimensional(model)
    noise = model.noise_kind
    if not (noise.one_sided and noise.pure_kicks):
        return None
    cands = [float(z) for z in stable_zeros(model)] + ([0.0] if has_atom(model) else [])
    v_edge = max(cands) if cands else float(model.attractor)
    return _force(model) * v_edge


def rate_function(model: Model, w: ArrayLike, *, h: float | None = None) -> np.ndarray:
    """Rate function of the work rate w (module docstring for the scaling), by the Legendre
    transform of :func:`scgf`, maximising the concave ``k w - lambda(k)`` over k in
    :func:`scgf_domain` (with one-sided kicks the SCGF is steep at its pole, so this is finite
    for every large w and asymptotically linear, :func:`rate_function_asymptote`; at the other
    edge of the support, :func:`work_edge`, it is ``rate``, +inf beyond).  NaN where
    no maximiser is found for |k| up to 2^40 times the Gaussian guess (w at or beyond the
    edge of the work's support)."""
    check_one_dimensional(model)
    F = _force(model)
    w = np.asarray(w, dtype=float)
    if not np.all(np.isfinite(w)):
        raise ValueError("w must be finite")
    if h is None:
        h = default_spacing(model)
    scale = model.gamma if math.isfinite(model.gamma) else 1.0
    mom = stationary_moments(model)
    mean = F * mom.mean
    # Gaussian guess lambda(k) ~ k <w> + k^2 F^2 D_x: the maximiser is near (w - <w>)/(2 F^2 D_x)
    curv = 2.0 * F * F * max(mom.diffusion, 1e-12)
    solver = _Scgf(model, h)
    edge = work_edge(model)
    out = np.empty(w.size)
    for i, wi in enumerate(w.ravel()):
        if wi == mean:
            out[i] = 0.0
            continue
        if edge is not None and F * (wi - edge) <= 0.0:
            # at the edge: no kick for the whole time (probability e^{-rate tau}); beyond: none
            out[i] = model.shot.rate / scale if wi == edge else math.inf  # type: ignore[union-attr]
            continue
        def obj(kk: float, wi: float = float(wi)) -> float:  # convex in k
            return -(kk * wi - float(solver(kk)))
        k0 = (wi - mean) / curv
        # bracket the minimum of the convex objective by doubling (one solve per step), then
        # one bounded search.  At the edge of the work's support (w = 0 with one-sided shot
        # noise) the minimiser runs to |k| -> inf, where the grid's lambda(k) is not resolved
        # (lambda(-1e4) = -1497 for circuits/shot.toml, below its bound -rate = -1): NaN, not
        # a number from there.  Towards the pole of the SCGF (:func:`scgf_domain`) the
        # bracket halves the distance to the pole instead of doubling k
        lo_d, hi_d = solver.domain

        def further(p: float) -> float:
            # double p, or go half way to the edge of the SCGF's domain (the pole) if that is
            # nearer: lambda is steep there, so the maximiser is interior for every w
            q = 2.0 * p
            if q >= hi_d:
                q = p + 0.5 * (hi_d - p)
            elif q <= lo_d:
                q = p + 0.5 * (lo_d - p)
            return q
        p0, p1 = 0.0, further(k0)
        f1 = obj(p1)
        # the Gaussian guess can overshoot (circuits/shot.toml, w = 1: 2 k0 = 143, pole 10):
        # halve until the objective is below its value at k = 0
        f0 = obj(0.0)
        for _ in range(40):
            if f1 < f0:
                break
            p1 *= 0.5
            f1 = obj(p1)
        for _ in range(40):
            p2 = further(p1)
            f2 = obj(p2)
            if not f2 < f1:
                break
            p0, p1, f1 = p1, p2, f2
        else:
            out[i] = math.nan
            continue
        lo, hi = sorted((p0, p2))
        res = optimize.minimize_scalar(obj, bounds=(lo, hi), method="bounded",
                                       options={"xatol": 1e-7 * max(1.0, abs(hi - lo))})
        out[i] = max(-res.fun, 0.0) / scale
    return out.reshape(w.shape)


# ------------------------------------------------------------------------------- sampling
def sample_stationary(model: Model, size: int | Sequence[int],
                      seed: int | np.random.SeedSequence | np.random.Generator | None = None) -> np.ndarray:
    """Independent draws from the stationary law of a 1-D member.  Gaussian only: inverse of
    the CDF of ``exp(-gamma U)`` tabulated by the trapezoid rule (spacing resolving the width,
    the Stribeck length and the kink); with shot noise: the atom at 0 with probability
    ``p_zero``, else a cell of the grid law (spacing h/2 of the default) and a uniform position
    in it."""
    check_one_dimensional(model)
    rng = np.random.default_rng(seed)
    # (np.ndim, not isinstance: numpy integers and 0-d arrays are scalar sizes too)
    shape = ((int(cast(int, size)),) if np.ndim(size) == 0
             else tuple(int(s) for s in cast("Sequence[int]", size)))
    h = default_spacing(model) / 2.0
    return _ROUTES[model.noise_kind.exact_solver].sample(  # type: ignore[index]
        model, h, shape, rng)


def _sample_fokker_planck(model: Model, h: float, shape: tuple[int, ...],
                          rng: np.random.Generator) -> np.ndarray:
    r = model._support_bound(50.0)
    n = int(min(2_000_000, math.ceil(2 * r / (h / 4.0))))
    v = np.linspace(-r, r, n + 1)
    u = model.gamma * model.potential(v)
    dens = np.exp(-(u - u.min()))
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (dens[1:] + dens[:-1]))])
    cdf /= cdf[-1]
    return np.interp(rng.random(shape), cdf, v)


def _sample_kolmogorov_feller(model: Model, h: float, shape: tuple[int, ...],
                              rng: np.random.Generator) -> np.ndarray:
    g = shot_generator(model, h)
    p = _solve_stationary(g, model)
    idx = rng.choice(g.n, size=shape, p=p)
    v = g.v[idx]
    is_cell = ~(g.atom & (idx == g.n - 1)) if g.atom else np.ones(shape, bool)
    jitter = (rng.random(shape) - 0.5) * g.h
    return np.where(is_cell, v + jitter, v)


class _Route(NamedTuple):
    """One exact solver's stationary law, moments and sampler (issue 20: the route is the
    noise variant's ``exact_solver``, not an attribute test)."""

    law: Callable[[Model, float], _Law]
    moments: Callable[[Model, float], tuple[float, ...]]
    sample: Callable[[Model, float, tuple[int, ...], np.random.Generator], np.ndarray]


_ROUTES: dict[str, _Route] = {
    "fokker-planck": _Route(_law_fokker_planck, _moments_fokker_planck, _sample_fokker_planck),
    "kolmogorov-feller": _Route(_law_kolmogorov_feller, _moments_kolmogorov_feller,
                                _sample_kolmogorov_feller),
}
