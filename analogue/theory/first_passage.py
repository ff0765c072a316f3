"""First passage to rest: the time ``T`` for a path started at ``v0 != 0`` to first reach
``v = 0`` (not in the paper; issue 23 item 2).  One-dimensional Gaussian-noise members (the
paper's model and every gradient member of the family).

By the mirror symmetry ``f(v, t | v0; a) = f(-v, t | -v0; -a)`` (every friction law of the
family is odd) a start ``v0 < 0`` is the start ``-v0`` of the model with ``-a``; below,
``v0 > 0``.

Distribution.  The Fokker-Planck equation on ``v > 0`` with an absorbing boundary at 0: on the
Scharfetter-Gummel grid of :mod:`analogue.theory.fokker_planck` (``v0`` on a node, ``v = 0`` a
node) the node 0 is removed (``p_0 = 0``), which leaves the sub-generator ``L_+`` of the nodes
``v > 0``, tridiagonal and similar to a symmetric negative definite matrix.  The survival
``S(t) = P(T > t) = 1^T e^{L_+ t} delta_{v0}`` and the density ``f(t) = -dS/dt = k_{1->0}
p_1(t)`` (the probability flux into the absorbed node) come from the Talbot contour of
:mod:`analogue.theory.propagation` (a few dozen complex tridiagonal solves per time, O(n);
``expm_multiply`` for starts too deep in the tail of the stationary law).  Moments:
``E T = 1^T (-L_+)^{-1} delta_{v0}``, ``E T^2 = 2 1^T (-L_+)^{-2} delta_{v0}`` (two real
tridiagonal solves).  Grids h and h/2 are Richardson-combined (second order).

Mean by quadrature (the backward equation ``(1/gamma) T'' - U' T' = -1``, ``T(0) = 0``,
``T'(inf) = 0``):

    T(v0) = gamma int_0^{v0} dy e^{gamma U(y)} int_y^inf e^{-gamma U(z)} dz,     v0 > 0.

For the sgn law on ``v > 0``, ``gamma U = (z - mu)^2/(2 s^2) + const`` with
``mu = (a - Delta) tau_m``, ``s^2 = tau_m/gamma``, so the inner integral is closed:
``e^{gamma U(y)} int_y^inf e^{-gamma U} = s sqrt(pi/2) erfcx((y - mu)/(s sqrt 2))`` and

    T(v0) = gamma s sqrt(pi/2) int_0^{v0} erfcx((y - mu)/(s sqrt 2)) dy

(Gauss-Legendre); other laws by nested adaptive quadrature.  Weak-noise limit (stick side,
``mu < 0``): ``erfcx(x) ~ 1/(sqrt(pi) x)`` gives ``T -> tau_m ln(1 + v0/((Delta - a) tau_m))
= t_a`` (eq. (31), :meth:`analogue.Model.stick_time`), with a correction of relative order
``tau_m/(gamma (Delta - a)^2 tau_m^2)``.

Accuracy (tests/unit/test_theory_first_passage.py; measured at tau_m = 1, Delta = 0.7,
a = 0.2): the grid mean equals the quadrature formula to 2e-9 - 4e-8 relative (gamma 10 -
100, v0 = -1, 0.3, 1); the survival integrates to the mean (4e-10) and the density to 1;
the erfcx closed form equals the nested quadrature to 1e-10; ``T - t_a`` = -1.7e-2, -1.8e-3,
-1.8e-4 at gamma = 1e2, 1e3, 1e4 (v0 = 1): O(1/gamma).  Cost: moments 1 ms, the law 2 ms
per time (contour).
"""
from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike
from scipy import integrate, sparse, special
from scipy.linalg import lapack
from scipy.sparse.linalg import expm_multiply

from .. import checks
from ..model import Model
from .exact_grid import resolved_grid
from .fokker_planck import Grid, generator, symmetric_generator
from .kolmogorov_feller import _grid_range, default_spacing
from .propagation import _talbot, amplification, contour_nodes

__all__ = ["first_passage_survival", "first_passage_density", "first_passage_moments",
           "first_passage_mean", "mean_slope_at_rest"]


def _upper(model: Model, v0: object) -> tuple[Model, float]:
    """``(model', v0')`` with ``v0' > 0``: the mirror image ``a -> -a`` for starts below 0."""
    checks.instance("model", model, Model, description="an analogue.Model")
    if not model.is_gradient:
        raise ValueError("first passage to rest is implemented for the 1-D Gaussian-noise members "
                         "(spring = 0, shot = None, finite gamma); with kicks a path can jump "
                         "across v = 0 without reaching it")
    x = checks.finite("v0", v0)
    if x == 0:
        raise ValueError("v0 must be != 0 (a diffusion started at v = 0 is there at once)")
    return (model, x) if x > 0 else (model.replace(a=-model.a), -x)


def _grids(model: Model, v0: float, h: float | None) -> tuple[Grid, Grid]:
    """Grids (h', h'/2) covering the stationary law and ``v0`` (the project's grids: those of
    the propagator for the paper's model, of :mod:`.family` otherwise), with h' <= h chosen so
    that ``v0`` is a node of both."""
    if model.is_paper:
        g = resolved_grid(model, extra=(v0,), h=h)
        lo, hi, step = g.v[0], g.v[-1], g.h
    else:
        step = default_spacing(model) if h is None else checks.positive("h", h)
        lo, hi = _grid_range(model, (v0,))
    step = v0 / math.ceil(v0 / step - 1e-9)
    return Grid.span(lo, hi, step), Grid.span(lo, hi, step / 2.0)


def _absorbing(model: Model, grid: Grid) -> tuple[np.ndarray, np.ndarray, np.ndarray, float,
                                                   np.ndarray]:
    """``(sub, dia, sup, k10, log_pi)`` of ``L_+`` (the generator on the nodes v > 0, node 0
    absorbing) and the rate ``k_{1->0}`` of the absorbed link."""
    L = generator(model, grid)
    z = grid.zero
    dia = L.diagonal(0)[z + 1:]
    sup = L.diagonal(1)[z + 1:]   # L[i, i+1]: rate i+1 -> i
    sub = L.diagonal(-1)[z + 1:]  # L[i+1, i]: rate i -> i+1
    k10 = float(L.diagonal(1)[z])  # L[0, 1]: rate 1 -> 0
    _, _, log_pi = symmetric_generator(model, grid)
    return sub, dia, sup, k10, log_pi[z + 1:]


def _start(grid: Grid, v0: float) -> np.ndarray:
    p0 = np.zeros(grid.i_max)
    p0[int(round(v0 / grid.h)) - 1] = 1.0
    return p0


def _survival_on_grid(model: Model, grid: Grid, v0: float, times: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray]:
    sub, dia, sup, k10, log_pi = _absorbing(model, grid)
    p0 = _start(grid, v0)
    nodes = contour_nodes(amplification(log_pi, p0))
    surv = np.empty(times.size)
    dens = np.empty(times.size)
    if nodes is None:  # deep in the tail: expm_multiply, stepping through the sorted times
        L = sparse.diags([sub, dia, sup], [-1, 0, 1], format="csc")
        p, t_prev = p0, 0.0
        for k in np.argsort(times, kind="stable"):
            if times[k] > t_prev:
                p = expm_multiply(L * (times[k] - t_prev), p)
                t_prev = float(times[k])
            surv[k], dens[k] = p.sum(), k10 * p[0]
        return np.clip(surv, 0.0, 1.0), np.clip(dens, 0.0, None)
    zs, cs = _talbot(nodes)
    b = p0.astype(complex)
    for k, t in enumerate(times):
        if t == 0:
            surv[k], dens[k] = 1.0, k10 * p0[0]
            continue
        acc = np.zeros(p0.size, dtype=complex)
        for zj, cj in zip(zs, cs):
            _, _, _, x, info = lapack.zgtsv(-t * sub, zj - t * dia, -t * sup, b)
            if info != 0:  # pragma: no cover - z_j is off the real spectrum
                raise np.linalg.LinAlgError(f"contour solve failed (info={info})")
            acc += cj * x
        p = 2.0 * acc.real
        surv[k], dens[k] = p.sum(), k10 * p[0]
    return np.clip(surv, 0.0, 1.0), np.clip(dens, 0.0, None)


def _times(t: ArrayLike) -> np.ndarray:
    try:
        arr = np.asarray(t, dtype=float)
    except (TypeError, ValueError):
        raise ValueError("t must be an array of real times") from None
    if not np.all(np.isfinite(arr)) or np.any(arr < 0):
        raise ValueError("t must be finite and >= 0")
    return arr


def _law(model: Model, v0: float, t: ArrayLike, h: float | None) -> tuple[np.ndarray, np.ndarray]:
    m, x0 = _upper(model, v0)
    arr = _times(t)
    if h is not None:
        checks.positive("h", h)
    coarse, fine = _grids(m, x0, h)
    sc, dc = _survival_on_grid(m, coarse, x0, arr.ravel())
    sf, df = _survival_on_grid(m, fine, x0, arr.ravel())
    surv = np.clip((4.0 * sf - sc) / 3.0, 0.0, 1.0)
    dens = np.clip((4.0 * df - dc) / 3.0, 0.0, None)
    return surv.reshape(arr.shape), dens.reshape(arr.shape)


def first_passage_survival(model: Model, v0: float, t: ArrayLike, *, h: float | None = None
                           ) -> np.ndarray:
    """``S(t) = P(T > t)``, T the first time the path from ``v0`` reaches ``v = 0`` (module
    docstring; absorbing Fokker-Planck, Richardson over (h, h/2)); t any shape, >= 0."""
    return _law(model, v0, t, h)[0]


def first_passage_density(model: Model, v0: float, t: ArrayLike, *, h: float | None = None
                          ) -> np.ndarray:
    """Density ``f(t) = -dS/dt`` of the first-passage time to rest (the flux into the
    absorbing node); t any shape, >= 0."""
    return _law(model, v0, t, h)[1]


def _moments_on_grid(model: Model, grid: Grid, v0: float) -> tuple[float, float]:
    sub, dia, sup, _, _ = _absorbing(model, grid)
    # (-L_+) x = p0, then (-L_+) y = x: E T = 1.x, E T^2 = 2 1.y  (dgtsv, partial pivoting)
    rhs = np.stack([_start(grid, v0)], axis=1)
    _, _, _, x, info = lapack.dgtsv(-sub, -dia, -sup, rhs)
    _, _, _, y, info2 = lapack.dgtsv(-sub, -dia, -sup, x)
    if info or info2:  # pragma: no cover - -L_+ is a nonsingular M-matrix
        raise np.linalg.LinAlgError("first-passage moment solve failed")
    return float(x.sum()), 2.0 * float(y.sum())


def first_passage_moments(model: Model, v0: float, *, h: float | None = None
                          ) -> tuple[float, float]:
    """``(E T, Var T)`` of the first-passage time to rest from the absorbing generator
    (module docstring), Richardson over (h, h/2)."""
    m, x0 = _upper(model, v0)
    if h is not None:
        checks.positive("h", h)
    coarse, fine = _grids(m, x0, h)
    (mc, sc), (mf, sf) = _moments_on_grid(m, coarse, x0), _moments_on_grid(m, fine, x0)
    mean = (4.0 * mf - mc) / 3.0
    second = (4.0 * sf - sc) / 3.0
    return float(mean), float(second - mean * mean)


_GL_X, _GL_W = np.polynomial.legendre.leggauss(64)


def _inner(model: Model, y: float) -> float:
    """``e^{gamma U(y)} int_y^inf e^{-gamma U(z)} dz`` (y > 0, v > 0 half line)."""
    if model.is_paper and model.epsilon == 0:
        s = model.velocity_scale
        mu = (model.a - model.delta) * model.tau_m
        return s * math.sqrt(math.pi / 2.0) * float(special.erfcx((y - mu) / (s * math.sqrt(2.0))))
    g, uy = model.gamma, float(model.potential(y))
    val, _ = integrate.quad(lambda z: math.exp(-g * (float(model.potential(z)) - uy)), y, math.inf,
                            epsabs=0.0, epsrel=1e-12, limit=400)
    return float(val)


def first_passage_mean(model: Model, v0: float) -> float:
    """Mean first-passage time to rest by the quadrature formula of the module docstring
    (independent of the grid): the sgn law by ``erfcx`` and 4 x 64-point Gauss-Legendre
    panels, other laws by nested adaptive quadrature.  Weak-noise limit: ``t_a``."""
    m, x0 = _upper(model, v0)
    edges = np.linspace(0.0, x0, 5)
    total = 0.0
    for lo, hi in zip(edges[:-1], edges[1:]):
        ys = 0.5 * (hi - lo) * (_GL_X + 1.0) + lo
        total += 0.5 * (hi - lo) * float(np.dot(_GL_W, [_inner(m, float(y)) for y in ys]))
    return m.gamma * total


def mean_slope_at_rest(model: Model, side: float) -> float:
    """``dT/dv0`` at ``v0 -> 0`` on the side ``sign(side)``: ``gamma e^{gamma U(0)} int_0^inf
    e^{-gamma U}`` (the mean time to travel a small distance b to rest is this times b; the
    sampling bias of a discretely observed first passage uses it,
    :func:`analogue.estimators.first_passage.sampling_bias`).  Stick regime at weak noise:
    ``1/(Delta - a)``."""
    m, _ = _upper(model, side)
    return m.gamma * _inner(m, 0.0)
