"""Weak-noise large deviations of the work done by the external force (paper, section V).

The work over ``[0, tau]`` is ``W_tau = F * integral v ds`` with ``F = m a`` (eq. (3)) and the
work rate ``w = W_tau / tau`` (eq. (52)).  In the joint limit ``tau, gamma -> infinity``
the paper writes ``P_tau(w) ~ exp(-tau gamma I(w))`` (eq. (54)) with

    I(w) = (1/4) (w/(m a tau_m) + sgn(w/(m a)) Delta - a)^2          (eq. (64)),

the Onsager-Machlup Lagrangian evaluated on the constant path ``v = tilde v_w = w/(m a)``
(eqs. (61), (63)), and the fluctuation relation ``I(-w) - I(w) = w/(m tau_m) + a Delta`` for
``a, w > 0`` (eq. (67)).

:func:`work_optimal_path` solves the finite-``tau`` problem behind eq. (64): minimise the action
``A`` subject to ``W_tau = w tau`` with fixed endpoints, through the modified action
``K = A - beta W`` (eqs. (57), (58), (60)).

Like the rest of the paper's weak-noise theory this module uses the exact ``sgn`` law and
ignores ``model.epsilon``; ``gamma`` does not enter (it is factored out of the action).

Note on the paper's open question: eq. (64) jumps at ``w = 0``.  A long path may also *share
time* between sticking at ``v = 0`` (free when ``|a| <= Delta``) and sliding, at an O(1) cost
for the switches; the true ``tau -> infinity`` limit of ``min A / tau`` is therefore the lower
convex envelope of eq. (64) (continuous, linear near ``w = 0``).  That limit is implemented in
:mod:`analogue.theory.work_statistics` (``weak_noise_limit_rate_function``); the functions here
are the paper's formulas.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy import optimize

from .. import checks
from ..checks import finite as _finite, finite_array as _finite_array
from ..model import Model

__all__ = ["rate_function", "fluctuation_relation", "work_optimal_path", "WorkOptimalPath"]


# ----------------------------------------------------------------------------- validation


def _require_force(model: Model) -> None:
    if model.a == 0:
        raise ValueError("a must be nonzero (a != 0): with a = 0 the work F * integral v is "
                         "identically 0 and has no rate function")


# ------------------------------------------------------------------------ rate function
def _hold_cost(model: Model, v: np.ndarray) -> np.ndarray:
    """Cost per unit time ``U'(v)^2 / 4`` of holding the velocity at ``v`` (the Lagrangian
    ``L(0, v)`` of eq. (9)).  At ``v = 0`` the sgn law is set-valued (Filippov): friction
    can supply any value in ``[-Delta, Delta]``, so holding ``v = 0`` costs
    ``max(|a| - Delta, 0)^2 / 4`` - zero when the object can stick, as the paper itself assigns
    zero action to paths that stay on ``v = 0`` (eqs. (33), (34))."""
    v = np.asarray(v, dtype=float)
    moving = v / model.tau_m + np.sign(v) * model.delta - model.a
    stuck = max(abs(model.a) - model.delta, 0.0)
    return 0.25 * np.where(v == 0, stuck * stuck, moving * moving)


def rate_function(model: Model, w: ArrayLike) -> float | np.ndarray:
    """The paper's work rate function ``I(w)`` (eq. (64)), vectorised over ``w``.

    ``I(w) = L(0, tilde v_w) = (1/4) (w/(m a tau_m) + sgn(w/(m a)) Delta - a)^2`` with
    ``tilde v_w = w/(m a)`` (eq. (63)), in the scaling ``P_tau(w) ~ exp(-tau gamma I(w))``
    (eq. (54)).  Valid for either sign of ``a``; ``a = 0`` raises ValueError (the work is
    then identically zero).

    At exactly ``w = 0`` (``v = 0``) the formula's ``sgn(0)`` is ambiguous.  Read literally with
    the paper's ``sigma(0) = 0`` it would give ``a^2/4``, which is the cost of no path at all and
    makes ``I`` fail to be lower semicontinuous (a requirement of a rate function) when
    ``|a| > Delta/2``.  We use the set-valued (Filippov) friction at ``v = 0``, i.e. the cheapest
    way of holding ``v = 0``: ``I(0) = max(|a| - Delta, 0)^2 / 4``.  This is 0 when the object
    can stick (``|a| <= Delta``; the paper's own indirect paths sit on ``v = 0`` at zero cost)
    and equals the limit from the attractor's side when ``|a| > Delta``.  Away from ``w = 0``
    this choice changes nothing.
    """
    _require_force(model)
    w = _finite_array("w", w)
    out = _hold_cost(model, w / model.force)
    return float(out) if out.ndim == 0 else out


def fluctuation_relation(model: Model, w: ArrayLike) -> float | np.ndarray:
    """``I(-w) - I(w)`` from eq. (64) (eq. (67)), vectorised over ``w``, any sign of ``a``.

    For ``a > 0`` and ``w > 0`` this is ``w/(m tau_m) + a Delta`` (eq. (67)); in general it is
    ``w/(m tau_m) + |a| Delta sgn(w)`` (odd in ``w``), with the value 0 at ``w = 0``.  The
    ratio ``P_tau(w)/P_tau(-w) ~ exp(tau gamma [I(-w) - I(w)])`` (eq. (68)).
    """
    _require_force(model)
    w = _finite_array("w", w)
    v = w / model.force
    out = np.asarray(_hold_cost(model, -v) - _hold_cost(model, v))
    return float(out) if out.ndim == 0 else out


# ------------------------------------------------------------------ work-optimal paths
@dataclass(frozen=True, eq=False)
class WorkOptimalPath:
    """Minimiser of the action at fixed work (eqs. (57), (58), (60)).

    Attributes
    ----------
    s, v : ndarray
        Times on ``[0, tau]`` and the optimal velocity path ``v*_w(s)`` (n + 1 samples).
    beta : float
        Lagrange multiplier of ``W_tau = w tau`` in ``K = A - beta W`` (eq. (57));
        ``beta = dA_min/dW`` (envelope theorem).
    v_w : float
        Attractor of the constrained motion ``tilde v_w = w/(m a)`` (eq. (63)).
    action : float
        Onsager-Machlup action ``A`` (eqs. (8), (9)) of the path.
    work : float
        ``F * integral v ds`` along the path (equals ``w tau``).
    kind : str
        Sign pattern of the pieces, e.g. ``"+"`` (one half plane), ``"+-"`` (one crossing),
        ``"-+-"`` (two crossings), ``"+0+"`` (sticks on ``v = 0`` in between).
    t_nodes : tuple of float
        Times at which the path reaches/leaves ``v = 0`` between pieces.
    """

    s: np.ndarray
    v: np.ndarray
    beta: float
    v_w: float
    action: float
    work: float
    kind: str
    t_nodes: tuple[float, ...] = field(default=())


class _Segments:
    """Closed-form pieces of the constrained optimal path for given node times.

    On a half plane ``sigma = sgn v`` the modified E-L equation (eq. (60)) reads
    ``v'' = U'(v) U''(v) - 2 beta m a = (v/tau_m + c)/tau_m - 2 beta m a`` with
    ``c = sigma Delta - a``.  (From ``K = (v' + U')^2/4 - beta m a v``:
    ``d/ds[(v' + U')/2] = (v' + U') U''/2 - beta m a``.)  Its solution with endpoint values
    ``x0, x1`` over a duration ``T`` is ``v = v_p + z`` with the particular solution
    ``v_p = -c tau_m + 2 beta m a tau_m^2`` and ``z'' = z / tau_m^2``.  Both the work integral and
    the action of such a piece are closed forms, affine and quadratic in ``beta``, so the
    multiplier fixing the total work is found exactly for given node times.  A stuck piece
    (``v = 0``) costs ``max(|a| - Delta, 0)^2/4`` per unit time and does no work.
    """

    def __init__(self, model: Model, pattern: str, v0: float, v: float):
        self.m = model
        self.pattern = pattern
        self.v0, self.v1 = v0, v
        n = len(pattern)
        # Endpoint values of every piece: interior nodes sit on v = 0.
        self.x0 = np.array([v0] + [0.0] * (n - 1))
        self.x1 = np.array([0.0] * (n - 1) + [v])
        self.sigma = np.array([{"+": 1.0, "-": -1.0, "0": 0.0}[c] for c in pattern])
        self.moving = self.sigma != 0
        tau = model.tau_m
        self.c = self.sigma * model.delta - model.a
        self.k = 2.0 * model.force * tau * tau  # d v_p / d beta
        stuck = max(abs(model.a) - model.delta, 0.0)
        self.stuck_rate = 0.25 * stuck * stuck

    # --- per piece, vectorised over rows of durations T (shape (..., n)) -------------
    def _pieces(self, T: np.ndarray, beta: np.ndarray | float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        tau = self.m.tau_m
        E = np.exp(-T / tau)
        vp = np.asarray(-self.c * tau + self.k * beta)
        z0 = np.asarray(self.x0 - vp)
        z1 = np.asarray(self.x1 - vp)
        b = np.asarray(2.0 * beta * self.m.force * tau)
        return E, vp, z0, z1, b

    def _work_terms(self, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Integral of v over each piece as ``J0 + beta * J1`` (closed form)."""
        tau = self.m.tau_m
        th = np.tanh(T / (2.0 * tau))
        vp0 = -self.c * tau
        J0 = vp0 * T + tau * (self.x0 + self.x1 - 2.0 * vp0) * th
        J1 = self.k * (T - 2.0 * tau * th)
        mv = self.moving
        return np.where(mv, J0, 0.0), np.where(mv, J1, 0.0)

    def beta_for(self, T: np.ndarray, target: float) -> np.ndarray:
        """Multiplier that makes ``integral v = target`` (target = w tau / F)."""
        J0, J1 = self._work_terms(T)
        return np.asarray((target - J0.sum(axis=-1)) / J1.sum(axis=-1))

    def action(self, T: np.ndarray, beta: np.ndarray | float) -> np.ndarray:
        """Action of every piece, using
        ``v' + U' = (2P/tau_m) e^{s/tau_m} + 2 beta m a tau_m`` for ``z = P e^{s/tau_m} + Q e^{-s/tau_m}``,
        written with ``E = e^{-T/tau_m}`` so that long pieces do not overflow."""
        tau = self.m.tau_m
        beta = np.asarray(beta)[..., None]
        E, vp, z0, z1, b = self._pieces(T, beta)
        r = z1 - z0 * E
        with np.errstate(divide="ignore", invalid="ignore"):
            A = 0.25 * ((2.0 / tau) * r * r / (1.0 - E * E) + 4.0 * b * r / (1.0 + E) + b * b * T)
        # A zero-length piece is free only if it does not have to jump.
        A = np.where(T > 0, A, np.where(r == 0, 0.0, np.inf))
        return np.where(self.moving, A, self.stuck_rate * T)

    def admissible(self, T: np.ndarray, beta: np.ndarray | float, rtol: float = 1e-9) -> np.ndarray:
        """True where every moving piece stays on its own half plane.  ``v - v_p`` is a sum of
        two exponentials, so it has at most one interior extremum, found in closed form."""
        tau = self.m.tau_m
        beta = np.asarray(beta)[..., None]
        E, vp, z0, z1, b = self._pieces(T, beta)
        with np.errstate(divide="ignore", invalid="ignore"):
            P = E * (z1 - z0 * E) / (1.0 - E * E)
            Q = z0 - P
            ratio = Q / P
            s_star = 0.5 * tau * np.log(ratio)
            interior = (ratio > 0) & (s_star > 0) & (s_star < T)
            ext = vp + 2.0 * np.sign(P) * np.sqrt(np.abs(P * Q))
        scale = rtol * (1.0 + abs(self.v0) + abs(self.v1) + np.abs(vp))
        bad = self.moving & interior & (self.sigma * ext < -scale)
        return np.asarray(~bad.any(axis=-1))

    def evaluate(self, T: np.ndarray, beta: float, s: np.ndarray) -> np.ndarray:
        """The path at times ``s`` for one set of durations ``T``."""
        tau = self.m.tau_m
        edges = np.concatenate([[0.0], np.cumsum(T)])
        out = np.zeros_like(s)
        E, vp, z0, z1, b = self._pieces(T, beta)
        for i in range(len(T)):  # a handful of pieces, not samples
            sel = (s >= edges[i]) & (s <= edges[i + 1])
            if not self.moving[i]:
                out[sel] = 0.0
                continue
            x = np.clip(s[sel] - edges[i], 0.0, T[i])
            Ti = T[i]
            if Ti <= 0:
                out[sel] = self.x1[i]
                continue
            # sinh(x)/sinh(T) written with decaying exponentials only
            den = 1.0 - math.exp(-2.0 * Ti / tau)
            f1 = np.exp((x - Ti) / tau) * (1.0 - np.exp(-2.0 * x / tau)) / den
            y = Ti - x
            f0 = np.exp((y - Ti) / tau) * (1.0 - np.exp(-2.0 * y / tau)) / den
            out[sel] = vp[i] + z0[i] * f0 + z1[i] * f1
        return out


def _patterns(v0: float, v: float, allow_stick: bool) -> list[str]:
    """Sign patterns of candidate optimal paths: up to three sliding pieces (so up to two
    crossings of v = 0) with, optionally, a stuck stretch at any node on v = 0."""
    first = ["+", "-"] if v0 == 0 else ["+" if v0 > 0 else "-"]
    last = ["+", "-"] if v == 0 else ["+" if v > 0 else "-"]
    out = []
    for f, l in itertools.product(first, last):
        for length in (1, 2, 3):
            signs = [f if i % 2 == 0 else ("-" if f == "+" else "+") for i in range(length)]
            if signs[-1] != l:
                continue
            nodes = length - 1 if length > 1 else 1
            stick_choices = [(False,), (True,)] if length == 1 else \
                itertools.product((False, True), repeat=nodes)
            for sticks in stick_choices:
                if length == 1 and not sticks[0]:
                    out.append(signs[0])
                    continue
                if length == 1:
                    if allow_stick:
                        out.append(signs[0] + "0" + signs[0])
                    continue
                if any(sticks) and not allow_stick:
                    continue
                p = signs[0]
                for sgn, st in zip(signs[1:], sticks):
                    p += ("0" if st else "") + sgn
                out.append(p)
    return list(dict.fromkeys(out))


def _softmax(x: np.ndarray) -> np.ndarray:
    e = np.exp(x - x.max(axis=-1, keepdims=True))
    return np.asarray(e / e.sum(axis=-1, keepdims=True))


def _best_durations(seg: _Segments, tau: float, target: float, rng: np.random.Generator
                    ) -> tuple[float, np.ndarray | None, float | None]:
    """Minimise the constrained action over the node times of one sign pattern."""
    n = len(seg.pattern)
    if n == 1:
        T = np.array([tau])
        beta = float(seg.beta_for(T, target))
        if not seg.admissible(T, beta):
            return math.inf, None, None
        return float(seg.action(T, beta).sum()), T, beta

    def objective(x: np.ndarray) -> float:
        T = tau * _softmax(np.concatenate([[0.0], x]))
        beta = seg.beta_for(T, target)
        if not np.isfinite(beta) or not seg.admissible(T, beta):
            return math.inf
        A = float(seg.action(T, beta).sum())
        return A if math.isfinite(A) else math.inf

    # Coarse vectorised search over the simplex of durations, then a local polish.
    X = rng.normal(scale=2.0, size=(600, n - 1))
    T = tau * _softmax(np.concatenate([np.zeros((X.shape[0], 1)), X], axis=1))
    betas = seg.beta_for(T, target)
    A = seg.action(T, betas).sum(axis=-1)
    A = np.where(np.isfinite(betas) & seg.admissible(T, betas) & np.isfinite(A), A, np.inf)
    order = np.argsort(A)
    best = (math.inf, None)
    for j in order[:2]:
        if not np.isfinite(A[j]):
            break
        res = optimize.minimize(objective, X[j], method="Nelder-Mead",
                                options={"xatol": 1e-10, "fatol": 1e-13, "maxiter": 4000})
        if res.fun < best[0]:
            best = (float(res.fun), res.x)
    if best[1] is None:
        return math.inf, None, None
    T = tau * _softmax(np.concatenate([[0.0], best[1]]))
    return best[0], T, float(seg.beta_for(T, target))


def work_optimal_path(model: Model, w: float, tau: float, v0: float, v: float,
                      n: int = 400) -> WorkOptimalPath:
    """Optimal path at fixed work rate (eqs. (57), (58), (60); Fig. 7 of the paper).

    Minimises the Onsager-Machlup action ``A`` over paths on ``[0, tau]`` with ``v(0) = v0``,
    ``v(tau) = v`` and work ``F * integral v ds = w tau`` via ``K = A - beta W``.  On each half
    plane the E-L equation of ``K`` is ``v'' = U'(v) U''(v) - 2 beta m a`` (linear there; see
    :class:`_Segments`), pieces are glued continuously on ``v = 0``.  For fixed times at which
    the path meets ``v = 0`` the constrained problem is a convex quadratic one solved in closed
    form (``beta`` from the affine work constraint); the node times are then optimised
    numerically (this yields the Weierstrass-Erdmann corner condition, conservation of
    ``H = (v'^2 - U'^2)/4 + beta m a v``, across the kink).  Candidates: one half plane, one or
    two crossings, and stuck stretches on ``v = 0``; each piece must stay on its half plane.

    For long ``tau`` the path sits on ``tilde v_w = w/(m a)`` (eq. (63)) in the middle, where
    ``beta -> U'(tilde v_w)/(2 m a tau_m)`` and ``A/tau -> I(w)`` of eq. (64) (when the optimal
    path is not a time-sharing one).
    """
    _require_force(model)
    w = _finite("w", w)
    tau = checks.positive("tau", tau)
    v0 = _finite("v0", v0)
    v = _finite("v", v)
    n = checks.integer("n", n, minimum=2)
    target = w * tau / model.force
    rng = np.random.default_rng(12345)  # deterministic multi-start
    best: tuple[float, Any, Any, _Segments | None] = (math.inf, None, None, None)
    for pattern in _patterns(v0, v, allow_stick=True):
        seg = _Segments(model, pattern, v0, v)
        A, T, beta = _best_durations(seg, tau, target, rng)
        if A < best[0] - 1e-12 * max(1.0, abs(A)):
            best = (A, T, beta, seg)
    A, T, beta, best_seg = best
    if best_seg is None:
        raise RuntimeError("no admissible work-optimal path found")  # pragma: no cover
    s = np.linspace(0.0, tau, n + 1)
    path = best_seg.evaluate(T, beta, s)
    path[0], path[-1] = v0, v
    J0, J1 = best_seg._work_terms(T)
    work = model.force * float((J0 + beta * J1).sum())
    nodes = tuple(float(x) for x in np.cumsum(T)[:-1])
    return WorkOptimalPath(s=s, v=path, beta=beta, v_w=w / model.force, action=A, work=work,
                           kind=best_seg.pattern, t_nodes=nodes)
