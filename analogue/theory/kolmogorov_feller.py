"""Conservative discretisation of the Kolmogorov-Feller (master) equation for shot noise.

With Poissonian kicks (rate ``lambda``, sizes ``z`` of density ``rho``) the velocity law obeys

    dp/dt = -d/dv [f(v) p] + (1/gamma) p'' + lambda [ integral p(v - z) rho(z) dz - p(v) ],

``f`` the force law of :meth:`analogue.Model.drift` (theory.md, "The extensions, in
equations").  Two discretisations, both exactly mass-conserving generators ``dP/dt = L P``:

* **gamma = inf (pure shot noise).**  Cells ``[j h, (j+1) h]`` with ``v = 0`` on a cell *edge*,
  plus, in the stick regime (``|a| <= Delta(0)``, sgn law), a separate state **S = "stuck at
  v = 0"** that carries the atom of the stationary law.  The drift is upwind finite volumes:
  the flux through an edge ``e`` is ``f(e) P_upstream / h``; at the edge ``v = 0`` the one-sided
  values ``f(0+) = a - Delta(0)`` and ``f(0-) = a + Delta(0)`` are used, so the flow into the
  stuck state is exactly the arrival flux ``|f(0+-)| p(0+-)`` of the continuum equation and S
  only empties by kicks (rate lambda).  First order in h: moments are Richardson-extrapolated
  over (h, h/2) by the callers.
* **gamma finite (shot + Gaussian).**  The Scharfetter-Gummel drift-diffusion generator of
  :mod:`analogue.theory.fokker_planck` on nodes (cells centred on nodes), plus the jumps; no
  atom (diffusion leaves 0 at once).

Jumps: the exact **cell-integrated exponential kernel**.  For mass uniform in a cell, a kick of
exponential size (mean ``mu``) lands ``d >= 1`` cells further with probability

    P_d = (mu/h) (e^{h/mu} - 1) (1 - e^{-h/mu}) e^{-d h/mu},   P_0 = 1 - (mu/h)(1 - e^{-h/mu}),

(the P_0 part stays in its cell); from S (a point at the edge 0) it lands in cell ``j >= 0``
with probability ``e^{-j h/mu} - e^{-(j+1) h/mu}``.  Two-sided kicks use each direction with
weight 1/2.  Mass that would leave the grid is put into the outermost cell (conservation).
"""
from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from scipy import optimize, sparse

from ..model import Model, ShotNoise
from .fokker_planck import Grid
from .fokker_planck import generator as sg_generator

__all__ = ["ShotGrid", "shot_generator", "jump_kernel", "has_atom", "premultiplier",
           "stable_zeros", "Kicks"]


@dataclass(frozen=True)
class Kicks:
    """Exponential kicks at total ``rate``: up with probability ``w_up`` and mean ``mean_up``,
    down with ``w_down`` (0: one-sided) and ``mean_down``.  :class:`ShotNoise` is the case
    ``w_up = w_down = 1/2`` with equal means; the exponential change of measure of the SCGF
    (:func:`analogue.theory.family._kick_transform`) makes two-sided kicks asymmetric."""

    rate: float
    w_up: float
    mean_up: float
    w_down: float = 0.0
    mean_down: float = 1.0

    @classmethod
    def of(cls, shot: ShotNoise) -> Kicks:
        if shot.two_sided:
            return cls(shot.rate, 0.5, shot.mean, 0.5, shot.mean)
        return cls(shot.rate, 1.0, shot.mean)

    @property
    def two_sided(self) -> bool:
        return self.w_down > 0

    def dirs(self) -> list[tuple[float, int, float]]:
        """(weight, sign, mean) of each direction."""
        out = [(self.w_up, 1, self.mean_up)]
        if self.two_sided:
            out.append((self.w_down, -1, self.mean_down))
        return out


def _kicks(mean: float, two_sided: bool) -> Kicks:
    return Kicks(1.0, 0.5, mean, 0.5, mean) if two_sided else Kicks(1.0, 1.0, mean)


def premultiplier(mean: float, h: float, n_cells: int, two_sided: bool, extra: int = 0
                  ) -> sparse.csc_matrix:
    """The discrete ``(1 + mu d/dv)`` (one-sided) or ``(1 - mu^2 d^2/dv^2)`` (two-sided): the
    bidiagonal ``N = I - q S`` (S the shift to the next cell, ``q = e^{-h/mu}``), or
    ``(I - q S^T)(I - q S)``.  It maps the geometric (exponential) kernel to a banded one, so
    ``N L`` is banded but for a few rows (the folds at the ends, the stuck state): the
    theory.md ODE reduction done on the grid, which makes sparse LU cheap.  ``extra`` identity
    rows are appended (the stuck state)."""
    return kicks_premultiplier(_kicks(mean, two_sided), h, n_cells, extra)


def kicks_premultiplier(k: Kicks, h: float, n_cells: int, extra: int = 0) -> sparse.csc_matrix:
    """:func:`premultiplier` for :class:`Kicks`: ``(I - q_d S^T)(I - q_u S)``,
    ``q_u = e^{-h/mean_up}``, ``q_d = e^{-h/mean_down}``."""
    S = sparse.diags([np.ones(n_cells - 1)], [-1], shape=(n_cells, n_cells))
    I = sparse.identity(n_cells)
    N = I - math.exp(-h / k.mean_up) * S
    if k.two_sided:
        N = (I - math.exp(-h / k.mean_down) * S.T) @ N
    if extra:
        N = sparse.block_diag([N, sparse.identity(extra)])
    return sparse.csc_matrix(N)


def has_atom(model: Model) -> bool:
    """True when the stationary law has an atom at v = 0: no Gaussian noise, the exact sgn law,
    and the stick regime ``|a| <= Delta(0)`` (the flow reaches 0 in finite time from both sides
    and stays until the next kick)."""
    return (not math.isfinite(model.gamma) and model.epsilon == 0
            and model.static_friction > 0 and abs(model.a) <= model.static_friction)


@dataclass(frozen=True)
class ShotGrid:
    """Discretisation of one member: velocities ``v`` of the states (cell centres, or nodes;
    with an atom the last state is S at v = 0), spacing ``h``, and the generator split as
    ``L = base + rate (K - I)``: ``base`` the drift(-diffusion) part, K the jump kernel of
    :func:`jump_kernel` (plus the landing column of S)."""

    v: np.ndarray
    h: float
    atom: bool
    nodal: bool  # True: nodes of a Scharfetter-Gummel grid (gamma finite); False: cells (+ S)
    base: sparse.csc_matrix
    shot: ShotNoise | None = None  # the kicks, if any
    col_s: np.ndarray | None = None  # landing distribution of a kick from S (cells)
    kicks: Kicks | None = None  # the kicks' law when not that of ``shot`` (asymmetric)

    @property
    def n_cells(self) -> int:
        return self.v.size - (1 if self.atom else 0)

    @property
    def _kicks(self) -> Kicks:
        if self.kicks is not None:
            return self.kicks
        if self.shot is None:
            raise ValueError("this generator has no shot noise")
        return Kicks.of(self.shot)

    @property
    def L(self) -> sparse.csc_matrix:
        """The explicit generator (dense band of width ~45 mean/h for the jumps)."""
        if self.shot is None:
            return self.base
        n = self.n_cells
        K = kicks_kernel(self._kicks, self.h, n)
        if self.atom:
            assert self.col_s is not None  # an atom comes with its landing column
            K = sparse.bmat([[K, sparse.csc_matrix(self.col_s[:, None])],
                             [sparse.csc_matrix((1, n)), sparse.csc_matrix((1, 1))]])
        return (self.base + self._kicks.rate * (K - sparse.identity(self.v.size))).tocsc()

    @property
    def premultiplier(self) -> sparse.csc_matrix | None:
        if self.shot is None:
            return None
        return kicks_premultiplier(self._kicks, self.h, self.n_cells, int(self.atom))

    def banded_L(self) -> sparse.csc_matrix:
        """``N L`` in closed form (see :func:`banded_jump_kernel`): banded but for a few rows,
        built without ever forming the dense band of L."""
        N = self.premultiplier
        if N is None:
            return self.base
        n = self.n_cells
        NK = banded_kicks_kernel(self._kicks, self.h, n)
        if self.atom:
            Ncol = kicks_premultiplier(self._kicks, self.h, n) @ self.col_s
            Ncol[np.abs(Ncol) < 1e-16] = 0.0
            NK = sparse.bmat([[NK, sparse.csc_matrix(Ncol[:, None])],
                              [sparse.csc_matrix((1, n)), sparse.csc_matrix((1, 1))]])
        return sparse.csc_matrix(N @ self.base + self._kicks.rate * (NK - N))

    @property
    def n(self) -> int:
        return self.v.size

    def weights_to_density(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(continuous density at ``v`` of the cells/nodes, atom mass)."""
        if self.atom:
            return p[..., :-1] / self.h, p[..., -1]
        return p / self.h, np.zeros(p.shape[:-1])

    def landing(self, u: float) -> np.ndarray:
        """Probabilities over the states of the landing point ``u + z`` of one kick from the
        point ``u`` (exact cell integrals of the exponential law; beyond the grid: end cell)."""
        n = self.n_cells
        centres = self.v[:n]
        lo_e, hi_e = centres - 0.5 * self.h, centres + 0.5 * self.h
        out = np.zeros(self.n)
        for w, sgn, mean in self._kicks.dirs():
            a = np.maximum(sgn * (lo_e if sgn > 0 else hi_e) - sgn * u, 0.0)
            b = np.maximum(sgn * (hi_e if sgn > 0 else lo_e) - sgn * u, 0.0)
            cell = np.exp(-a / mean) - np.exp(-b / mean)
            cell = np.clip(cell, 0.0, None)
            out[:n] += w * cell
            out[n - 1 if sgn > 0 else 0] += w * max(0.0, 1.0 - cell.sum())
        return out

    def initial(self, v0: float) -> np.ndarray:
        """Unit mass at ``v0``: the stuck state for v0 == 0 with an atom, else split linearly
        between the two neighbouring states of the same side of 0."""
        p = np.zeros(self.n)
        if self.atom and v0 == 0.0:
            p[-1] = 1.0
            return p
        centres = self.v[:-1] if self.atom else self.v
        if not centres[0] <= v0 <= centres[-1]:
            raise ValueError(f"v0={v0!r} lies outside the grid [{centres[0]}, {centres[-1]}]")
        j = int(np.clip(np.searchsorted(centres, v0) - 1, 0, centres.size - 2))
        theta = (v0 - centres[j]) / (centres[j + 1] - centres[j])
        if not self.nodal and (centres[j] < 0 < centres[j + 1]):
            # do not smear across the edge v = 0 (the kink/atom lives there)
            p[j if v0 < 0 else j + 1] = 1.0
            return p
        p[j], p[j + 1] = 1.0 - theta, theta
        return p


def jump_kernel(mean: float, h: float, n: int, two_sided: bool) -> sparse.csc_matrix:
    """Column-stochastic matrix K (n x n) of the destination cell of one kick from each cell
    (module docstring), mass beyond the ends folded into the end cells (exact geometric sums;
    the band is cut where ``q^d < e^{-45}``, whose mass also goes to the fold)."""
    return kicks_kernel(_kicks(mean, two_sided), h, n)


def kicks_kernel(k: Kicks, h: float, n: int) -> sparse.csc_matrix:
    """:func:`jump_kernel` for :class:`Kicks` (each direction its weight and mean)."""
    i = np.arange(n)
    parts = []
    for w, sign, mean in k.dirs():
        r = h / mean
        dmax = min(n - 1, int(math.ceil(45.0 / r)) + 1)
        d = np.arange(1, dmax + 1)
        c = (math.expm1(r) / r) * (-math.expm1(-r))
        pd = c * np.exp(-d * r)
        p0 = 1.0 - (-math.expm1(-r)) / r
        parts.append(sparse.diags([np.full(n, w * p0)], [0], shape=(n, n)))
        parts.append(sparse.diags([np.full(n - dd, w * pd[dd - 1]) for dd in d],
                                  [-sign * dd for dd in d], shape=(n, n)))
        # whatever of this direction is not on the band goes to the end cell it points to
        lands = np.minimum(n - 1 - i if sign > 0 else i, dmax)
        on_band = c * (np.exp(-r) - np.exp(-(lands + 1) * r)) / (1.0 - np.exp(-r))
        end = np.full(n, n - 1 if sign > 0 else 0)
        parts.append(sparse.csc_matrix((w * ((1.0 - p0) - on_band), (end, i)), shape=(n, n)))
    return sparse.csc_matrix(sum(parts[1:], parts[0]))


def banded_jump_kernel(mean: float, h: float, n: int, two_sided: bool) -> sparse.csc_matrix:
    """``N K`` in closed form, N of :func:`premultiplier`, K the kernel of :func:`jump_kernel`
    with the full (untruncated) geometric band and exact folds (:func:`banded_kicks_kernel`)."""
    return banded_kicks_kernel(_kicks(mean, two_sided), h, n)


def banded_kicks_kernel(k: Kicks, h: float, n: int) -> sparse.csc_matrix:
    """``N K`` in closed form for :class:`Kicks`.  Writing
    ``K = P_0 I + w_u (T_u + e_{n-1} f_u^T) + w_d (T_d^T + e_0 f_d^T)`` with
    ``T_{i+d,i} = c q^d`` per direction (``c = (e^r - 1)(1 - e^{-r})/r``, ``r = h/mean``,
    ``q = e^{-r}``), fold sums ``f_u[i] = c_u q_u^{n-i}/(1-q_u)``,
    ``f_d[i] = c_d q_d^{i+1}/(1-q_d)``, S the shift down and
    ``N = (I - q_d S^T)(I - q_u S) = (I - q_u S)(I - q_d S^T) - q_u q_d (e_{n-1} e_{n-1}^T -
    e_0 e_0^T)``: one-sided ``(I - q_u S) T_u = c_u q_u S``; two-sided
    ``N T_u = c_u q_u (S - q_d S^T S)``,
    ``N T_d^T = c_d q_d (S^T - q_u S S^T) + q_u q_d e_0 (row 0 of T_d^T)``,
    ``N e_{n-1} = e_{n-1} - q_d e_{n-2}``, ``N e_0 = (1 + q_u q_d) e_0 - q_u e_1``."""
    i = np.arange(n)

    def geo(mean: float) -> tuple[float, float, float, float]:
        r = h / mean
        return r, math.exp(-r), (math.expm1(r) / r) * (-math.expm1(-r)), 1.0 - (-math.expm1(-r)) / r
    r_u, q_u, c_u, p0_u = geo(k.mean_up)
    f_u = c_u * np.exp(-(n - i) * r_u) / (1.0 - q_u)
    # The fold rows are dense but decay like q^distance: entries below 1e-17 of the kernel's
    # scale are dropped (a mass error < 1e-17 per column), which keeps the LU banded
    # (36k states: 2.4 s -> 0.05 s per factorisation).
    f_u = np.where(f_u > 1e-17 * c_u, f_u, 0.0)
    N = kicks_premultiplier(k, h, n)
    S = sparse.diags([np.ones(n - 1)], [-1], shape=(n, n))
    if not k.two_sided:
        fold = sparse.csc_matrix((f_u, (np.full(n, n - 1), i)), shape=(n, n))
        return sparse.csc_matrix(p0_u * N + c_u * q_u * S + fold)
    r_d, q_d, c_d, p0_d = geo(k.mean_down)
    f_d = c_d * np.exp(-(i + 1) * r_d) / (1.0 - q_d)
    f_d = np.where(f_d > 1e-17 * c_d, f_d, 0.0)
    d1 = sparse.diags([np.r_[np.ones(n - 1), 0.0]], [0])
    d0 = sparse.diags([np.r_[0.0, np.ones(n - 1)]], [0])
    row0 = np.where(i >= 1, c_d * np.exp(-i * r_d), 0.0) * q_u * q_d
    row0 = np.where(row0 > 1e-17 * c_d, row0, 0.0)
    up = c_u * q_u * (S - q_d * d1) + sparse.csc_matrix(
        (np.r_[f_u, -q_d * f_u], (np.r_[np.full(n, n - 1), np.full(n, n - 2)], np.r_[i, i])),
        shape=(n, n))
    down = (c_d * q_d * (S.T - q_u * d0)
            + sparse.csc_matrix((row0, (np.zeros(n, int), i)), shape=(n, n))
            + sparse.csc_matrix((np.r_[(1 + q_u * q_d) * f_d, -q_u * f_d],
                                 (np.r_[np.zeros(n, int), np.ones(n, int)], np.r_[i, i])),
                                shape=(n, n)))
    p0 = k.w_up * p0_u + k.w_down * p0_d
    return sparse.csc_matrix(p0 * N + k.w_up * up + k.w_down * down)


def _gaussian_range(model: Model, tail: float = 50.0) -> tuple[float, float]:
    """Where ``gamma (U - U_min) < tail`` (scanned on a grid over the bound of
    :meth:`Model._support_bound`, so double wells are covered), widened by 2 % of the span."""
    r = model._support_bound(tail)
    grid = np.linspace(-r, r, 20001)
    u = model.gamma * model.potential(grid)
    inside = np.flatnonzero(u - u.min() < tail)
    lo, hi = grid[max(inside[0] - 1, 0)], grid[min(inside[-1] + 1, grid.size - 1)]
    pad = 0.02 * (hi - lo)
    return lo - pad, hi + pad


def _grid_range(model: Model, v0s: Iterable[float] = ()) -> tuple[float, float]:
    shot = model.shot
    tau = model.tau_m
    if shot is None:
        lo, hi = _gaussian_range(model)
    else:
        lam, mu = shot.rate, shot.mean
        # Stationary excursions: the drift-free reach tau (|a| + lambda mu) plus 45 jump means
        # and 10 standard deviations of the linear-friction (Gamma-like) law, plus the
        # Gaussian reach.
        reach = tau * (abs(model.a) + lam * mu) + 45.0 * mu + 10.0 * math.sqrt(lam * tau) * mu
        if math.isfinite(model.gamma):
            reach += model._support_bound(45.0)
        lo, hi = -reach, reach
        if model.noise_kind.one_sided and model.noise_kind.pure_kicks:
            # one-sided kicks, no diffusion: on v < 0 the drift is >= -v/tau_m + a > 0 below
            # tau_m a, so nothing below min(0, tau_m a) is ever visited (from such starts).
            lo = min(0.0, tau * model.a)
    for v0 in v0s:
        lo, hi = min(lo, float(v0) - 1e-12), max(hi, float(v0) + 1e-12)
    if math.isfinite(model.gamma):  # a start outside: room for its Gaussian spreading
        spread = 10.0 * model.velocity_scale
        lo = min(lo, min((float(v) - spread for v in v0s), default=lo))
        hi = max(hi, max((float(v) + spread for v in v0s), default=hi))
    return lo, hi


def default_spacing(model: Model, align: bool = True) -> float:
    """Spacing resolving the jump mean/25, the Gaussian width/40, the Stribeck length/10 and
    the kink length 1/(gamma (Delta(0) + |a|))/2 (when gamma is finite); for pure shot noise
    refined by :func:`_pure_shot_spacing` (with ``align``, also aligned with the attractor)."""
    scales = [mean / 25.0 for mean in model.noise_kind.jump_scales()]
    if math.isfinite(model.gamma):
        scales.append(math.sqrt(model.tau_m / model.gamma) / 40.0)
        if model.static_friction > 0:
            scales.append(0.5 / (model.gamma * (model.static_friction + abs(model.a))))
    scales.append(model.friction.velocity_length / 10.0)  # Stribeck's v_s (else inf)
    if model.epsilon > 0:
        scales.append(model.epsilon / 8.0)
    h = min(scales)
    if model.noise_kind.pure_kicks:
        h = _pure_shot_spacing(model, h, align)
    return h


def _pure_shot_spacing(model: Model, h: float, align: bool = True) -> float:
    """Pure shot noise (cells): refine and align h with the sliding attractor ``v*``.

    Between kicks the flow runs into ``v*`` (the zero of the drift), so near it the density
    behaves like ``|v - v*|^(rate/|drift'(v*)| - 1)``: integrable but singular when
    ``rate tau_m < 1``.  With ``v*`` inside a cell the upwind error depends on where ``v*``
    falls in it, which changes between h and h/2, so the Richardson step did not cancel it:
    for the Gamma law (Delta = 0, a = -0.3, tau_m = 0.5, rate 0.5, mean 0.3) the mean was off
    by 1.3e-2 standard deviations, P(v > 0) by 8e-4.  With ``v*`` on a cell edge (as v = 0
    already is) the mean error is ~1e-14; resolving the law's width ``mean sqrt(rate tau_m)``
    by 40 cells brings the variance error from 1e-3 to below 1e-4 (measured)."""
    shot = model.shot
    assert shot is not None
    h = min(h, shot.mean * math.sqrt(shot.rate * model.tau_m) / 40.0)
    target = abs(model.attractor)
    if target == 0.0:
        # stuck from rest, but a velocity-weakening law can have a second (sliding) attractor
        # that kicks reach: align with that one (the nearest to 0 if there are several)
        sliding = stable_zeros(model)
        target = float(np.min(np.abs(sliding))) if sliding.size else 0.0
    if align and target > 0.0:
        h = target / math.ceil(target / h)
    return h


def stable_zeros(model: Model) -> np.ndarray:
    """The nonzero stable zeros of the drift (sign change + -> - with increasing v): the
    sliding attractors of the noise-free flow.  Velocity weakening (Stribeck) can add one to
    the stuck state at v = 0 (e.g. tau_m = 5, Delta = 0.3, delta_s = 1, v_s = 0.2, a = 0.6:
    v* = 1.49998, beside the unstable zero 0.39).  All zeros lie in
    ``|v| <= tau_m (|a| + max Delta(v))`` (beyond, -v/tau_m dominates); scanned on 20001
    points of that range, each sign change refined by brentq."""
    top = max(model.delta, model.static_friction)
    r = model.tau_m * (abs(model.a) + top) * 1.01 + 1e-300
    v = np.linspace(-r, r, 20001)
    f = model.drift(v)
    out = []
    for i in np.flatnonzero((f[:-1] > 0) & (f[1:] <= 0)):
        lo, hi = float(v[i]), float(v[i + 1])
        if lo < 0.0 < hi or lo == 0.0 or hi == 0.0:
            continue  # the kink at 0 (stuck), not a sliding attractor
        z = hi if f[i + 1] == 0 else optimize.brentq(lambda x: float(model.drift(x)), lo, hi,
                                                      xtol=1e-15, rtol=1e-15)
        out.append(z)
    return np.asarray(out, dtype=float)


def shot_generator(model: Model, h: float | None = None, v0s: Iterable[float] = (),
                   max_states: int = 400_000, kicks: Kicks | None = None,
                   span: tuple[float, float] | None = None) -> ShotGrid:
    """Generator of the Kolmogorov-Feller equation of ``model`` (module docstring); ``kicks``
    replaces the law of ``model.shot`` (which must be set) and ``span`` the velocity range."""
    if h is None:
        h = default_spacing(model)
    lo, hi = _grid_range(model, v0s) if span is None else span
    shot = model.shot
    if math.isfinite(model.gamma):
        grid = Grid.span(lo, hi, h)
        if grid.n > max_states:
            raise ValueError(f"grid would need {grid.n} states (> {max_states}); pass a coarser h")
        return ShotGrid(grid.v, h, False, True, sg_generator(model, grid).tocsc(), shot,
                        kicks=kicks)
    # gamma = inf: cells [j h, (j+1) h]
    j_lo = min(int(math.floor(lo / h)), -1)
    j_hi = max(int(math.ceil(hi / h)), 1)
    n = j_hi - j_lo
    if n + 1 > max_states:
        raise ValueError(f"grid would need {n + 1} states (> {max_states}); pass a coarser h")
    edges = h * np.arange(j_lo, j_hi + 1, dtype=float)
    centres = 0.5 * (edges[1:] + edges[:-1])
    zero_edge = -j_lo  # edges[zero_edge] == 0: between cell zero_edge-1 and cell zero_edge
    f = model.drift(edges[1:-1])  # interior edges
    up = np.maximum(f, 0.0) / h     # cell e-1 -> cell e  (e = interior edge index 1..n-1)
    down = np.maximum(-f, 0.0) / h  # cell e -> cell e-1
    atom = has_atom(model)
    iz = zero_edge - 1  # index into the interior-edge arrays of the edge v = 0
    if model.epsilon == 0:
        f_plus = model.a - model.static_friction
        f_minus = model.a + model.static_friction
        if atom:
            up[iz] = down[iz] = 0.0
        else:  # slip: flux through 0 from the upstream side
            up[iz] = max(f_minus, 0.0) / h
            down[iz] = max(-f_plus, 0.0) / h
    m = n + (1 if atom else 0)
    rows, cols, vals = [], [], []
    e = np.arange(1, n)
    rows += [e, e - 1]
    cols += [e - 1, e]
    vals += [up, down]
    out = np.zeros(m)
    out[e - 1] += up
    out[e] += down
    if atom:
        s = n
        into_from_above = -(model.a - model.static_friction) / h  # cell zero_edge -> S
        into_from_below = (model.a + model.static_friction) / h   # cell zero_edge-1 -> S
        rows += [np.array([s]), np.array([s])]
        cols += [np.array([zero_edge]), np.array([zero_edge - 1])]
        vals += [np.array([into_from_above]), np.array([into_from_below])]
        out[zero_edge] += into_from_above
        out[zero_edge - 1] += into_from_below
    L = sparse.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                          shape=(m, m)) - sparse.diags(out)
    col_s = None
    if shot is not None and atom:
        # kicks from S: exact landing probabilities from the point v = 0
        col_s = np.zeros(n)
        for w, sgn, mean in (kicks or Kicks.of(shot)).dirs():
            jj = np.arange(n - zero_edge if sgn > 0 else zero_edge)
            land = np.exp(-jj * h / mean) * -math.expm1(-h / mean)
            if sgn > 0:
                col_s[zero_edge:] += w * land
                col_s[-1] += w - w * land.sum()  # beyond the grid: end cell
            else:
                col_s[zero_edge - 1 - jj] += w * land
                col_s[0] += w - w * land.sum()
    v = np.concatenate([centres, [0.0]]) if atom else centres
    return ShotGrid(v, h, atom, False, L.tocsc(), shot, col_s, kicks)
