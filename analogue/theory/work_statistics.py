"""Exact finite-noise statistics of the work ``W_tau = F int_0^tau v ds`` (eq. work) in the
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
contains the h grid).

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
    I_0(w) = L(0, w/F) = (1/4) U'(w/F)^2 for w != 0 (the paper's eq. Iw),
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
paper's eq. ftexp ``w/(m tau_m) + a Delta`` once both sides are on their parabolas.
"""
from __future__ import annotations

import math
import warnings

import numpy as np
from scipy import integrate, linalg, optimize

from ..checks import finite_array as _finite_array
from ..model import Model
from .fokker_planck import Grid

try:
    from threadpoolctl import threadpool_limits as _threadpool_limits
except ImportError:  # pragma: no cover - declared dependency; only speed depends on it
    _threadpool_limits = None


def _single_threaded():
    """Context limiting BLAS/LAPACK to one thread (a no-op without threadpoolctl)."""
    import contextlib
    return _threadpool_limits(1) if _threadpool_limits is not None else contextlib.nullcontext()

__all__ = ["scgf", "scgf_derivative", "rate_function", "work_pdf", "work_rate_mean",
           "paper_rate_function", "weak_noise_limit_rate_function", "tilted_grid_spacing",
           "tilted_operator"]

_TAIL = 40.0           # ground states are resolved down to exp(-TAIL) in probability
_PPW = 20.0            # minimum nodes per stationary width sqrt(tau_m/gamma)
_MAX_NODES = 2_000_000


# ---------------------------------------------------------------------------- validation
def _check_model(model) -> Model:
    if not isinstance(model, Model):
        raise ValueError(f"model must be an analogue.Model, got {type(model).__name__}")
    return model


def _force(model: Model) -> float:
    if model.force == 0:
        raise ValueError("a must be != 0: for a == 0 the work W = m a int v vanishes identically")
    return model.force



# ----------------------------------------------------------------------------- grids
def _reach(model: Model) -> float:
    """Half-width around a ground-state centre outside which its weight is below e^-TAIL."""
    return math.sqrt(2.0 * _TAIL * model.tau_m / model.gamma) + 4.0 * model.velocity_scale


def _tilt_centres(model: Model, k) -> np.ndarray:
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


def tilted_operator(model: Model, grid: Grid, k: float = 0.0):
    """``(diag, off)`` of the symmetric tridiagonal discretisation of the tilted generator
    ``S_k = (1/gamma) d^2/dv^2 - V(v) + k F v``, ``V = gamma U'^2/4 - U''/2`` (ground-state
    transform of the Fokker-Planck operator, detailed balance).

    Far from v = 0, V is evaluated pointwise (central differences: O(h^2) relative to the
    ground-state width, whatever the tilt; the Scharfetter-Gummel form would need
    ``gamma h |U'| << 1``, prohibitive for large tilts).  Within ``|v| <= tau_m (Delta + |a|)``
    V is the exact discrete ground-state transform of ``exp(-gamma U/2)``,
    ``V_i = (1/(gamma h^2)) sum_{+-} (exp(-gamma (U_{i+-1} - U_i)/2) - 1)``, which carries the
    delta function of ``U''`` at the kink of the sgn law (eq. U_pot) exactly: the stationary
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


def _grid_for(model: Model, k: float, h: float, extra=()) -> Grid:
    c = _tilt_centres(model, k)
    pts = np.concatenate([c, np.asarray(extra, dtype=float)])
    r = _reach(model)
    grid = Grid.span(float(pts.min()) - r, float(pts.max()) + r, h)
    if grid.n > _MAX_NODES:
        raise ValueError(f"the tilt needs {grid.n} grid nodes (> {_MAX_NODES}); "
                         "reduce the range of k or w, or pass a coarser h")
    return grid


# ------------------------------------------------------------------ principal eigenpair
def _principal(model: Model, k: float, grid: Grid):
    """Principal eigenvalue and Hellmann-Feynman derivative ``F <phi| v |phi>``."""
    d, e = tilted_operator(model, grid, k)
    v = grid.v
    lam, vec = linalg.eigh_tridiagonal(d, e, select="i",
                                       select_range=(grid.n - 1, grid.n - 1))
    phi = vec[:, 0]
    return float(lam[0]), model.force * float(np.dot(phi * phi, v))


def _scgf_pair(model: Model, k: float, h: float, check: bool = True):
    """Richardson-extrapolated (lambda, lambda') from spacings h and h/2."""
    g1 = _grid_for(model, k, h)
    g2 = Grid(h / 2.0, 2 * g1.i_min, 2 * g1.i_max)
    l1, d1 = _principal(model, k, g1)
    l2, d2 = _principal(model, k, g2)
    lam = (4.0 * l2 - l1) / 3.0
    der = (4.0 * d2 - d1) / 3.0
    if check:
        # natural eigenvalue scale: the Schroedinger potential gamma U'^2/4 near the attractor
        scale = max(1.0, abs(lam), 1e-2 * model.gamma * (model.delta + abs(model.a)) ** 2)
        if abs(l2 - l1) > 0.05 * scale:
            warnings.warn(f"scgf at k={k:g} not converged in h (h={h:g}: {l1:g}, h/2: {l2:g}); "
                          "pass a smaller h", RuntimeWarning, stacklevel=3)
    return lam, der


def scgf(model: Model, k, *, h: float | None = None):
    """Scaled cumulant generating function ``lambda(k) = lim (1/tau) ln E exp(k W_tau)``.

    Principal eigenvalue of the symmetrised tilted generator ``S_0 + k F diag(v)`` (Touchette,
    Prellberg & Just 2012; the Legendre dual of the paper's eq. largeDev rate function, with
    ``gamma I(w) = sup_k [k w - lambda(k)]``).  Vectorised over k.  The grid covers every
    place the tilted eigenvector can sit, its spacing comes from :func:`tilted_grid_spacing`
    (or ``h``), and values on h and h/2 are Richardson-extrapolated; a RuntimeWarning flags an
    unconverged grid.
    """
    return _scgf_and_derivative(model, k, h)[0]


def scgf_derivative(model: Model, k, *, h: float | None = None):
    """``lambda'(k)`` by Hellmann-Feynman: ``F <phi_k| v |phi_k>`` (the tilted mean work rate)."""
    return _scgf_and_derivative(model, k, h)[1]


def _scgf_and_derivative(model, k, h):
    model = _check_model(model)
    k = _finite_array("k", k)
    if h is None:
        h = tilted_grid_spacing(model)
    out = np.array([_scgf_pair(model, float(kk), h) for kk in k.ravel()]).reshape(k.shape + (2,))
    return out[..., 0], out[..., 1]


# ---------------------------------------------------------------------- rate function
def work_rate_mean(model: Model) -> float:
    """``<w> = F <v>`` with ``<v>`` by quadrature of the exact stationary law (eq. p_stat)."""
    model = _check_model(model)
    c = model.potential_minimum()
    r = _reach(model)
    pts = sorted({0.0, c})
    val, _ = integrate.quad(lambda v: v * float(model.stationary_pdf(v)), c - r, c + r,
                            points=[p for p in pts if c - r < p < c + r], limit=400,
                            epsabs=1e-14, epsrel=1e-12)
    return model.force * val


def _k_guess(model: Model, w):
    """k whose weak-noise tilt centre is at v = w/F (OU-like: lambda'(k) ~ F tau_m (2kF tau_m/gamma + a))."""
    F, tm, g = model.force, model.tau_m, model.gamma
    return g * (w / F - tm * model.a) / (2.0 * F * tm * tm)


def _legendre_root(model: Model, w: float, h: float, mean: float):
    """k with lambda'(k) = w, bracketed from k = 0 (where lambda'(0) = <w>) outwards."""
    if w == mean:
        return 0.0, 0.0
    f = lambda k: _scgf_pair(model, k, h, check=False)[1] - w
    side = 1.0 if w > mean else -1.0
    step = max(abs(_k_guess(model, w)), model.gamma / (model.force**2 * model.tau_m**2) * 1e-3,
               1e-12)
    lo, hi = 0.0, side * step
    for _ in range(200):
        if side * f(hi) > 0:
            break
        lo, hi = hi, 2.0 * hi
    else:  # pragma: no cover - lambda' is unbounded, so this cannot happen on a valid grid
        raise RuntimeError(f"could not bracket the Legendre root for w={w:g}")
    a, b = (lo, hi) if lo < hi else (hi, lo)
    # I = k w - lambda(k) is stationary in k at the root: k to 1e-9 gives I to ~1e-18.
    k = optimize.brentq(f, a, b, xtol=1e-9 * max(1.0, abs(b)), rtol=1e-12, maxiter=200)
    return k, _scgf_pair(model, k, h)[0]


def rate_function(model: Model, w, *, h: float | None = None):
    """Exact rate function ``I(w) = (1/gamma) sup_k [k w - lambda(k)]`` in the paper's scaling
    ``P_tau(w) ~ exp(-tau gamma I(w))`` (eqs. largeDev, eqi1).

    For each w the maximiser solves ``lambda'(k) = w`` (Hellmann-Feynman derivative) with a
    bracketing root finder (Brent), so the transform is accurate to the eigenvalue's accuracy.
    ``I(<w>) = 0`` at ``<w> = F <v>``.  Vectorised over w.
    """
    model = _check_model(model)
    _force(model)
    w = _finite_array("w", w)
    if h is None:
        h = tilted_grid_spacing(model)
    mean = float(_scgf_pair(model, 0.0, h)[1])
    out = np.empty(w.size)
    for i, wi in enumerate(w.ravel()):
        k, lam = _legendre_root(model, float(wi), h, mean)
        out[i] = max(k * wi - lam, 0.0) / model.gamma
    return out.reshape(w.shape)


# --------------------------------------------------------------- weak-noise objects
def paper_rate_function(model: Model, w):
    """The paper's eq. Iw, ``I(w) = (1/4)(w/(m a tau_m) + sgn(w) Delta - a)^2`` (at w = 0 the
    formula is ambiguous; sgn(0) = 0 is used)."""
    model = _check_model(model)
    F = _force(model)
    v = _finite_array("w", w) / F
    return 0.25 * (v / model.tau_m + np.sign(v) * model.delta - model.a) ** 2


def _envelope_right(v, a, delta, tm):
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


def weak_noise_limit_rate_function(model: Model, w):
    """``lim_{gamma -> inf} I_gamma(w)``: the lower convex envelope of the cost of holding the
    velocity at ``v = w/F`` (see the module docstring for the derivation).

    ``I_0(w) = (1/4)(v/tau_m + Delta sgn v - a)^2`` for v != 0 (the paper's eq. Iw) and
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
def work_pdf(model: Model, w, tau, *, h: float | None = None, modes: int = 48):
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
    for finite inputs; the (w, tau) of fallbacks are appended to ``_FALLBACKS``, and a
    RuntimeWarning is issued when a fallback density exceeds 1e-8.
    Cost: per w, a Legendre root of the SCGF, two tridiagonal eigen-solves of ``modes``
    vectors and 12-120 dense complex ``modes x modes`` eigen-decompositions per grid
    (the y range adapts to the slowly decaying characteristic function of the stick regime);
    BLAS is limited to one thread meanwhile.
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
    modes = int(modes)
    if modes < 4:
        raise ValueError(f"modes must be >= 4, got {modes}")
    if h is None:
        h = tilted_grid_spacing(model)
    # The many small dense eigen-problems run 10-30x faster single-threaded than under
    # OpenBLAS threading (thread start-up dominates at 48 x 48).
    with _single_threaded():
        mean = float(_scgf_pair(model, 0.0, h, check=False)[1])
        out = np.empty(w.size)
        for i, wi in enumerate(w.ravel()):
            out[i] = _work_pdf_one(model, float(wi), tau, h, modes, mean)
    return out.reshape(w.shape)


class _Reduced:
    """``S_k`` restricted to the top eigenvectors of ``S_{k0}`` on one grid."""

    def __init__(self, model: Model, k0: float, grid: Grid, modes: int):
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

    def matrix(self, k):
        k = np.atleast_1d(k)
        return np.diag(self.mu)[None] + (k - self.k0)[:, None, None] * self.B[None]

    def log_g_and_derivatives(self, k: float, tau: float):
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

    def log_g_complex(self, k: complex | np.ndarray, tau: float, shift: float):
        """ln G at complex k (array), relative to exp(tau*shift)."""
        A = self.matrix(np.asarray(k, dtype=complex))
        # A is complex symmetric: A = V diag(mu) V^-1, and c^T V = (V^T c)^T.
        mu, V = np.linalg.eig(A)
        left = np.einsum("i,kij->kj", self.c, V)
        right = np.linalg.solve(V, np.broadcast_to(self.c.astype(complex), mu.shape)[..., None])[..., 0]
        # a failing basis shows up as overflow/NaN here; the caller checks and retries
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            return np.log(np.sum(left * right * np.exp(tau * (mu - shift)), axis=-1))


def _work_pdf_one(model, w, tau, h, modes, mean):
    """ln p on the fine grid (h/2) by the contour integral, with the O(h^2) grid error of the
    saddle term ``K(k*) - k* W`` (the eigenvalue error times tau) removed by Richardson
    extrapolation against the coarse grid h at the same k*; the remaining factor (the contour
    integral, O(1)) carries only an O(h^2) relative error and is taken from the fine grid.

    Robustness: the reduced (Galerkin) generating function is checked against the bound
    ``|G(k*+iy)| <= G(k*)`` that every moment generating function obeys; if it fails (the
    mode basis at the Legendre point k0 cannot represent the far tail), the basis is doubled
    once, and if that fails too the leading-order saddle-point formula with exact tilting,
    ``p_W = exp(K(k*) - k* W) / sqrt(2 pi K''(k*))``, is returned (relative error O(1/tau);
    only reached far in the tail, at densities far below 1e-8).
    """
    k0, lam = _legendre_root(model, w, h, mean)
    W = w * tau
    g1 = _grid_for(model, k0, h, extra=_tilt_centres(model, 0.0))
    g2 = Grid(h / 2.0, 2 * g1.i_min, 2 * g1.i_max)
    ks = k0
    # attempts: the basis at the Legendre point k0, twice the modes there, twice the modes
    # centred on the finite-tau saddle (at short tau it can lie far from k0)
    for m, centre in ((modes, False), (2 * modes, False), (2 * modes, True)):
        kb = ks if centre else k0
        red2 = _Reduced(model, kb, g2, m)
        ks, K2, curv = _saddle(model, red2, W, tau, kb)
        integral = _contour_integral(red2, ks, W, tau, K2, curv)
        if integral is not None:
            red1 = _Reduced(model, red2.k0, g1, m)
            K1 = red1.log_g_and_derivatives(ks, tau)[0]
            # the contour integral on the coarse grid too (same k*, any real point is exact):
            # its O(h^2) error grows into the tails (1e-4 at 8 standard deviations)
            integral1 = _contour_integral(red1, ks, W, tau, K1, curv) or integral
            log_p = (4.0 * (K2 + math.log(integral)) - (K1 + math.log(integral1))) / 3.0
            return math.exp(math.log(tau) + log_p - ks * W - math.log(math.pi))
    # Fallback (far tail): large-deviation density with the Gaussian (Bahadur-Rao) prefactor
    # from the principal eigenpair only; the overlap factor of the stationary state with the
    # tilted ground state (too small to compute from eigenvectors in floating point) is left
    # out, so ln p is right to O(1), i.e. -ln p / tau to O(1/tau).
    _FALLBACKS.append((w, tau))
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


def _log_ground_state(d, c, lam, phi):
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


def _log_overlap(model, grid, k):
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


_FALLBACKS: list = []   # (w, tau) of large-deviation fallbacks, for diagnostics and tests


def _saddle(model, red, W, tau, k0):
    """Real saddle k* of ``ln G(k) - k W`` (ln G convex, so its derivative is increasing),
    ``K(k*)`` and ``K''(k*)``.  Any real point gives the same integral; the saddle only makes
    the contour integral well-conditioned, so k* is needed to a fraction of 1/sqrt(K'')."""
    def dK(k):
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


def _contour_integral(red, ks, W, tau, K, curv):
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
