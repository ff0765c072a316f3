"""Exact finite-noise statistics of the work ``W_tau = F int_0^tau v ds`` (eq. (3)) in the
stationary state: scaled cumulant generating function, rate function, finite-tau density, and
the weak-noise limit that settles the paper's open question about the jump of I(w) at w = 0.

Numerics.  The symmetrised tilted generator ``S_k = Pi^{-1/2} (L + k F v) Pi^{1/2}`` is the
Schroedinger operator ``(1/gamma) d^2/dv^2 - gamma U'^2/4 + U''/2 + k F v``, discretised on a
uniform grid with v = 0 on a node (:func:`tilted_operator`): pointwise potential away from the
kink, exact discrete ground-state transform near it (so the delta function in U'' of the sgn
law and the stuck state are exact).  The exponentially fitted Scharfetter-Gummel form of
:mod:`analogue.theory.fokker_planck` was tried first: it resolves a tilted ground state at
velocity v only if ``gamma h |U'(v)| << 1`` (its effective potential grows like |U'|/h instead
of gamma U'^2/4), which at gamma = 100 already gave eigenvalue errors of order 1 for moderate
tilts and picked the wrong (sliding instead of stuck) state near the time-sharing crossover.
The O(h^2) error is removed by Richardson extrapolation between h and h/2 (the h/2 grid
contains the h grid).  At large gamma a uniform grid needs 10^4 - 10^5 nodes (spacing
~1/gamma for the stuck state, extent O(1) for the tilt); the graded mesh of
:func:`_graded_nodes` keeps spacing h only where the stuck state lives, 20 nodes per
stationary width where a tilted ground state can sit, and grows in between (linear finite
elements with lumped mass, :func:`_mesh_operator`), so its cost does not grow with gamma;
``mesh="auto"`` uses it once the uniform grid would exceed 6000 nodes.  Rate functions are
computed in a sorted sweep over w, each Legendre root bracketed from its neighbour's.

Weak-noise limit (answer to the open question of Section V).  Write the symmetrised generator as
a Schroedinger operator, ``S_k = (1/gamma) d^2/dv^2 - gamma U'^2/4 + U''/2 + k F v``.  With
``k = gamma beta`` the smooth part gives, by WKB, a principal eigenvalue
``gamma sup_v [beta F v - U'(v)^2/4] + O(1)``; but for the sgn law ``U''/2`` contains
``Delta delta(v)``, an attractive delta well whose bound state has energy of order gamma.
On the scale v ~ 1/gamma the well sees the step potential ``-gamma (Delta sgn v - a)^2/4``;
the bound state has decay rates ``kappa_pm = gamma |Delta -+ a|/2`` and exists iff
``kappa_+ + kappa_- = gamma Delta``, i.e. iff ``|a| <= Delta``, where its energy cancels the
step exactly: holding v = 0 (sticking) then costs nothing; for ``|a| > Delta`` it costs
``(|a| - Delta)^2/4`` (the limit of U'^2/4 at v = 0 on the downhill side).  Hence

    lim gamma^-1 lambda(gamma beta) = Lambda(beta) = sup_v [beta F v - I_0(F v)],
    I_0(w) = L(0, w/F) = (1/4) U'(w/F)^2 for w != 0 (the paper's eq. (64)),
    I_0(0) = max(|a| - Delta, 0)^2 / 4,

and, by Legendre duality, the gamma -> infinity limit of the exact rate function is the lower
convex envelope of I_0, not I_0 itself.  At every finite gamma the SCGF is analytic (principal
eigenvalue with a gap), so I_gamma is convex and continuous; the paper's I(w) is not convex
and, for |a| < Delta, never reaches zero -- it cannot be a rate function.  The envelope keeps
the paper's parabolas for large |w| and replaces the neighbourhood of w = 0 by straight lines
from (0, I_0(0)): time-sharing between sticking at v = 0 and sliding at the tangent velocity.
The limit is continuous; for |a| <= Delta it is piecewise linear near 0 (slopes
``(Delta - a)/(F tau_m)`` and ``-(Delta + a)/(F tau_m)`` up to ``v = tau_m (Delta -+ a)``);
for |a| > Delta it has a kink at w = 0 but no jump.  The fluctuation relation ``I(-w) - I(w)``
is continuous too: it equals ``2 w/(m tau_m)`` near w = 0 when |a| < Delta and joins the
paper's eq. (67) ``w/(m tau_m) + a Delta`` once both sides are on their parabolas.
"""
from __future__ import annotations

import math
import warnings
from collections.abc import Iterator
from contextlib import AbstractContextManager, contextmanager
from contextvars import ContextVar
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy import integrate, linalg, optimize

from .. import checks
from ..checks import finite_array as _finite_array
from ..model import Model
from .fokker_planck import Grid
from .stationary import autocorrelation, integrated_autocorrelation

try:
    from threadpoolctl import threadpool_limits as _threadpool_limits
except ImportError:  # pragma: no cover - declared dependency; only speed depends on it
    _threadpool_limits = None


def _single_threaded() -> AbstractContextManager[Any]:
    """Context limiting BLAS/LAPACK to one thread (a no-op without threadpoolctl)."""
    import contextlib
    return _threadpool_limits(1) if _threadpool_limits is not None else contextlib.nullcontext()

__all__ = ["scgf", "scgf_derivative", "rate_function", "rate_function_curve", "work_pdf",
           "recorded_fallbacks",
           "work_rate_mean", "work_variance",
           "paper_rate_function", "weak_noise_limit_rate_function", "tilted_grid_spacing",
           "tilted_operator"]

_TAIL = 40.0           # ground states are resolved down to exp(-TAIL) in probability
_PPW = 20.0            # minimum nodes per stationary width sqrt(tau_m/gamma)
_MAX_NODES = 2_000_000


# ---------------------------------------------------------------------------- validation
def _check_model(model: Model) -> Model:
    checks.instance("model", model, Model, description="an analogue.Model")
    return model


def _force(model: Model) -> float:
    if model.force == 0:
        raise ValueError("a must be != 0: for a == 0 the work W = m a int v vanishes identically")
    return model.force



# ----------------------------------------------------------------------------- grids
def _reach(model: Model) -> float:
    """Half-width around a ground-state centre outside which its weight is below e^-TAIL."""
    return math.sqrt(2.0 * _TAIL * model.tau_m / model.gamma) + 4.0 * model.velocity_scale


def _tilt_centres(model: Model, k: ArrayLike) -> np.ndarray:
    """Velocities where the tilted ground state can sit: the maxima of k F v - U'(v)^2 (gamma/4)
    on either half line (``v = tau_m (2 k F tau_m/gamma + a -+ Delta)``), and the stuck state 0."""
    k = np.atleast_1d(np.asarray(k, dtype=float))
    tm, g = model.tau_m, model.gamma
    base = tm * (2.0 * k * model.force * tm / g + model.a)
    return np.concatenate([base - tm * model.delta, base + tm * model.delta, [0.0, model.attractor]])


def tilted_grid_spacing(model: Model) -> float:
    """Node spacing h for the tilted operator (see :func:`tilted_operator`).

    At least 20 nodes per stationary width ``sqrt(tau_m/gamma)`` (the width of every tilted
    ground state away from v = 0), ``gamma h (Delta + |a|) <= 0.1`` so that the stuck state at
    v = 0 (decay lengths ``2/(gamma |Delta -+ a|)``) is resolved, and ``h <= epsilon/8``.
    The spacing does not depend on the tilt (the grid's extent does, see ``_grid_for``), so
    every k of a root search sees the same discretisation.
    """
    model = _check_model(model)
    h = model.velocity_scale / _PPW
    if model.delta > 0:
        h = min(h, 0.1 / (model.gamma * (model.delta + abs(model.a))))
    if model.epsilon > 0:
        h = min(h, model.epsilon / 8.0)
    return h


def tilted_operator(model: Model, grid: Grid,
                    k: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """``(diag, off)`` of the symmetric tridiagonal discretisation of the tilted generator
    ``S_k = (1/gamma) d^2/dv^2 - V(v) + k F v``, ``V = gamma U'^2/4 - U''/2`` (ground-state
    transform of the Fokker-Planck operator, detailed balance).

    Far from v = 0, V is evaluated pointwise (central differences: O(h^2) relative to the
    ground-state width, whatever the tilt; the Scharfetter-Gummel form would need
    ``gamma h |U'| << 1``, prohibitive for large tilts).  Within ``|v| <= tau_m (Delta + |a|)``
    V is the exact discrete ground-state transform of ``exp(-gamma U/2)``,
    ``V_i = (1/(gamma h^2)) sum_{+-} (exp(-gamma (U_{i+-1} - U_i)/2) - 1)``, which carries the
    delta function of ``U''`` at the kink of the sgn law (eq. (5)) exactly: the stationary
    state and the stuck state are exact there.
    """
    v = grid.v
    h, g, tm = grid.h, model.gamma, model.tau_m
    up = -model.drift(v)
    if model.epsilon > 0:
        upp = 1.0 / tm + model.delta / model.epsilon / np.cosh(np.clip(v / model.epsilon, -300, 300)) ** 2
    else:
        upp = np.full_like(v, 1.0 / tm)
    V = 0.25 * g * up * up - 0.5 * upp
    if model.delta > 0:
        u = g * model.potential(v)
        near = np.flatnonzero(np.abs(v) <= tm * (model.delta + abs(model.a)))
        near = near[(near > 0) & (near < grid.n - 1)]
        V[near] = (np.expm1(-0.5 * (u[near + 1] - u[near])) + np.expm1(-0.5 * (u[near - 1] - u[near]))) / (g * h * h)
    c = 1.0 / (g * h * h)
    return -2.0 * c - V + k * model.force * v, np.full(grid.n - 1, c)


def _grid_for(model: Model, k: float, h: float, extra: ArrayLike = ()) -> Grid:
    c = _tilt_centres(model, k)
    pts = np.concatenate([c, np.asarray(extra, dtype=float)])
    r = _reach(model)
    grid = Grid.span(float(pts.min()) - r, float(pts.max()) + r, h)
    if grid.n > _MAX_NODES:
        raise ValueError(f"the tilt needs {grid.n} grid nodes (> {_MAX_NODES}); "
                         "reduce the range of k or w, or pass a coarser h")
    return grid


# -------------------------------------------------------------- graded meshes (large gamma)
_GROWTH = 0.05         # graded mesh: the spacing grows by at most this much per unit distance
_UNIFORM_MAX = 6000    # mesh="auto": the uniform grid while it has at most this many nodes
_KINK_NODES = 60       # graded mesh: uniform spacing h over |v| <= this many h (the kink zone)
MESHES = ("auto", "uniform", "graded")


def _kink_half_width(model: Model, h: float) -> float:
    """Half-width of the uniform zone of spacing h around v = 0 on a graded mesh, where the
    stuck state lives and the exact discrete ground-state transform is used: at least 60 h (6
    decay lengths 1/(gamma (Delta + |a|)) of the stuck state's sharp side at the default h),
    10 epsilon (tanh law), and 12 lengths ``2/(gamma |Delta - |a||)`` (the decay length of
    the stuck state's slow side for |a| < Delta; for |a| > Delta a strong enough tilt against
    the sliding direction binds a state at the kink with lengths of that order); never more
    than the transform zone tau_m (Delta + |a|) of the uniform grid.  Measured: with 60 h
    only, the eigenvalue was off by 5e-4 at every k (gamma = 1000, a = 0.5) and by 4e-5 at
    the state bound at the kink (gamma = 100, a = 1.5, k = -150), enough to move the
    stuck/slide crossover and I(w) on its linear stretch by up to 5e-2.  The zone holds
    ~700-2400 nodes, whatever gamma (it grows like gamma only as |a| -> Delta)."""
    if model.delta == 0:
        return 0.0
    width = max(_KINK_NODES * h, 10.0 * model.epsilon)
    if abs(model.a) != model.delta:
        width = max(width, 24.0 / (model.gamma * abs(model.delta - abs(model.a))))
    return min(model.tau_m * (model.delta + abs(model.a)), width)


def _graded_nodes(model: Model, k: float, h: float) -> np.ndarray:
    """Nodes (sorted, v = 0 exactly on a node) of a graded mesh for the tilt k.

    The spacing is the finest of: ``h1 = h sqrt(tau_m/gamma)/(20 h_default)`` (20 nodes per
    stationary width, scaled like ``h``) within ``_reach`` of every place the tilted ground
    state can sit (:func:`_tilt_centres`), ``h`` on the kink zone |v| <= :func:`_kink_half_width`
    (where the stuck state with its decay lengths ~1/(gamma |Delta -+ a|) lives), and between
    and beyond these zones it grows linearly, by ``_GROWTH`` per unit of distance.  Every zone
    has a number of nodes independent of gamma (the zones' widths scale like the spacings), and
    the graded stretches only grow logarithmically: the cost of an eigen-solve no longer grows
    like gamma (uniform grid: extent O(1) over spacing ~1/gamma).
    """
    h0 = h
    h1 = max(h0, h / tilted_grid_spacing(model) * model.velocity_scale / _PPW)
    r = _reach(model)
    cents = _tilt_centres(model, k)
    lo, hi = float(cents.min()) - r, float(cents.max()) + r
    lo, hi = min(lo, -2.0 * h0), max(hi, 2.0 * h0)
    zones = [(float(c), r, h1) for c in cents]
    lk = _kink_half_width(model, h0)
    if lk > 0:
        zones.append((0.0, lk, h0))
    zc = np.array([z[0] for z in zones])
    zw = np.array([z[1] for z in zones])
    zh = np.array([z[2] for z in zones])
    # auxiliary points: zone edges and geometric steps away from them (the node density
    # 1/(h_z + g d) varies by a factor e^{0.1} between consecutive points)
    span = hi - lo
    t = np.expm1(np.linspace(0.0, math.log1p(_GROWTH * span / zh.min()) + 0.1, 200))
    aux = [np.array([lo, hi, 0.0])]
    for c, wz, hz in zones:
        d = wz + hz / _GROWTH * t
        aux += [np.array([c - wz, c + wz]), c - d, c + d]
    x = np.unique(np.clip(np.concatenate(aux), lo, hi))
    dist = np.maximum(np.abs(x[:, None] - zc[None, :]) - zw[None, :], 0.0)
    rho = np.max(1.0 / (zh[None, :] + _GROWTH * dist), axis=1)
    N = np.concatenate([[0.0], np.cumsum(0.5 * (rho[1:] + rho[:-1]) * np.diff(x))])
    N -= N[np.searchsorted(x, 0.0)]
    j = np.arange(math.floor(N[0]), math.ceil(N[-1]) + 1, dtype=float)
    j = j[(j >= N[0]) & (j <= N[-1])]
    nodes = np.asarray(np.interp(j, N, x), dtype=float)
    nodes[j == 0] = 0.0
    if nodes.size > _MAX_NODES:
        raise ValueError(f"the tilt needs {nodes.size} mesh nodes (> {_MAX_NODES}); "
                         "reduce the range of k or w, or pass a coarser h")
    return nodes


def _refined(nodes: np.ndarray) -> np.ndarray:
    """The mesh with every interval halved (it contains the coarse nodes: Richardson)."""
    out = np.empty(2 * nodes.size - 1)
    out[0::2] = nodes
    out[1::2] = 0.5 * (nodes[1:] + nodes[:-1])
    return out


def _mesh_operator(model: Model, v: np.ndarray, k: float,
                   transform_half_width: float) -> tuple[np.ndarray, np.ndarray]:
    """``(diag, off)`` of the tilted generator on the nodes ``v`` (any spacing): linear finite
    elements with lumped mass ``m_i = (s_{i-1} + s_i)/2`` (``s`` the spacings; the ends
    continue their last spacing, as :func:`tilted_operator`), symmetrised by ``M^{-1/2}``:

        diag_i = -(1/s_{i-1} + 1/s_i)/(gamma m_i) - V_i + k F v_i,
        off_i  = 1/(gamma s_i sqrt(m_i m_{i+1})).

    ``V`` is pointwise, except on ``|v| <= transform_half_width`` (the uniform kink zone)
    where it is the discrete ground-state transform of ``exp(-gamma U/2)`` as in
    :func:`tilted_operator` (which this reproduces on a uniform grid): the delta function of
    ``U''`` at the kink and the stuck state stay exact.  Eigenvalue errors are O(max s^2)
    (Richardson-extrapolated by the caller between a mesh and its refinement)."""
    g, tm = model.gamma, model.tau_m
    s = np.diff(v)
    sl = np.concatenate([s[:1], s])
    sr = np.concatenate([s, s[-1:]])
    m = 0.5 * (sl + sr)
    up = -model.drift(v)
    if model.epsilon > 0:
        upp = 1.0 / tm + model.delta / model.epsilon / np.cosh(np.clip(v / model.epsilon, -300, 300)) ** 2
    else:
        upp = np.full_like(v, 1.0 / tm)
    V = 0.25 * g * up * up - 0.5 * upp
    if model.delta > 0 and transform_half_width > 0:
        u = g * model.potential(v)
        near = np.flatnonzero(np.abs(v) <= transform_half_width * (1.0 + 1e-12))
        near = near[(near > 0) & (near < v.size - 1)]
        V[near] = (np.expm1(-0.5 * (u[near + 1] - u[near])) / sr[near]
                   + np.expm1(-0.5 * (u[near - 1] - u[near])) / sl[near]) / (g * m[near])
    diag = -(1.0 / sl + 1.0 / sr) / (g * m) - V + k * model.force * v
    return diag, 1.0 / (g * s * np.sqrt(m[:-1] * m[1:]))


def _mesh_kind(model: Model, h: float, mesh: str) -> str:
    """Resolve ``mesh``: "auto" keeps the uniform grid (the validated reference) while it is
    small (<= _UNIFORM_MAX nodes at k = 0: gamma = 10 for the paper's models) and grades it
    beyond (gamma >= 100, where a uniform grid needs 10^4 - 10^5 nodes)."""
    if mesh not in MESHES:
        raise ValueError(f"mesh must be one of {MESHES}, got {mesh!r}")
    if mesh == "auto":
        return "uniform" if _grid_for(model, 0.0, h).n <= _UNIFORM_MAX else "graded"
    return mesh


# ------------------------------------------------------------------ principal eigenpair
_II_MAXIT = 30          # inverse iterations before falling back to LAPACK
_II_RES = 64.0          # residual target, in units of eps ||T||_inf (the matrix's own rounding)


def _top_eigenpair(d: np.ndarray, e: np.ndarray,
                   guess: float | None = None) -> tuple[float, np.ndarray]:
    """Principal eigenpair of the symmetric tridiagonal (d, e) with e > 0 (every tilted
    operator here).  Without ``guess``: LAPACK bisection + inverse iteration
    (``eigh_tridiagonal``), ~2 ms at 4400 nodes, almost all of it bisection from the
    Gershgorin interval.  With a ``guess`` of the eigenvalue (a neighbouring k, or the
    coarse grid's value for the refined grid): :func:`_top_eigenpair_shifted`, falling back to
    LAPACK if it does not converge."""
    if guess is not None and d.size >= 3 and math.isfinite(guess):
        out = _top_eigenpair_shifted(d, e, float(guess))
        if out is not None:
            return out
    n = d.size
    lam, vec = linalg.eigh_tridiagonal(d, e, select="i", select_range=(n - 1, n - 1))
    return float(lam[0]), vec[:, 0]


def _top_eigenpair_shifted(d: np.ndarray, e: np.ndarray,
                           guess: float) -> tuple[float, np.ndarray] | None:
    """Certified shifted inverse iteration for the principal eigenpair (None: not converged).

    A shift sigma is accepted only if the Cholesky factorisation (``pttrf``) of ``sigma - T``
    succeeds, i.e. ``sigma - T`` is positive definite: sigma lies above the top eigenvalue
    (a failed factorisation moves it up, from ``guess + 1e-7 max(1, |guess|)`` by factors 8).
    ``sigma - T`` is then a nonsingular M-matrix (off-diagonal ``-e < 0``), its inverse is
    entrywise positive, so the iterates from a positive start stay positive and converge to
    the only positive eigenvector, the top one (Perron-Frobenius): never to another state.
    After each solve the Rayleigh quotient rho (<= lambda_max) and the residual r = ||T x -
    rho x|| give the next shift rho + r when it factorises (superlinear, as Rayleigh quotient
    iteration, but never below the top eigenvalue).  Stops at ``r <= 64 eps ||T||_inf``, the
    rounding of the matrix entries themselves.  Measured against LAPACK on the open question's
    operators (gamma 10-1000, a = 0.5, 1.5, k = -2 gamma .. gamma, refined meshes): eigenvalues
    within 3e-10 relative (|d lambda| <= eps ||T||: both are at the data's rounding), F <v>
    within 1e-10; 2-3 factorisations and 3-4 solves (0.03 ms each) instead of ~2 ms."""
    if not np.all(e > 0):
        return None
    from scipy.linalg import lapack
    n = d.size
    rad = np.zeros(n)
    rad[:-1] += e
    rad[1:] += e
    top = float(np.max(d + rad))                     # Gershgorin: lambda_max <= top
    tol = _II_RES * np.finfo(float).eps * float(np.max(np.abs(d) + rad))
    step = 1e-7 * max(1.0, abs(guess))
    while True:
        sigma = min(guess + step, top)
        c, f, info = lapack.dpttrf(sigma - d, -e)
        if info == 0:
            break
        if sigma >= top:                             # pragma: no cover - Gershgorin bound
            return None
        step *= 8.0
    x = np.full(n, 1.0 / math.sqrt(n))
    history: list[float] = []
    for it in range(_II_MAXIT):
        x, info = lapack.dpttrs(c, f, x)
        if info != 0:                                # pragma: no cover
            return None
        x /= math.sqrt(float(x @ x))
        tx = d * x
        tx[:-1] += e * x[1:]
        tx[1:] += e * x[:-1]
        rho = float(x @ tx)
        res = tx - rho * x
        r = math.sqrt(float(res @ res))
        if r <= tol:
            return rho, x
        # stagnation (a second state within ~r of the top one: the stuck/slide crossings,
        # gaps 2e-7 - 8e-6, where 54 of 2500 calls of the open question ran all 30 solves
        # in vain): LAPACK at once
        history.append(r)
        if it >= 5 and r > 0.5 * history[-4]:
            return None
        if rho + r < sigma:
            c2, f2, info = lapack.dpttrf(rho + r - d, -e)
            if info == 0:
                sigma, c, f = rho + r, c2, f2
    return None


def _principal(model: Model, k: float, grid: Grid,
               guess: float | None = None) -> tuple[float, float]:
    """Principal eigenvalue and Hellmann-Feynman derivative ``F <phi| v |phi>``."""
    d, e = tilted_operator(model, grid, k)
    lam, phi = _top_eigenpair(d, e, guess)
    return lam, model.force * float(np.dot(phi * phi, grid.v))


def _principal_nodes(model: Model, k: float, v: np.ndarray, h: float,
                     guess: float | None = None) -> tuple[float, float]:
    d, e = _mesh_operator(model, v, k, _kink_half_width(model, h))
    lam, phi = _top_eigenpair(d, e, guess)
    return lam, model.force * float(np.dot(phi * phi, v))


def _scgf_pair(model: Model, k: float, h: float, check: bool = True,
               mesh: str = "uniform") -> tuple[float, float]:
    """Richardson-extrapolated (lambda, lambda') from spacings h and h/2 (``mesh``: "uniform"
    grid of spacing h, or "graded" mesh of :func:`_graded_nodes`, and their refinements)."""
    lam, der, l1, l2 = _scgf_pair_raw(model, k, h, mesh)
    if check:
        _check_converged(model, k, h, lam, l1, l2)
    return lam, der


def _grid_pairs(model: Model, k: float, h: float, mesh: str,
                guess: float | None = None) -> tuple[float, float, float, float]:
    """(l1, d1, l2, d2): principal eigenvalue and derivative on the grid of spacing h and on
    its refinement.  ``guess``: an estimate of l1 (then both solves use the shifted inverse
    iteration of :func:`_top_eigenpair`, the refinement seeded with l1); None: LAPACK."""
    if mesh == "graded":
        v1 = _graded_nodes(model, k, h)
        l1, d1 = _principal_nodes(model, k, v1, h, guess)
        l2, d2 = _principal_nodes(model, k, _refined(v1), h / 2.0,
                                  None if guess is None else l1)
    else:
        g1 = _grid_for(model, k, h)
        g2 = Grid(h / 2.0, 2 * g1.i_min, 2 * g1.i_max)
        l1, d1 = _principal(model, k, g1, guess)
        l2, d2 = _principal(model, k, g2, None if guess is None else l1)
    return l1, d1, l2, d2


def _scgf_pair_raw(model: Model, k: float, h: float, mesh: str,
                   guess: float | None = None) -> tuple[float, float, float, float]:
    """(lambda, lambda', l1, l2), Richardson-extrapolated from the two grids.

    Where the stuck and the sliding state cross (large gamma: lambda' jumps there), the two
    grids can put different states on top within a window of k ~1e-5 wide; extrapolating
    between them is meaningless (measured gamma = 100, a = 0.5, k = -298.0014: lambda' =
    -0.988, neither state's 0.004 or -0.745, which sent the next Legendre root the wrong way
    and put I(-0.84), I(-0.96) on the time-sharing line, 0.01 and 0.05 too low).  There the
    fine grid's pair is returned as it is (O(h^2) error, ~1e-6 in I at gamma = 100, only in
    that window).  (Continuing a consistent pair from k +- 1e-4 |k| instead was worse at
    gamma = 10, where the crossing is not sharp: 2e-4 in I.)
    """
    l1, d1, l2, d2 = _grid_pairs(model, k, h, mesh, guess)
    # derivative difference between the grids: <= 0.03 of this scale elsewhere (gamma = 10)
    scale = abs(model.force) * (model.tau_m * (model.delta + abs(model.a)) + model.velocity_scale)
    if abs(d2 - d1) > 0.1 * scale:
        return l2, d2, l1, l2
    return (4.0 * l2 - l1) / 3.0, (4.0 * d2 - d1) / 3.0, l1, l2


def _check_converged(model: Model, k: float, h: float, lam: float, l1: float,
                     l2: float) -> None:
    # natural eigenvalue scale: the Schroedinger potential gamma U'^2/4 near the attractor
    scale = max(1.0, abs(lam), 1e-2 * model.gamma * (model.delta + abs(model.a)) ** 2)
    if abs(l2 - l1) > 0.05 * scale:
        warnings.warn(f"scgf at k={k:g} not converged in h (h={h:g}: {l1:g}, h/2: {l2:g}); "
                      "pass a smaller h", RuntimeWarning, stacklevel=4)


def scgf(model: Model, k: ArrayLike, *, h: float | None = None, mesh: str = "auto") -> np.ndarray:
    """Scaled cumulant generating function ``lambda(k) = lim (1/tau) ln E exp(k W_tau)``.

    Principal eigenvalue of the symmetrised tilted generator ``S_0 + k F diag(v)`` (Touchette,
    Prellberg & Just 2012; the Legendre dual of the paper's eq. (54) rate function, with
    ``gamma I(w) = sup_k [k w - lambda(k)]``).  Vectorised over k.  The grid covers every
    place the tilted eigenvector can sit, its spacing comes from :func:`tilted_grid_spacing`
    (or ``h``), and values on h and h/2 are Richardson-extrapolated; a RuntimeWarning flags an
    unconverged grid.

    ``mesh``: "uniform" (spacing h everywhere: 10^4 - 10^5 nodes at gamma >= 100), "graded"
    (spacing h only in the kink zone around v = 0, 20 nodes per width sqrt(tau_m/gamma) where
    the ground state can sit, growing in between: ~2000 - 4600 nodes at any gamma, see
    :func:`_graded_nodes`) or "auto" (uniform while it has at most 6000 nodes, e.g. gamma =
    10; graded beyond).  Measured against the uniform grid (tau_m = Delta = 1, a = 0.5 and
    1.5, k = -gamma .. gamma): relative differences <= 3e-9 at gamma = 100 and 1000, with
    3-35x fewer nodes (the uniform grid fails for sliding states of stronger negative tilts,
    see benchmarks/README.md).
    """
    return _scgf_and_derivative(model, k, h, mesh)[0]


def scgf_derivative(model: Model, k: ArrayLike, *, h: float | None = None,
                    mesh: str = "auto") -> np.ndarray:
    """``lambda'(k)`` by Hellmann-Feynman: ``F <phi_k| v |phi_k>`` (the tilted mean work rate);
    ``mesh`` as in :func:`scgf`."""
    return _scgf_and_derivative(model, k, h, mesh)[1]


def _scgf_and_derivative(model: Model, k: ArrayLike, h: float | None,
                         mesh: str = "auto") -> tuple[np.ndarray, np.ndarray]:
    model = _check_model(model)
    k = _finite_array("k", k)
    if h is None:
        h = tilted_grid_spacing(model)
    kind = _mesh_kind(model, h, mesh)
    out = np.array([_scgf_pair(model, float(kk), h, mesh=kind)
                    for kk in k.ravel()]).reshape(k.shape + (2,))
    return out[..., 0], out[..., 1]


# ---------------------------------------------------------------------- rate function
def work_rate_mean(model: Model) -> float:
    """``<w> = F <v>`` with ``<v>`` by quadrature of the exact stationary law (eq. (6))."""
    model = _check_model(model)
    c = model.potential_minimum()
    r = _reach(model)
    pts = sorted({0.0, c})
    val, _ = integrate.quad(lambda v: v * float(model.stationary_pdf(v)), c - r, c + r,
                            points=[p for p in pts if c - r < p < c + r], limit=400,
                            epsabs=1e-14, epsrel=1e-12)
    out: float = model.force * val
    return out


def _k_guess(model: Model, w: float) -> float:
    """k whose weak-noise tilt centre is at v = w/F (OU-like: lambda'(k) ~ F tau_m (2kF tau_m/gamma + a))."""
    F, tm, g = model.force, model.tau_m, model.gamma
    return g * (w / F - tm * model.a) / (2.0 * F * tm * tm)


def _legendre_root(model: Model, w: float, h: float, mean: float, mesh: str = "uniform",
                   near: tuple[float, float, float] | None = None,
                   counter: list[float] | None = None,
                   memo: dict[float, tuple[float, float, float, float]] | None = None,
                   ) -> tuple[float, ...]:
    """k with lambda'(k) = w (lambda' increases with k) and lambda(k).

    Without ``near`` the root is bracketed from k = 0 (where lambda'(0) = <w>) outwards by
    doubling steps.  ``near = (k1, d1, slope)`` continues from a solved neighbour with
    ``lambda'(k1) = d1`` as computed there (not the neighbour's w: at large gamma lambda'
    jumps where the stuck and the sliding state cross, and the root can sit on the jump) with
    the first step ``slope |w - d1|`` (slope ~ dk/dw from the previous two roots), so that a
    sorted sweep over w needs fewer eigen-pairs per point than bracketing from k = 0.  ``counter``: optional list, appended one
    item per eigen-pair (for benchmarks).

    ``memo``: optional ``{k: (lambda, lambda', l1, l2)}`` shared by the roots of a sweep (the
    previous root's pair is not recomputed when Brent starts from it).  With it every new k is
    solved by the shifted inverse iteration of :func:`_top_eigenpair`, seeded with the tangent
    ``l1(k') + lambda'(k') (k - k')`` at the nearest solved k' (a lower estimate: lambda is
    convex); without it (the old route, ``memo=None``) by LAPACK alone."""
    if w == mean:
        return 0.0, 0.0
    seeded = memo is not None
    pairs: dict[float, tuple[float, float, float, float]] = {} if memo is None else memo

    def pair(k: float) -> tuple[float, float, float, float]:
        if k not in pairs:
            guess = None
            if seeded and pairs:
                near_k = min(pairs, key=lambda q: abs(q - k))
                _, der, l1, _ = pairs[near_k]
                guess = l1 + der * (k - near_k)
            pairs[k] = _scgf_pair_raw(model, k, h, mesh, guess)
            if counter is not None:
                counter.append(k)
        return pairs[k]

    def f(k: float) -> float:
        return pair(k)[1] - w

    if near is None:
        side = 1.0 if w > mean else -1.0
        step = max(abs(_k_guess(model, w)),
                   model.gamma / (model.force**2 * model.tau_m**2) * 1e-3, 1e-12)
        lo, hi = 0.0, side * step
    else:
        k1, d1, slope = near
        if d1 == w:
            return k1, pair(k1)[0], d1
        side = 1.0 if w > d1 else -1.0
        scale = model.gamma / (model.force**2 * model.tau_m**2)
        step = max(1.5 * abs(slope * (w - d1)), 1e-4 * scale, 1e-12)
        lo, hi = k1, k1 + side * step
    for _ in range(200):
        if side * f(hi) > 0:
            break
        lo, hi = hi, hi + 2.0 * (hi - lo)
    else:  # pragma: no cover - lambda' is unbounded, so this cannot happen on a valid grid
        raise RuntimeError(f"could not bracket the Legendre root for w={w:g}")
    a, b = (lo, hi) if lo < hi else (hi, lo)
    # I = k w - lambda(k) is stationary in k at the root: k to 1e-9 gives I to ~1e-18.
    k = optimize.brentq(f, a, b, xtol=1e-9 * max(1.0, abs(b)), rtol=1e-12, maxiter=200)
    lam, der, l1, l2 = pair(k)
    _check_converged(model, k, h, lam, l1, l2)
    return (k, lam, der) if near is not None else (k, lam)


def _legendre_sweep(model: Model, w: np.ndarray, h: float, mesh: str,
                    counter: list[float] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(k, lambda(k)) at the Legendre points of every w (flat array), solved in two sorted
    sweeps outwards from the mean, each root continued from the previous one."""
    # one memo for the whole sweep: k = 0 seeds the first roots' eigen-solves (LAPACK there)
    memo: dict[float, tuple[float, float, float, float]] = {}
    memo[0.0] = raw0 = _scgf_pair_raw(model, 0.0, h, mesh)
    _check_converged(model, 0.0, h, raw0[0], raw0[2], raw0[3])
    mean = float(raw0[1])
    ks = np.zeros(w.size)
    lams = np.zeros(w.size)
    order = np.argsort(w, kind="stable")
    up = [i for i in order if w[i] >= mean]
    down = [i for i in order[::-1] if w[i] < mean]
    scale0 = model.gamma / (2.0 * model.force**2 * model.tau_m**2)   # OU dk/dw
    for seq in (up, down):
        prev = [(0.0, mean, 0.0, mean)]           # solved (k, w, lambda(k), lambda'(k))
        for i in seq:
            wi = float(w[i])
            k1, w1, lam1, d1 = prev[-1]
            if wi == w1:                          # repeated w (or w = <w>): same root
                ks[i], lams[i] = k1, lam1
                continue
            slope = scale0
            if len(prev) >= 2:
                slope = (k1 - prev[-2][0]) / (w1 - prev[-2][1])
            ks[i], lams[i], d = _legendre_root(model, wi, h, mean, mesh,
                                               near=(k1, d1, max(slope, 0.0)), counter=counter,
                                               memo=memo)
            prev.append((ks[i], wi, lams[i], d))
    return ks, lams


def rate_function(model: Model, w: ArrayLike, *, h: float | None = None,
                  mesh: str = "auto") -> np.ndarray:
    """Exact rate function ``I(w) = (1/gamma) sup_k [k w - lambda(k)]`` in the paper's scaling
    ``P_tau(w) ~ exp(-tau gamma I(w))`` (eqs. (54), (55)).

    For each w the maximiser solves ``lambda'(k) = w`` (Hellmann-Feynman derivative) with a
    bracketing root finder (Brent), so the transform is accurate to the eigenvalue's accuracy.
    The w are solved in sorted order outwards from the mean, each root bracketed from its
    neighbour's.  ``I(<w>) = 0`` at ``<w> = F <v>``.  Vectorised over w.  ``mesh``: see
    :func:`scgf` (the graded mesh makes the cost independent of gamma).

    At Delta = 0 (OU) the fluctuation relation ``I(-w) = I(w) + w/(m tau_m)`` is exact
    (Gallavotti-Cohen symmetry ``lambda(k) = lambda(-k - gamma/(m tau_m))``, see
    :func:`rate_function_curve`); for Delta > 0 it is not, and every w is computed.
    """
    model = _check_model(model)
    _force(model)
    w = _finite_array("w", w)
    if h is None:
        h = tilted_grid_spacing(model)
    kind = _mesh_kind(model, h, mesh)
    flat = w.ravel()
    ks, lams = _legendre_sweep(model, flat, h, kind)
    out: np.ndarray = np.maximum(ks * flat - lams, 0.0) / model.gamma
    return out.reshape(w.shape)


def rate_function_curve(model: Model, w: ArrayLike, *, h: float | None = None,
                        mesh: str = "auto") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(w, I(w), I(-w) - I(w))`` on a grid symmetric about 0, every point computed once.

    ``w`` must be symmetric (``w[::-1] == -w`` to 1e-9 of max |w|; it is symmetrised
    exactly); ``I(-w)`` is ``I[::-1]``, so a figure of I and of the fluctuation relation
    needs no second call.  At Delta = 0 (OU, where the fluctuation relation is exact:
    ``lambda(k) = lambda(-k - gamma/(m tau_m))`` because the tilted Schroedinger operator
    ``(1/gamma) d^2 - gamma (v/tau_m - a)^2/4 + 1/(2 tau_m) + k F v`` maps to itself under
    ``v -> -v``, ``k F -> -k F - gamma a/tau_m``) only w >= 0 is computed and
    ``I(-w) = I(w) + w/(m tau_m)``.  For Delta > 0 the term ``gamma a Delta sgn(v)/2`` of the
    operator breaks that symmetry and every point is computed.  Returns a plain tuple of
    arrays (so it can pass through :mod:`analogue.theory.cache`)."""
    model = _check_model(model)
    _force(model)
    wa = _finite_array("w", w)
    if wa.ndim != 1 or wa.size < 1:
        raise ValueError(f"w must be a non-empty 1-D grid, got shape {wa.shape}")
    span = float(np.max(np.abs(wa)))
    if np.max(np.abs(wa + wa[::-1])) > 1e-9 * max(span, 1e-300):
        raise ValueError("w must be symmetric about 0 (w[::-1] == -w), e.g. "
                         "np.linspace(-wmax, wmax, n)")
    ws_ = 0.5 * (wa - wa[::-1])
    if model.delta == 0:
        half = ws_ >= 0
        rate = np.empty(ws_.size)
        rate[half] = rate_function(model, ws_[half], h=h, mesh=mesh)
        neg = ~half
        rate[neg] = rate[::-1][neg] - ws_[neg] / (model.mass * model.tau_m)
    else:
        rate = np.asarray(rate_function(model, ws_, h=h, mesh=mesh), dtype=float)
    return ws_, rate, rate[::-1] - rate


def work_variance(model: Model, taus: ArrayLike, *, n: int | None = None,
                  h: float | None = None) -> np.ndarray:
    """``Var(w)`` of the work rate ``w = W_tau/tau`` in the stationary state for every window
    in ``taus``: ``(F/tau)^2 2 int_0^tau (tau - s) C(s) ds`` with C the exact stationary
    velocity autocorrelation (the Green-Kubo route, independent of :func:`work_pdf`).

    ``n=None`` (default; the paper's model): the integral in closed form on the FP grid
    (:func:`analogue.theory.stationary.integrated_autocorrelation`: one Poisson solve and a
    Talbot contour per window, O(n) each, no eigen-decomposition, no quadrature over lags).
    Measured against the route below: the work model's windows 1, 2, 5, 10 differ by 4e-10,
    3.5e-9, 7.6e-8, 8.0e-7 relative, and the differences shrink to <= 1e-10 as that route's
    lags are refined to 12801 (its Simpson error), at 0.006 s instead of 0.34 s (ideal
    model) and 0.03 s instead of 7.2 s (smoothed model, whose > 6000-node grid took the
    partial-spectrum path).

    ``n`` (odd >= 3; family members always, with 801): Simpson's rule on ``n`` lags per
    window of :func:`analogue.theory.stationary.autocorrelation` (one call for all windows).
    Vectorised over taus."""
    model = _check_model(model)
    ta = _finite_array("taus", taus)
    if np.any(ta <= 0):
        raise ValueError(f"taus must be > 0, got {taus!r}")
    flat = ta.ravel()
    if n is None and model.is_paper:
        var = (model.force / flat) ** 2 * integrated_autocorrelation(model, flat, h=h)
        return np.asarray(var).reshape(ta.shape)
    n = 801 if n is None else int(n)
    if n < 3 or n % 2 == 0:
        raise ValueError(f"n must be an odd integer >= 3 (Simpson's rule), got {n}")
    lags = np.concatenate([np.linspace(0.0, t, n) for t in flat])
    c = np.asarray(autocorrelation(model, lags, h=h), dtype=float).reshape(flat.size, n)
    out = np.empty(flat.size)
    for i, t in enumerate(flat):
        s = lags[i * n:(i + 1) * n]
        out[i] = (model.force / t) ** 2 * 2.0 * integrate.simpson((t - s) * c[i], x=s)
    return out.reshape(ta.shape)


# --------------------------------------------------------------- weak-noise objects
def paper_rate_function(model: Model, w: ArrayLike) -> np.ndarray:
    """The paper's eq. (64), ``I(w) = (1/4)(w/(m a tau_m) + sgn(w) Delta - a)^2`` (at w = 0 the
    formula is ambiguous; sgn(0) = 0 is used)."""
    model = _check_model(model)
    F = _force(model)
    v = _finite_array("w", w) / F
    out: np.ndarray = 0.25 * (v / model.tau_m + np.sign(v) * model.delta - model.a) ** 2
    return out


def _envelope_right(v: np.ndarray, a: float, delta: float, tm: float) -> np.ndarray:
    """Convex envelope on v >= 0 of {(0, c0)} and the branch (v/tm + Delta - a)^2/4 (v > 0)."""
    branch = 0.25 * (v / tm + delta - a) ** 2
    if abs(a) <= delta:          # tangent from (0, 0) touches at v_t = tm (Delta - a)
        vt, slope, c0 = tm * (delta - a), (delta - a) / tm, 0.0
    elif a > delta:              # c0 equals the branch's limit at 0+: nothing to add
        return branch
    else:                        # a < -Delta: tangent from (0, c0) at v_t = 2 tm sqrt(|a| Delta)
        vt = 2.0 * tm * math.sqrt(-a * delta)
        slope = (math.sqrt(-a) + math.sqrt(delta)) ** 2 / (2.0 * tm)
        c0 = 0.25 * (-a - delta) ** 2
    return np.where(v < vt, c0 + slope * v, branch)


def weak_noise_limit_rate_function(model: Model, w: ArrayLike) -> np.ndarray:
    """``lim_{gamma -> inf} I_gamma(w)``: the lower convex envelope of the cost of holding the
    velocity at ``v = w/F`` (see the module docstring for the derivation).

    ``I_0(w) = (1/4)(v/tau_m + Delta sgn v - a)^2`` for v != 0 (the paper's eq. (64)) and
    ``I_0(0) = max(|a| - Delta, 0)^2/4``.  Two parabolas of equal curvature have a common
    tangent only with slope 0 at both minima, which cannot lie on opposite half lines when
    Delta > 0, so the envelope passes through (0, I_0(0)) and is built on each half line from
    the tangent line through that point.  gamma, epsilon are ignored (epsilon -> 0 limit).
    """
    model = _check_model(model)
    F = _force(model)
    v = _finite_array("w", w) / F
    tm, d, a = model.tau_m, model.delta, model.a
    right = _envelope_right(np.abs(v), a, d, tm)
    left = _envelope_right(np.abs(v), -a, d, tm)   # mirror (v, a) -> (-v, -a)
    return np.where(v >= 0, right, left)


# ------------------------------------------------------------------ finite-tau density
def work_pdf(model: Model, w: ArrayLike, tau: ArrayLike, *, h: float | None = None,
             modes: int = 48, share: bool = True, propagator: str = "expm") -> np.ndarray:
    """Exact density of the work rate ``w = W_tau/tau`` at finite tau in the stationary state.

    ``G(k) = E e^{kW} = <sqrt(pi)| exp(tau S_k) |sqrt(pi)>`` (sqrt(pi) the normalised discrete
    ground state of S_0).  For each w the Laplace inversion runs along the steepest-descent
    contour ``k = k* + i y`` through the real saddle of ``ln G(k) - k W``,
    ``p(W) = (1/pi) int_0^inf Re[G(k*+iy) e^{-(k*+iy) W}] dy`` (exponential tilting, so tails
    are as accurate as the centre); the integral is a trapezoid rule, exponentially convergent
    for this analytic integrand.  ``exp(tau S_k)`` is evaluated in the span of the top
    ``modes`` eigenvectors of ``S_{k0}`` (k0 the SCGF's Legendre point for w), where
    ``S_k = diag(mu) + (k - k0) B`` is a small dense complex-symmetric matrix.  Returns the
    density of w (``tau`` times the density of W).  The O(h^2) grid error of ln p (which the
    eigenvalue error enters times tau) is removed by Richardson extrapolation.

    Accuracy measured against the Delta = 0 closed form (gamma = 10): relative 1e-8 to 4e-7 at
    tau = 2 from -6 to +8 standard deviations (densities down to 4e-14); short windows need
    more modes (at tau = 0.5, 32 modes give 1e-2).

    Far tails.  The basis overlaps ``<phi_i|sqrt(pi)>`` of the stationary state with tilted
    states far from it fall below floating-point resolution, and the projected generating
    function then violates ``|G(k*+iy)| <= G(k*)`` (true of every moment generating
    function) or stops decaying along the contour.  This is checked; the basis is then
    doubled (at k0, then centred on the finite-tau saddle), and if that fails too the density
    falls back to the large-deviation form ``<phi_k0|sqrt(pi)>^2 sqrt(tau / (2 pi
    lambda''(k0))) exp(-tau (k0 w - lambda(k0)))`` (principal eigenpair, Gaussian prefactor,
    overlap from log-space ground states, :func:`_log_ground_state`).  It leaves out the
    finite-tau boundary terms of ln G, so ``-ln p / tau`` is right only to O(1/tau): OU,
    gamma = 10, tau = 2, w = -1.5 (8 sd): 3.2e-40 against the exact 4.6e-47 (ln p off by 16
    of 107).  Measured (gamma = 10, tau_m = 1, w in [-1.5, 2.5]): at tau >= 2 the fallback
    is reached only below ~1e-13; at tau = 1 also at some densities 1e-13 .. 1e-6 (contour
    not resolved by 96 modes; 192 modes resolve them at ~30 s per point).  It never raises
    for finite inputs; the (w, tau) of fallbacks are listed by :func:`recorded_fallbacks`, and a
    RuntimeWarning is issued when a fallback density exceeds 1e-8.
    Cost: per w, a Legendre root of the SCGF, two tridiagonal eigen-solves of ``modes``
    vectors and 12-120 dense complex ``modes x modes`` matrix exponentials (or, with
    ``propagator="eig"``, eigen-decompositions) per grid (the y range adapts to the slowly
    decaying characteristic function of the stick regime); BLAS is limited to one thread
    meanwhile.

    ``share=True`` (default) shares the expensive part across w: the contour abscissa k need
    not be each W's own saddle (any real k gives the same integral), so one contour ``k_c +
    iy``, i.e. one set of complex eigen-decompositions of the reduced generator (the factor
    ``G(k_c + iy)/G(k_c)`` does not depend on W), serves every W within 2 standard deviations
    of the tilted law's mean ``K'(k_c)`` (the integral then loses at most a factor e^2 to
    cancellation; the trapezoid step is 0.5/sqrt(K'') instead of 0.7, so aliases lie >= 12.6
    standard deviations away), with the mode basis centred on ``k_c``.  A W whose shared
    integral is not resolved (too small against the integrand: cancellation; an undecayed
    tail; h and h/2 disagreeing by more than 0.01 in ln p) waits for a later group centred
    nearer to it, and the lowest W of a group is computed alone (``share=False`` path, with
    its fallbacks) if its own group fails; a group whose contour does not decay with
    ``modes`` retries with twice as many first.  Measured on 30 w over +-4 sd (the report's range),
    gamma = 10, under load: Fig. 8 model tau = 2 / 5 / 10: 23 / 19 / 29 s -> 2.4 / 2.8 / 3.2 s;
    OU tau = 1 / 2 / 5 / 10: 6-8x; OU against the closed form: 6e-6 (tau = 1), 2e-8 (tau >= 2).
    In the stick regime the shared densities differ from the per-w ones by up to 1.7e-3 near
    w = 0: that is aliasing of the per-w step 0.7 (per-w with step 0.5 / 0.35 moves to within
    2e-4 / 5e-5 of the shared values, which change by 1e-5 between steps 0.5 and 0.35; Fig. 8
    model, tau = 5, w = 0.002).  At the peak near w = 0 of that regime both routes also depend
    on the contour abscissa and the mode basis at the 1e-3 level (tau = 2, w = 0.0076: 10.2891
    per-w, 10.2881 shared alone, 10.2985 shared in a group of 9), which bounds the accuracy of
    the density there; the circuit's statistical errors are >= 1e-2.

    ``propagator`` chooses how ``<c|exp(tau S_k)|c>`` is evaluated at the complex contour
    points: ``"expm"`` (default) by a batched Pade scaling-and-squaring matrix exponential
    of the reduced ``modes x modes`` complex-symmetric matrix (no eigenvectors, so no
    ill-conditioned ``V^-1``); ``"eig"`` by its eigen-decomposition (the route before, kept for
    comparison).  The two agree to 1e-12 in ``G/G(k_c)``; measured on the report's Fig. 8
    model, tau = 1, 30 w over +-4 sd: see benchmarks/bench_theory.py.  The Krylov (Arnoldi)
    route was measured too and rejected: with the reduced spectrum reaching tau*mu ~ -125 it
    needs 70-96 of the 96 steps, no cheaper than the dense exponential.
    """
    model = _check_model(model)
    _force(model)  # refuses a = 0: the work is identically zero
    w = _finite_array("w", w)
    tau_arr = _finite_array("tau", tau)
    if tau_arr.ndim != 0:
        raise ValueError(f"tau must be a single number (one window length per call), got {tau!r}")
    tau = float(tau_arr)
    if not tau > 0:
        raise ValueError(f"tau must be > 0, got {tau!r}")
    if propagator not in PROPAGATORS:
        raise ValueError(f"propagator must be one of {PROPAGATORS}, got {propagator!r}")
    modes = int(modes)
    if modes < 4:
        raise ValueError(f"modes must be >= 4, got {modes}")
    if h is None:
        h = tilted_grid_spacing(model)
    # The many small dense eigen-problems run 10-30x faster single-threaded than under
    # OpenBLAS threading (thread start-up dominates at 48 x 48).
    with _single_threaded():
        mean = float(_scgf_pair(model, 0.0, h, check=False)[1])
        if share:
            out = _work_pdf_shared(model, w.ravel(), tau, h, modes, mean, propagator)
        else:
            out = np.empty(w.size)
            for i, wi in enumerate(w.ravel()):
                out[i] = _work_pdf_one(model, float(wi), tau, h, modes, mean, propagator)
    return out.reshape(w.shape)


PROPAGATORS = ("expm", "eig")   # work_pdf(propagator=...): how exp(tau S_k) is applied
_GROUP_SD = 2.0     # shared contour: W within this many tilted standard deviations of K'(k_c)
_DY_SHARED = 0.5    # its trapezoid step in units of 1/sqrt(K''(k_c))
_MIN_SHARED = 0.02  # a shared integral below this many 1/sd is recomputed alone
_RICHARDSON_GAP = 0.01   # ... and so is one whose ln p differs by more between h and h/2
# y range of a shared contour before the tail test, in 1/sqrt(K''), as for per-w contours.
# (In the stick regime |f| can level off near 1e-7 -- Fig. 8 model, tau = 2 -- so that members
# with small integrals fail the tail test and are recomputed alone; 400 widths did not help:
# the plateau stayed, at 2.5x the cost.)
_Y_MAX_SHARED = 150.0


def _work_pdf_shared(model: Model, w: np.ndarray, tau: float, h: float, modes: int,
                     mean: float, propagator: str = "expm") -> np.ndarray:
    """:func:`work_pdf` with one contour per group of nearby W (see its docstring)."""
    out = np.full(w.size, np.nan)
    k0s, lams = _legendre_sweep(model, w, h, "uniform")
    todo = [int(i) for i in np.argsort(w, kind="stable")]
    while todo:
        i = todo[0]
        Wi = float(w[i]) * tau
        k0 = float(k0s[i])
        probe = _grid_for(model, k0, h, extra=_tilt_centres(model, 0.0))
        group = None
        # (the basis is re-centred on the shared contour below, so a third attempt centred
        # on the saddle, as in _work_pdf_one, would repeat the second)
        for m in (modes, 2 * modes):
            red2 = _Reduced(model, k0, probe, m, propagator)  # coarse grid: only locates the saddles
            ks, Ks, curv = _saddle(model, red2, Wi, tau, red2.k0)
            # the group's contour sits 1 standard deviation above the lowest W (members from
            # Wi - sd to Wi + 3 sd); far members that fail stay for the next group
            target = Wi + math.sqrt(curv)
            try:
                kc, K2, curvc = _saddle(model, red2, target, tau, ks)
            except ValueError:       # the reduced K' cannot reach the target: no group
                kc, K2, curvc = ks, Ks, curv
            sd = math.sqrt(curvc)
            if abs(Wi - target) > _GROUP_SD * sd:   # curvature changed a lot: Wi's own saddle
                kc, K2, curvc, target = ks, Ks, curv, Wi
                sd = math.sqrt(curvc)
            group = [j for j in todo if abs(float(w[j]) * tau - target) <= _GROUP_SD * sd]
            if i not in group:
                group = [i] + group
            # the basis is centred on the shared contour (the members' saddles lie around
            # it); at Wi's Legendre point it misrepresented far members (measured: factors
            # up to 1e14 at 2 sd in the stick regime)
            g1 = _grid_for(model, kc, h, extra=_tilt_centres(model, 0.0))
            g2 = Grid(h / 2.0, 2 * g1.i_min, 2 * g1.i_max)
            red2 = _Reduced(model, kc, g2, m, propagator)
            K2, _ = red2.log_g_and_derivatives(kc, tau)
            f2 = _contour_values(red2, kc, tau, K2, curvc)
            if f2 is None:
                continue
            fine_integrals = {j: _integrate_contour(f2, float(w[j]) * tau) for j in group}
            if all(v is None for v in fine_integrals.values()):
                # no member resolved on the fine grid: the coarse contour could not change
                # that, so it is not computed.  If the contour did not decay (Fig. 8 model,
                # tau = 1: |G| levels off at ~1e-6 with 48 modes, a basis artifact -- 96 and
                # 144 modes decay below 1e-9), the group retries with twice the modes
                # instead of sending each W off alone with 48 (measured on the report's quick
                # bins: 7.7 -> 4.3 CPU-s, and those W moved from up to 3.1e-5 to <= 7.6e-7 of
                # the 96-mode per-W values)
                if f2[2] is not None:
                    continue
                break
            red1 = _Reduced(model, red2.k0, g1, m, propagator)
            K1 = red1.log_g_and_derivatives(kc, tau)[0]
            f1 = _contour_values(red1, kc, tau, K1, curvc)
            for j in group:
                W = float(w[j]) * tau
                i2 = fine_integrals[j]
                i1 = _integrate_contour(f1, W) if f1 is not None else None
                if i2 is None or i1 is None:
                    continue
                fine, coarse = K2 + math.log(i2), K1 + math.log(i1)
                if abs(fine - coarse) > _RICHARDSON_GAP:   # the grids disagree: not resolved
                    continue
                log_p = (4.0 * fine - coarse) / 3.0
                out[j] = math.exp(math.log(tau) + log_p - kc * W - math.log(math.pi))
            break
        if np.isnan(out[i]):     # the lowest W not resolved by its group: alone, as before
            out[i] = _work_pdf_one(model, float(w[i]), tau, h, modes, mean, propagator,
                                   root=(float(k0s[i]), float(lams[i])))
        # members not resolved stay for a later group, centred nearer to them
        todo = [j for j in todo if np.isnan(out[j])]
    return out


def _contour_values(red: _Reduced, kc: float, tau: float, K: float,
                    curv: float) -> tuple[float, np.ndarray, tuple[float, float] | None] | None:
    """``(dy, f, tail)``: ``f_j = G(k_c + i y_j)/G(k_c)`` on ``y_j = j dy`` (dy =
    _DY_SHARED/sqrt(K'')) until it decays below _TOL (``tail`` None), or up to _Y_MAX_SHARED widths
    (``tail = (last, rate)`` for the per-W tail test of :func:`_integrate_contour`); None when
    the reduced generating function violates ``|G(k_c + iy)| <= G(k_c)`` (basis too small)."""
    sy = 1.0 / math.sqrt(curv)
    dy = _DY_SHARED * sy
    shift = K / tau
    chunks = []
    start = 0
    while True:
        y = dy * np.arange(start, start + _CHUNK)
        f = np.exp(red.log_g_complex(kc + 1j * y, tau, shift) + tau * shift - K)
        if not np.all(np.isfinite(f)) or np.max(np.abs(f)) > 1.0 + 1e-6:
            return None
        chunks.append(f)
        start += _CHUNK
        last = float(np.max(np.abs(f[-3:])))
        if last < _TOL:
            return dy, np.concatenate(chunks), None
        if y[-1] > _Y_MAX_SHARED * sy:
            prev = float(np.max(np.abs(chunks[-2][-3:])))
            rate = math.log(max(prev, 1e-300) / max(last, 1e-300)) / (_CHUNK * dy)
            return dy, np.concatenate(chunks), (last, rate)


def _integrate_contour(values: tuple[float, np.ndarray, tuple[float, float] | None] | None,
                       W: float) -> float | None:
    """``int_0^inf Re[f(y) e^{-iyW}] dy`` by the trapezoid rule, or None if not positive or if
    an undecayed tail may exceed 1e-4 of it (the tests of :func:`_contour_integral`), or if the
    result is below 1e-6 of the integrand's scale (cancellation: W too far from the contour's
    saddle)."""
    if values is None:
        return None
    dy, f, tail = values
    g = f * np.exp(-1j * dy * np.arange(f.size) * W)
    integral = dy * (0.5 * g[0].real + g[1:].real.sum())
    if not integral > 0:
        return None
    if tail is not None:
        last, rate = tail
        if not (rate > 0 and last / rate < 1e-4 * integral):
            return None
    # |f| <= 1 over a width ~1/sd (a Gaussian tilted law gives sqrt(pi/2)/sd at W = K' and
    # 0.17/sd at 2 sd); far below that the sum is mostly cancellation of round-off (~1e-10):
    # measured in the stick regime (Fig. 8 model, tau = 2), where the tilted law is far from
    # Gaussian, members accepted down to 1e-6/sd came out wrong by factors up to 1e9
    if integral < _MIN_SHARED * dy / _DY_SHARED:
        return None
    return float(integral)


class _Reduced:
    """``S_k`` restricted to the top eigenvectors of ``S_{k0}`` on one grid."""

    def __init__(self, model: Model, k0: float, grid: Grid, modes: int, propagator: str = "expm"):
        self.propagator = propagator
        d0, e = tilted_operator(model, grid, 0.0)
        v = grid.v
        n = grid.n
        m = min(modes, n)
        # Discrete ground state of S_0 (sqrt(pi) up to O(h^2)); its eigenvalue (0 up to O(h^2))
        # is subtracted so that G(0) = 1 exactly.
        lam0, s = linalg.eigh_tridiagonal(d0, e, select="i", select_range=(n - 1, n - 1))
        s = s[:, 0]
        mu, phi = linalg.eigh_tridiagonal(d0 - lam0[0] + k0 * model.force * v, e, select="i",
                                          select_range=(n - m, n - 1))
        self.c = phi.T @ s
        self.captured = float(self.c @ self.c)
        self.mu = mu
        self.B = (phi.T * (model.force * v)) @ phi
        self.k0 = k0

    def matrix(self, k: ArrayLike) -> np.ndarray:
        k = np.atleast_1d(k)
        out: np.ndarray = np.diag(self.mu)[None] + (k - self.k0)[:, None, None] * self.B[None]
        return out

    def log_g_and_derivatives(self, k: float, tau: float) -> tuple[float, float]:
        """ln G(k), d/dk ln G and d^2/dk^2 ln G for real k (eigen-decomposition + Daleckii-Krein)."""
        mu, U = np.linalg.eigh(self.matrix(k)[0])
        top = mu.max()
        z = U.T @ self.c
        e = np.exp(tau * (mu - top))
        G = float(np.sum(z * z * e))
        Bt = U.T @ self.B @ U
        dmu = mu[:, None] - mu[None, :]
        with np.errstate(divide="ignore", invalid="ignore"):
            dd = np.where(np.abs(dmu) > 1e-12 * max(1.0, abs(top)),
                          (e[:, None] - e[None, :]) / np.where(dmu == 0, 1.0, dmu),
                          tau * 0.5 * (e[:, None] + e[None, :]))
        dG = float(z @ (Bt * dd) @ z)
        return tau * top + math.log(G), dG / G

    def log_g_complex(self, k: complex | np.ndarray, tau: float, shift: float) -> np.ndarray:
        """ln G at complex k (array), relative to exp(tau*shift)."""
        A = self.matrix(np.asarray(k, dtype=complex))
        if self.propagator == "expm":
            # Only <c|exp(tau A)|c> is needed, not the modes: the batched Pade exponential
            # costs about a third of eig + solve (measured 0.05 vs 0.12 s per batch of 12
            # 96 x 96 matrices, single-threaded under load) and avoids the ill-conditioned
            # eigenvector inverse.  exp(tau (A - shift)) keeps the values O(1).
            n = self.mu.size
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                try:
                    E = linalg.expm(tau * (A - shift * np.eye(n)))
                except (np.linalg.LinAlgError, ValueError):  # overflow: the caller retries
                    return np.full(A.shape[0], np.nan + 0j)
                out: np.ndarray = np.log(np.einsum("i,kij,j->k", self.c, E, self.c))
                return out
        # A is complex symmetric: A = V diag(mu) V^-1, and c^T V = (V^T c)^T.
        mu, V = np.linalg.eig(A)
        left = np.einsum("i,kij->kj", self.c, V)
        right = np.linalg.solve(V, np.broadcast_to(self.c.astype(complex), mu.shape)[..., None])[..., 0]
        # a failing basis shows up as overflow/NaN here; the caller checks and retries
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            log_g: np.ndarray = np.log(np.sum(left * right * np.exp(tau * (mu - shift)), axis=-1))
            return log_g


def _work_pdf_one(model: Model, w: float, tau: float, h: float, modes: int, mean: float,
                  propagator: str = "expm", root: tuple[float, float] | None = None) -> float:
    """ln p on the fine grid (h/2) by the contour integral, with the O(h^2) grid error of the
    saddle term ``K(k*) - k* W`` (the eigenvalue error times tau) removed by Richardson
    extrapolation against the coarse grid h at the same k*; the remaining factor (the contour
    integral, O(1)) carries only an O(h^2) relative error and is taken from the fine grid.

    Robustness: the reduced (Galerkin) generating function is checked against the bound
    ``|G(k*+iy)| <= G(k*)`` that every moment generating function obeys; if it fails (the
    mode basis at the Legendre point k0 cannot represent the far tail), two more bases are
    tried (twice the modes at k0, then twice the modes centred on the finite-tau saddle), and
    if all three fail the large-deviation form of :func:`work_pdf` is returned (ln p right to
    O(1); only reached far in the tail, at densities far below 1e-8).
    """
    # root: (k0, lambda(k0)) already solved by the caller's sweep (the same equation,
    # lambda'(k0) = w, bracketed from a neighbour instead of from k = 0)
    k0, lam = root if root is not None else _legendre_root(model, w, h, mean)[:2]
    W = w * tau
    g1 = _grid_for(model, k0, h, extra=_tilt_centres(model, 0.0))
    g2 = Grid(h / 2.0, 2 * g1.i_min, 2 * g1.i_max)
    ks = k0
    # attempts: the basis at the Legendre point k0, twice the modes there, twice the modes
    # centred on the finite-tau saddle (at short tau it can lie far from k0)
    for m, centre in ((modes, False), (2 * modes, False), (2 * modes, True)):
        kb = ks if centre else k0
        red2 = _Reduced(model, kb, g2, m, propagator)
        ks, K2, curv = _saddle(model, red2, W, tau, kb)
        integral = _contour_integral(red2, ks, W, tau, K2, curv)
        if integral is not None:
            red1 = _Reduced(model, red2.k0, g1, m, propagator)
            K1 = red1.log_g_and_derivatives(ks, tau)[0]
            # the contour integral on the coarse grid too (same k*, any real point is exact):
            # its O(h^2) error grows into the tails (1e-4 at 8 standard deviations)
            integral1 = _contour_integral(red1, ks, W, tau, K1, curv) or integral
            log_p = (4.0 * (K2 + math.log(integral)) - (K1 + math.log(integral1))) / 3.0
            return math.exp(math.log(tau) + log_p - ks * W - math.log(math.pi))
    # Fallback (far tail): large-deviation density with the Gaussian (Bahadur-Rao) prefactor
    # from the principal eigenpair and the overlap factor of the stationary state with the
    # tilted ground state (from log-space ground states: far below 1e-16, eigenvectors alone
    # cannot give it); the finite-tau boundary terms of ln G are left out, so ln p is right to
    # O(1), i.e. -ln p / tau to O(1/tau).
    _note_fallback(w, tau)
    d = 1e-4 * max(abs(k0), 1.0)
    lpp = (_scgf_pair(model, k0 + d, h, check=False)[1]
           - _scgf_pair(model, k0 - d, h, check=False)[1]) / (2 * d)
    log_overlap = 2.0 * (_log_overlap(model, g2, k0))
    p = math.exp(log_overlap - tau * (k0 * w - lam)
                 + 0.5 * math.log(tau / (2.0 * math.pi * max(lpp, 1e-300))))
    if p > 1e-8:
        warnings.warn(f"work_pdf: contour not resolved at w={w:g}, tau={tau:g} with up to "
                      f"{2 * modes} modes; large-deviation fallback {p:.3g} may be off by a "
                      "large factor: pass a larger modes", RuntimeWarning, stacklevel=3)
    return p


def _log_ground_state(d: np.ndarray, c: float, lam: float, phi: np.ndarray) -> np.ndarray:
    """ln of a positive tridiagonal ground state ``c phi_{i-1} + d_i phi_i + c phi_{i+1} =
    lam phi_i`` with tails far below round-off: the eigen-solver's vector (accurate only to
    1e-16 of its peak) anchors the peak, the ratios phi_{i-1}/phi_i (from the left end) and
    phi_{i+1}/phi_i (from the right end) continue it outwards, each recursion run in its
    stable direction (towards the peak).  Sequential in i by nature."""
    n = d.size
    x = (d - lam) / c
    q = np.zeros(n)          # q[i] = phi_{i-1}/phi_i
    r = np.zeros(n)          # r[i] = phi_{i+1}/phi_i
    for i in range(n - 1):
        q[i + 1] = -1.0 / (x[i] + q[i])
    for i in range(n - 1, 0, -1):
        r[i - 1] = -1.0 / (x[i] + r[i])
    j = int(np.argmax(np.abs(phi)))
    out = np.empty(n)
    out[j] = math.log(abs(phi[j]))
    with np.errstate(divide="ignore", invalid="ignore"):
        lq = np.log(np.where(q > 0, q, np.nan))
        lr = np.log(np.where(r > 0, r, np.nan))
    out[:j] = out[j] + np.cumsum(lq[j:0:-1])[::-1]
    out[j + 1:] = out[j] + np.cumsum(lr[j:n - 1])
    return out


def _log_overlap(model: Model, grid: Grid, k: float) -> float:
    """ln <phi_k|phi_0> of the normalised principal eigenvectors of S_k and S_0 (both
    positive), with the tails from :func:`_log_ground_state`, so that overlaps far below
    1e-16 (tilted states far from the stationary one) are resolved."""
    from scipy.special import logsumexp
    logs = []
    for kk in (k, 0.0):
        d, e = tilted_operator(model, grid, kk)
        n = grid.n
        lam, vec = linalg.eigh_tridiagonal(d, e, select="i", select_range=(n - 1, n - 1))
        lphi = _log_ground_state(d, e[0], lam[0], vec[:, 0])
        lphi = np.where(np.isfinite(lphi), lphi, -np.inf)
        logs.append(lphi - 0.5 * logsumexp(2.0 * lphi))
    return float(logsumexp(logs[0] + logs[1]))


_FALLBACK_LOG: ContextVar[list[tuple[float, float]] | None] = ContextVar(
    "work_pdf_fallbacks", default=None)


@contextmanager
def recorded_fallbacks() -> Iterator[list[tuple[float, float]]]:
    """Collect the ``(w, tau)`` at which :func:`work_pdf` fell back to the large-deviation
    form inside the block (diagnostics, benchmarks): ``with recorded_fallbacks() as fb:``.
    Nothing is kept outside such a block."""
    log: list[tuple[float, float]] = []
    token = _FALLBACK_LOG.set(log)
    try:
        yield log
    finally:
        _FALLBACK_LOG.reset(token)


def _note_fallback(w: float, tau: float) -> None:
    log = _FALLBACK_LOG.get()
    if log is not None:
        log.append((w, tau))


def _saddle(model: Model, red: _Reduced, W: float, tau: float,
            k0: float) -> tuple[float, float, float]:
    """Real saddle k* of ``ln G(k) - k W`` (ln G convex, so its derivative is increasing),
    ``K(k*)`` and ``K''(k*)``.  Any real point gives the same integral; the saddle only makes
    the contour integral well-conditioned, so k* is needed to a fraction of 1/sqrt(K'')."""
    def dK(k: float) -> float:
        return red.log_g_and_derivatives(k, tau)[1] - W

    scale = max(abs(k0), model.gamma / (model.force**2 * model.tau_m * max(tau, model.tau_m)))
    lo, hi = k0 - 0.25 * scale, k0 + 0.25 * scale
    for _ in range(200):
        if dK(lo) < 0:
            break
        lo -= (hi - lo)
    for _ in range(200):
        if dK(hi) > 0:
            break
        hi += (hi - lo)
    ks = optimize.brentq(dK, lo, hi, xtol=1e-6 * scale, rtol=1e-10)
    K, _ = red.log_g_and_derivatives(ks, tau)
    eps = 1e-5 * scale
    curv = max((dK(ks + eps) - dK(ks - eps)) / (2 * eps), 1e-300)
    return ks, K, curv


_CHUNK = 12        # y nodes per batch of dense eigen-decompositions
_DY = 0.7          # trapezoid step in units of the saddle width 1/sqrt(K'')
_TOL = 1e-9        # integrand (relative to its value at the saddle) counted as negligible:
                   # above the round-off floor (~1e-10) of the ill-conditioned complex eigenvectors


def _contour_integral(red: _Reduced, ks: float, W: float, tau: float, K: float,
                      curv: float) -> float | None:
    """``int_0^inf Re[G(k*+iy) e^{-iyW}] dy / (G(k*) e^{-k* W})`` by the trapezoid rule (step
    0.7/sqrt(K''): error ~exp(-2 pi^2/0.7^2) ~ 3e-18 for a Gaussian integrand), or None when
    the reduced integrand violates ``|G(k*+iy)| <= G(k*)`` (a property of every moment
    generating function), or when it has not decayed within 150 saddle widths to where the
    remaining tail (bounded by its size times its decay length) is below 1e-4 of the integral.
    In the stick regime the tilted law of W can hold a sharp peak near W = 0 (windows spent
    stuck), whose characteristic function decays slowly: the y range adapts to it."""
    sy = 1.0 / math.sqrt(curv)
    dy = _DY * sy
    shift = K / tau
    chunks = []
    start = 0
    while True:
        y = dy * np.arange(start, start + _CHUNK)
        f = np.exp(red.log_g_complex(ks + 1j * y, tau, shift) - 1j * y * W + tau * shift - K)
        if not np.all(np.isfinite(f)) or np.max(np.abs(f)) > 1.0 + 1e-6:
            return None
        chunks.append(f)
        start += _CHUNK
        last = np.max(np.abs(f[-3:]))
        if last < _TOL:
            break
        if y[-1] > 150.0 * sy:
            g = np.concatenate(chunks)
            integral = dy * (0.5 * g[0].real + g[1:].real.sum())
            # tail decay length from the envelope over the last two chunks
            prev = np.max(np.abs(chunks[-2][-3:]))
            rate = math.log(max(prev, 1e-300) / max(last, 1e-300)) / (_CHUNK * dy)
            if integral > 0 and rate > 0 and last / rate < 1e-4 * integral:
                break
            return None
    f = np.concatenate(chunks)
    integral = dy * (0.5 * f[0].real + f[1:].real.sum())
    return integral if integral > 0 else None
