"""The paper's weak-noise theory: optimal paths and transition probability (sections III-IV).

In the limit ``gamma -> infinity`` the propagator is ``f(v,t|v0,t0) ~ exp(-gamma A*)``
(eq. (12)) with ``A*`` the minimal Onsager-Machlup action (eq. (8), Lagrangian
eq. (9) ``L = (v' + U'(v))^2 / 4``).  The minimum is taken over the paper's five kinds
of admissible optimal paths:

* ``direct``: one basic solution (eq. (16)) on one half plane, action ``Lambda_pm``
  (eqs. (22), (20));
* ``direct-crossing``: two basic solutions glued at ``v = 0`` at ``t_cross`` (eqs. (23),
  (24)), ``t_cross`` the root of eq. (25);
* ``indirect`` / ``indirect-crossing`` (``|a| <= Delta`` only): relax deterministically to
  ``v = 0`` at ``t_a`` (eq. (31)), stick, leave at ``t_b`` (eq. (32)); valid iff
  ``t_a <= t_b``; action ``U(v)`` with ``U(0) = 0`` (eqs. (33), (34));
* ``twice-crossing`` (``|a| > Delta``, v0 and v on the side opposite the attractor): eq. (36),
  the crossing times ``t_1 < t_2`` found numerically (see below).

A path is *admissible* only if each basic piece stays on its own half plane; a basic solution
that dips through ``v = 0`` is not a direct path.  ``v0 = 0`` or ``v = 0`` belong to both half
planes (every candidate on either side is tried), which gives the correct limits.

Other signs: the paper writes out ``a > 0``.  ``a < 0`` is reduced to ``a > 0`` by the symmetry
``f(v, t | v0; a) = f(-v, t | -v0; -a)`` (section II), i.e. everything is computed for
``(-v, -v0, -a)`` and mirrored back.  ``v0 < 0`` cases (which the paper leaves to the reader)
are handled by the same half-plane algebra with ``b_sigma = Delta - sigma a`` on the side
``sigma = sgn v`` (see :mod:`.weak_noise_pieces`); ``a = +-Delta`` (``b = 0``: sticking is
free but never reached from that side, ``t_a = inf``), ``a = 0`` and ``Delta = 0`` (pure
Ornstein-Uhlenbeck) come out of the same formulas.

Twice-crossing times: with the conserved "energy" ``E = y'^2 - y^2/tau^2`` of each piece
(``y = |v| + b tau_m``), stationarity of eq. (36) in ``t_1, t_2`` means the three pieces share
one ``E``; the durations are then closed-form (:func:`.weak_noise_pieces.monotone_time` for the
monotone outer pieces, ``2 tau arccosh(|b|/sqrt(-E))`` for the bump), their sum increases
strictly with ``E`` (so the root is unique), and one scalar root gives ``t_1, t_2``.

This is the theory of the exact ``sgn`` law: ``model.epsilon`` is ignored.  The action does
not involve the mass (``gamma`` only enters the propagator).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike
from scipy.integrate import trapezoid
from scipy.optimize.elementwise import find_root

from .. import checks
from ..checks import finite as _finite
from ..model import Model
from .weak_noise_pieces import (FloatOrArray, bridge, bridge_min, monotone_time, ou_action,
                                ou_action_rate)

__all__ = ["action", "optimal_path", "OptimalPath", "boundaries", "boundary_examples", "propagator", "Lambda",
           "crossing_time", "lagrangian", "KINDS",
           "rate_function", "fluctuation_relation", "work_optimal_path"]

KINDS = ("direct", "direct-crossing", "indirect", "indirect-crossing", "twice-crossing")
_DIRECT, _DCROSS, _INDIRECT, _ICROSS, _TWICE = range(5)

# A piece that touches v = 0 only within this relative rounding still counts as admissible.
_ADMISSIBLE_RTOL = 1e-11


# ----------------------------------------------------------------------------- validation

def _times(t: float, t0: float) -> tuple[float, float]:
    t0 = _finite("t0", t0)
    t = _finite("t", t)
    if not t > t0:
        raise ValueError(f"t must be > t0 (= {t0!r}), got {t!r}")
    return t, t0


def _velocities(v: ArrayLike) -> np.ndarray:
    return checks.finite_array("v", v)


# ----------------------------------------------------------------------------- canonical frame
@dataclass(frozen=True)
class _Frame:
    """Parameters mirrored to ``a >= 0`` (``flip = -1`` if the model has ``a < 0``)."""

    tau: float
    delta: float
    a: float
    flip: float

    @classmethod
    def of(cls, model: Model) -> _Frame:
        checks.instance("model", model, Model, description="an analogue.Model")
        # the paper's friction law without a spring, white Gaussian noise (or none: the theory
        # does not depend on gamma), chosen by the model's variants (analogue.variants)
        if not (model.closed_form and model.noise_kind.white_gaussian_only):
            raise ValueError("analogue.theory.weak_noise is the paper's closed-form theory (cubic=0, "
                             "stribeck=None, spring=0, shot=None, noise=None); for the family use "
                             "analogue.theory.weak_noise_family")
        flip = -1.0 if model.a < 0 else 1.0
        return cls(model.tau_m, model.delta, abs(model.a), flip)

    def b(self, sigma: float) -> float:
        """``b_sigma = Delta - sigma a`` (eq. (20): ``Delta -+ a`` on the upper/lower plane)."""
        return self.delta - sigma * self.a

    def c(self, sigma: float) -> float:
        """``v = 0`` in the shifted coordinate ``y = |v| + b tau`` of side sigma."""
        return self.b(sigma) * self.tau

    def potential(self, v: FloatOrArray) -> FloatOrArray:
        return v * v / (2.0 * self.tau) + self.delta * np.abs(v) - self.a * v

    def stick_time(self, sigma: float, speed: ArrayLike) -> np.ndarray:
        """Deterministic time to reach v = 0 from |v| = speed on side sigma (eqs. (31)/(32));
        inf if that side never reaches v = 0 (b <= 0) unless speed == 0."""
        b = self.b(sigma)
        speed = np.asarray(speed, dtype=float)
        if b <= 0:
            return np.where(speed == 0, 0.0, np.inf)
        return self.tau * np.log1p(speed / (b * self.tau))


def _admissible(y0: FloatOrArray, y1: FloatOrArray, T: FloatOrArray, c: float,
                tau: float) -> np.ndarray:
    """Does the basic piece from y0 to y1 in time T stay on its side (y >= c)?  Touching
    within rounding of c counts as staying (pieces ending on v = 0 have y = c exactly)."""
    return bridge_min(y0, y1, T, tau) >= c - _ADMISSIBLE_RTOL * abs(c)


# ----------------------------------------------------------------------------- candidates
@dataclass
class _Best:
    """Running minimum over candidate kinds (arrays of the shape of v)."""

    action: np.ndarray
    kind: np.ndarray
    side0: np.ndarray
    side1: np.ndarray
    times: dict[str, np.ndarray] = field(default_factory=dict)

    @classmethod
    def empty(cls, shape: tuple[int, ...]) -> _Best:
        nan = np.full(shape, np.nan)
        return cls(np.full(shape, np.inf), np.full(shape, -1), np.zeros(shape), np.zeros(shape),
                   {k: nan.copy() for k in ("t_cross", "t_a", "t_b", "t_1", "t_2")})

    def offer(self, cand: FloatOrArray, kind: int | np.ndarray, side0: float, side1: float,
              **times: FloatOrArray) -> None:
        cand = np.where(np.isfinite(cand), cand, np.inf)
        margin = np.where(np.isfinite(self.action), 1e-13 * (1.0 + np.abs(self.action)), 0.0)
        better = cand < self.action - margin
        if not np.any(better):
            return
        self.action = np.where(better, cand, self.action)
        self.kind = np.where(better, kind, self.kind)
        self.side0 = np.where(better, side0, self.side0)
        self.side1 = np.where(better, side1, self.side1)
        for key in self.times:
            new = np.broadcast_to(np.asarray(times.get(key, np.nan), float), better.shape)
            self.times[key] = np.where(better, new, self.times[key])


def _direct(fr: _Frame, sigma: float, v0: float, v: FloatOrArray,
            T: FloatOrArray) -> np.ndarray:
    """eq. (22): Lambda_sigma, if the basic solution stays on side sigma."""
    c = fr.c(sigma)
    y0, y1 = abs(v0) + c, np.abs(v) + c
    ok = _admissible(y0, y1, T, c, fr.tau)
    return np.where(ok, ou_action(y0, y1, T, fr.tau), np.inf)


def _crossing(fr: _Frame, sigma0: float, v0: float, v: ArrayLike,
              T: float) -> tuple[np.ndarray, np.ndarray]:
    """eqs. (24), (25): minimise Lambda_s0(0,tx;v0,0) + Lambda_-s0(v,T;0,tx) over tx.

    Returns (action, tx); inf/NaN where eq. (25) has no interior root or a piece leaves its
    half plane."""
    sigma1 = -sigma0
    c0, c1, tau = fr.c(sigma0), fr.c(sigma1), fr.tau
    yA0 = abs(v0) + c0
    yC1 = np.abs(np.asarray(v, float)) + c1
    shape = yC1.shape
    yC1 = yC1.ravel()

    def slope(x: FloatOrArray, yc1: np.ndarray) -> np.ndarray:
        rate: np.ndarray = ou_action_rate(yA0, c0, x, tau) - ou_action_rate(c1, yc1, T - x, tau)
        return rate

    lo, hi = T * 1e-12, T * (1.0 - 1e-12)
    f_lo, f_hi = slope(lo, yC1), slope(hi, yC1)
    has = (f_lo < 0) & (f_hi > 0)
    tx = np.full(yC1.shape, np.nan)
    if np.any(has):
        res = find_root(slope, (np.full(has.sum(), lo), np.full(has.sum(), hi)), args=(yC1[has],),
                        tolerances=dict(xatol=1e-15 * T, xrtol=1e-15, fatol=0.0, frtol=0.0))
        tx[has] = np.where(res.success, res.x, np.nan)
    ok = np.isfinite(tx)
    txs = np.where(ok, tx, 0.5 * T)
    ok &= _admissible(yA0, c0, txs, c0, tau) & _admissible(c1, yC1, T - txs, c1, tau)
    act = ou_action(yA0, c0, txs, tau) + ou_action(c1, yC1, T - txs, tau)
    act = np.where(ok, act, np.inf)
    return act.reshape(shape), np.where(ok, tx, np.nan).reshape(shape)


def _indirect(fr: _Frame, sigma0: float, sigma1: float, v0: float, v: np.ndarray,
              T: float) -> tuple[FloatOrArray, FloatOrArray, FloatOrArray]:
    """eqs. (33)/(34): action U(v) when sticking is free (b >= 0 on both sides) and
    t_a (eq. (31)) <= t_b (eq. (32)).  Returns (action, t_a, t_b)."""
    if fr.a > fr.delta:  # sticking on v = 0 costs (a - Delta)^2/4 per unit time: no indirect paths
        return np.inf, np.nan, np.nan
    ta = fr.stick_time(sigma0, abs(v0))
    tb = T - fr.stick_time(sigma1, np.abs(v))
    ok = ta <= tb + 1e-12 * T
    act = np.where(ok, fr.potential(v), np.inf)
    return act, np.where(ok, ta, np.nan), np.where(ok, tb, np.nan)


def _twice(fr: _Frame, sigma: float, v0: float, v: ArrayLike,
           T: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """eq. (36): v0 and v on side sigma, the attractor on the other side (b_-sigma < 0).

    The common energy ``E = -b_B^2 q`` (``0 < q <= 1``) of the three pieces is the unique root
    of ``T_A(E) + T_B(E) + T_C(E) = T`` (the sum is strictly increasing in E: ``|T_A'| +
    |T_C'|`` is bounded by the first term of ``T_B'`` because ``b_A > |b_B|``).  Solved in
    ``z = ln q``.  ``T`` may be an array broadcastable with v.  Returns (action, t_1, t_2)."""
    bA, bB, tau = fr.b(sigma), fr.b(-sigma), fr.tau
    v, T = np.broadcast_arrays(np.asarray(v, float), np.asarray(T, float))
    shape = v.shape
    if not (bB < 0 < bA):
        nan = np.full(shape, np.nan)
        return np.full(shape, np.inf), nan, nan
    cA, cB = bA * tau, bB * tau
    yA0 = abs(v0) + cA
    yC1 = (np.abs(v) + cA).ravel()
    T = T.ravel()

    def durations(z: np.ndarray, yc1: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        q = np.exp(z)
        E = -bB * bB * q
        tA = monotone_time(yA0, cA, E, tau)
        tB = 2.0 * tau * (np.log1p(np.sqrt(np.maximum(1.0 - q, 0.0))) - 0.5 * z)
        tC = monotone_time(cA, yc1, E, tau)
        return tA, tB, tC

    def excess(z: np.ndarray, yc1: np.ndarray, tt: np.ndarray) -> np.ndarray:
        tA, tB, tC = durations(z, yc1)
        out: np.ndarray = tA + tB + tC - tt
        return out

    zl = -(T / tau) - 2.0  # there T_B alone exceeds T
    zh = np.zeros(T.shape)
    has = excess(zh, yC1, T) < 0  # at q = 1 the bump has zero length: the shortest total time
    act = np.full(T.shape, np.inf)
    t1 = np.full(T.shape, np.nan)
    t2 = np.full(T.shape, np.nan)
    if np.any(has):
        res = find_root(excess, (zl[has], zh[has]), args=(yC1[has], T[has]),
                        tolerances=dict(xatol=1e-15, xrtol=1e-15, fatol=0.0, frtol=0.0))
        tA, tB, tC = durations(res.x, yC1[has])
        with np.errstate(invalid="ignore", divide="ignore"):
            a_A = np.where(tA > 0, ou_action(yA0, cA, tA, tau), 0.0)
            a_C = np.where(tC > 0, ou_action(cA, yC1[has], tC, tau), 0.0)
        a_B = ou_action(cB, cB, tB, tau)
        act[has] = np.where(res.success, a_A + a_B + a_C, np.inf)
        t1[has] = tA
        t2[has] = T[has] - tC
    return act.reshape(shape), t1.reshape(shape), t2.reshape(shape)


def _solve(fr: _Frame, v: ArrayLike, T: float, v0: float) -> _Best:
    """Minimal action over all admissible candidates, canonical frame (a >= 0), t0 = 0."""
    v = np.asarray(v, float)
    best = _Best.empty(v.shape)
    sides0 = (1.0, -1.0) if v0 == 0 else (math.copysign(1.0, v0),)
    for s0 in sides0:
        for s1 in (1.0, -1.0):
            on = (s1 * v >= 0)
            if not np.any(on):
                continue
            inf = np.where(on, 0.0, np.inf)  # candidates only for v on side s1
            # Offered from the simplest kind up; a later kind must be strictly cheaper, so
            # degenerate ties (e.g. v0 = 0 at a = Delta, where a zero-cost "bump" on v = 0 is
            # sticking) keep the simpler name.
            if s0 == s1:
                best.offer(_direct(fr, s0, v0, v, T) + inf, _DIRECT, s0, s1)
            act, ta, tb = _indirect(fr, s0, s1, v0, v, T)
            kind = np.where((s0 != s1) & (v != 0) & (v0 != 0), _ICROSS, _INDIRECT)
            best.offer(act + inf, kind, s0, s1, t_a=ta, t_b=tb)
            if s0 != s1:
                act, tx = _crossing(fr, s0, v0, v, T)
                best.offer(act + inf, _DCROSS, s0, s1, t_cross=tx)
            else:
                act, t1, t2 = _twice(fr, s0, v0, v, T)
                best.offer(act + inf, _TWICE, s0, s1, t_1=t1, t_2=t2)
    if not np.all(np.isfinite(best.action)):
        raise RuntimeError(f"no admissible optimal path found (please report: v0={v0!r}, "
                           f"T={T!r})")
    return best


# ----------------------------------------------------------------------------- public API
def Lambda(sign: int, v: ArrayLike, t: float, v0: float, t0: float,
           model: Model) -> float | np.ndarray:
    """Action of the basic solution on the upper (``sign = +1``) or lower (``-1``) half plane,
    eq. (20): ``Lambda_pm(v,t;v0,t0)`` with ``Delta -+ a``; uses ``|v|, |v0|`` as the paper
    does.  No admissibility check (that is the caller's business).  Vectorised in v."""
    if sign not in (1, -1):
        raise ValueError(f"sign must be +1 or -1, got {sign!r}")
    t, t0 = _times(t, t0)
    v0 = _finite("v0", v0)
    c = (model.delta - sign * model.a) * model.tau_m
    out = ou_action(abs(v0) + c, np.abs(_velocities(v)) + c, t - t0, model.tau_m)
    return float(out) if np.ndim(out) == 0 else out


def crossing_time(model: Model, v: ArrayLike, t: float, v0: float,
                  t0: float = 0.0) -> float | np.ndarray:
    """Crossing time ``t_cross`` of the direct crossing path (root of eq. (25)), absolute
    time; NaN where v and v0 are on the same side (or v0 = 0 / v = 0) or where the direct
    crossing path is not admissible.  Vectorised in v."""
    t, t0 = _times(t, t0)
    v0 = _finite("v0", v0)
    v = _velocities(v)
    fr = _Frame.of(model)
    vc, v0c = fr.flip * v, fr.flip * v0
    if v0c == 0:
        out = np.full(v.shape, np.nan)
    else:
        s0 = math.copysign(1.0, v0c)
        _, tx = _crossing(fr, s0, v0c, vc, t - t0)
        out = np.where(s0 * vc < 0, t0 + tx, np.nan)
    return float(out) if out.ndim == 0 else out


def action(model: Model, v: ArrayLike, t: float, v0: float,
           t0: float = 0.0) -> float | np.ndarray:
    """Minimal Onsager-Machlup action ``A*(v, t | v0, t0)`` (eqs. (8), (9)) over the
    admissible direct, direct-crossing, indirect, indirect-crossing and twice-crossing paths
    (eqs. (22), (24), (33), (34), (36)).  ``f ~ exp(-gamma A*)`` (eq. (12)).

    ``v`` may be a scalar (returns float) or an array (same shape).  ``U(0) = 0`` convention.
    """
    t, t0 = _times(t, t0)
    v0 = _finite("v0", v0)
    v = _velocities(v)
    fr = _Frame.of(model)
    out = _solve(fr, fr.flip * v, t - t0, fr.flip * v0).action
    return float(out) if out.ndim == 0 else out


def lagrangian(model: Model, v: ArrayLike, vdot: ArrayLike) -> np.ndarray:
    """Onsager-Machlup Lagrangian eq. (9) ``(v' + U'(v))^2 / 4`` for the sgn law; on
    ``v = 0`` the set-valued ``sgn(0) in [-1, 1]`` is resolved to the cheapest value (Filippov),
    so sticking costs nothing when ``|a| <= Delta``."""
    v = np.asarray(v, float)
    vdot = np.asarray(vdot, float)
    force = vdot + v / model.tau_m - model.a
    moving = force + model.delta * np.sign(v)
    sticking = np.maximum(np.abs(force) - model.delta, 0.0)
    return np.where(v == 0, sticking, moving) ** 2 / 4.0


@dataclass(frozen=True, eq=False)
class OptimalPath:
    """The minimal-action path from ``(v0, t0)`` to ``(v, t)``.

    ``kind`` is one of :data:`KINDS`; ``s`` and ``v`` hold ``n + 1`` samples on ``[t0, t]``;
    switching times are absolute and NaN where they do not apply: ``t_cross`` (direct crossing,
    eq. (25)), ``t_a``/``t_b`` (indirect, eqs. (31)/(32)), ``t_1``/``t_2`` (twice crossing,
    eq. (36))."""

    kind: str
    s: np.ndarray
    v: np.ndarray
    action: float
    t_cross: float = math.nan
    t_a: float = math.nan
    t_b: float = math.nan
    t_1: float = math.nan
    t_2: float = math.nan


def optimal_path(model: Model, v: float, t: float, v0: float, t0: float = 0.0,
                 n: int = 400) -> OptimalPath:
    """The optimal path (eqs. (21), (23), (26), (27), (35)) and its action."""
    t, t0 = _times(t, t0)
    v0 = _finite("v0", v0)
    v = _finite("v", v)
    n = checks.integer("n", n, minimum=2)
    fr = _Frame.of(model)
    T = t - t0
    vc, v0c = fr.flip * v, fr.flip * v0
    best = _solve(fr, np.asarray(vc), T, v0c)
    kind = int(best.kind)
    s0, s1 = float(best.side0), float(best.side1)
    times = {k: float(x) for k, x in best.times.items()}
    s = np.linspace(0.0, T, n + 1)

    def piece(sigma: float, speed0: float, speed1: float, start: float,
              end: float) -> tuple[np.ndarray, np.ndarray]:
        """Basic solution on side sigma between (start, speed0) and (end, speed1)."""
        c = fr.c(sigma)
        inside = (s >= start) & (s <= end)
        if end <= start:
            return inside, np.zeros_like(s)
        dur = end - start
        y = bridge(speed0 + c, speed1 + c, dur, fr.tau, np.clip(s - start, 0.0, dur))
        return inside, sigma * np.maximum(y - c, 0.0)

    path = np.zeros_like(s)
    if kind == _DIRECT:
        segs = [(s0, abs(v0c), abs(vc), 0.0, T)]
    elif kind == _DCROSS:
        tx = times["t_cross"]
        segs = [(s0, abs(v0c), 0.0, 0.0, tx), (s1, 0.0, abs(vc), tx, T)]
    elif kind in (_INDIRECT, _ICROSS):
        ta, tb = times["t_a"], times["t_b"]
        segs = [(s0, abs(v0c), 0.0, 0.0, ta), (s1, 0.0, abs(vc), tb, T)]
    else:
        t1, t2 = times["t_1"], times["t_2"]
        segs = [(s0, abs(v0c), 0.0, 0.0, t1), (-s0, 0.0, 0.0, t1, t2), (s1, 0.0, abs(vc), t2, T)]
    for seg in segs:
        inside, vals = piece(*seg)
        path = np.where(inside, vals, path)
    path[0], path[-1] = v0c, vc
    return OptimalPath(kind=KINDS[kind], s=t0 + s, v=fr.flip * path, action=float(best.action),
                       **{k: (t0 + x if math.isfinite(x) else math.nan) for k, x in times.items()})


def _w_cr(fr: _Frame, v0: float, T: np.ndarray) -> np.ndarray:
    """eq. (49): the v (on v0's side) where the direct and the twice-crossing actions are
    equal, by bisection in ``x = ln(1 + |v|/((Delta+a) tau))`` (canonical frame, v0 < 0).

    The twice-crossing path wins on ``(w_cr, 0)``; it is infeasible below the v at which even a
    zero-length bump cannot fit into ``T``, which brackets the root.  NaN where the twice
    crossing never wins."""
    bA, bB, tau = fr.b(-1.0), fr.b(1.0), fr.tau
    cA, cB = bA * tau, bB * tau

    def sign(x: np.ndarray) -> np.ndarray:
        v = -cA * np.expm1(x)
        d = _direct(fr, -1.0, v0, v, T)
        tc, _, _ = _twice(fr, -1.0, v0, v, T)
        return np.where(np.isinf(tc), -1.0, np.where(np.isinf(d), 1.0, np.sign(d - tc)))

    # Actions grow like v^2: beyond |v| ~ 1e150 they overflow, and there w_cr is reported
    # as -inf (it grows like e^{t/tau_m}; that happens for t > ~340 tau_m).
    y_max = (cA + math.sqrt(cA * cA - cB * cB)) * np.exp(np.minimum(T / tau, 340.0))
    lo = np.zeros(T.shape)
    hi = np.log1p(y_max / cA)
    found = sign(lo) > 0
    beyond = sign(hi) > 0
    for _ in range(80):  # 2^-80 of the bracket: below double precision
        mid = 0.5 * (lo + hi)
        up = sign(mid) > 0
        lo, hi = np.where(up, mid, lo), np.where(up, hi, mid)
    root = np.where(beyond, -np.inf, -cA * np.expm1(0.5 * (lo + hi)))
    return np.where(found, root, np.nan)


def boundaries(model: Model, t: ArrayLike, v0: float,
               t0: float = 0.0) -> dict[str, Any]:
    """Boundary lines of the optimal-path kinds in the (v, t) plane (section IV).

    Returns a dict of arrays (floats for scalar t):

    * ``"w"``: eq. (41), ``w^+`` for ``v0 > 0`` and ``w^-`` for ``v0 < 0``: indirect paths (action
      ``U(v)``) beat direct ones between 0 and w.  Only for ``|a| <= Delta`` and ``t >= t_a``.
    * ``"u"``: eq. (45) (upper sign for ``v0 > 0``: the sign of v0 picks the branch), the limit ``t_b = t_a`` of
      indirect crossing paths: between u and 0 the indirect crossing path wins.  Only for
      ``|a| <= Delta`` and ``t >= t_a``.
    * ``"w_cr"``: eq. (49) (numerical), for ``|a| > Delta`` and v0 on the side opposite to the
      attractor: between w_cr and 0 the twice-crossing path beats the direct one.  It grows
      like ``e^{t/tau_m}``; once the two actions (~ v^2) agree to rounding the root is found
      to that precision, and beyond ``|v| ~ 1e150`` (t > ~340 tau_m) it is ``-inf``.

    NaN where a boundary does not apply.  ``v0 = 0`` is taken as the limit ``v0 -> 0+`` (then
    w and u are the upper and lower edges of the indirect region).  Each formula agrees with
    the continuity of the minimal action across it (checked in the tests).
    """
    t0 = _finite("t0", t0)
    v0 = _finite("v0", v0)
    t_arr = np.asarray(t, dtype=float)
    if not np.all(np.isfinite(t_arr)):
        raise ValueError("t must be finite")
    if np.any(t_arr <= t0):
        raise ValueError(f"t must be > t0 (= {t0!r})")
    T = t_arr - t0
    fr = _Frame.of(model)
    v0c = fr.flip * v0
    s0 = fr.flip * (math.copysign(1.0, v0) if v0 != 0 else 1.0)  # canonical side of v0
    nan = np.full(T.shape, np.nan)
    w = u = w_cr = nan
    if fr.a <= fr.delta:
        c0, c1 = fr.c(s0), fr.c(-s0)
        y0 = abs(v0c) + c0
        after = T >= fr.stick_time(s0, abs(v0c))
        if np.any(after):
            tt = np.minimum(T / fr.tau, 700.0)
            E, Ei = np.exp(tt), np.exp(-tt)
            # eq. (41), lower root, written without cancellation for large t
            root = np.sqrt(np.maximum((y0 * y0 - c0 * c0) * -np.expm1(-2.0 * tt), 0.0))
            if y0 > 0:
                w_mag = (y0 * y0 * Ei + c0 * c0 * (E - Ei)) / (y0 + root) - c0
            else:  # v0 = 0 with a = +-Delta: the indirect region on that side is {0}
                w_mag = np.zeros(T.shape)
            w = np.where(after, s0 * fr.flip * w_mag, np.nan)
            ratio = c0 / y0 if y0 > 0 else 1.0
            u_mag = c1 * (E * ratio - 1.0)  # eq. (45)
            u = np.where(after, -s0 * fr.flip * u_mag, np.nan)
    elif s0 < 0:
        w_cr = fr.flip * _w_cr(fr, v0c, np.maximum(T, 0.0).astype(float))
    out = {"w": w, "u": u, "w_cr": w_cr}
    if t_arr.ndim == 0:
        return {k: float(x) for k, x in out.items()}
    return out


def boundary_examples(model: Model, t: float, v0: float, margin: float = 0.8,
                      t0: float = 0.0) -> dict[str, float]:
    """Final velocities at time t of one optimal path of each kind around the boundary lines
    of :func:`boundaries` (paper, Fig. 5; stick regime ``|a| <= Delta``, ``t >= t_a``): beyond
    the stick band ``[min(w, u), max(w, u)]`` by ``margin`` on the side of v0 a direct path,
    on the other side a direct-crossing one, and ``u/2`` (inside the band, between u and 0 on
    the side opposite to v0) an indirect-crossing one.  Keys are names of :data:`KINDS`; the
    tests check that :func:`optimal_path` has that kind at each velocity."""
    if not abs(model.a) <= model.delta:
        raise ValueError(f"boundary_examples needs the stick regime |a| <= Delta, got a={model.a!r}, "
                         f"Delta={model.delta!r}")
    b = boundaries(model, float(t), v0, t0)
    w, u = float(b["w"]), float(b["u"])
    if math.isnan(w) or math.isnan(u):
        raise ValueError(f"t={t!r} is before the stick time t_a: the boundaries do not exist yet")
    above, below = max(w, u) + margin, min(w, u) - margin
    same, other = (above, below) if v0 >= 0 else (below, above)
    return {"direct": same, "direct-crossing": other, "indirect-crossing": 0.5 * u}


def propagator(model: Model, v: ArrayLike, t: float, v0: float,
               t0: float = 0.0) -> np.ndarray:
    """Saddle-point transition probability ``f(v,t|v0,t0) ~ exp(-gamma A*)`` (eq. (12);
    eqs. (46), (47), (51) and their mirror images), normalised on the grid ``v`` by the
    trapezoid rule, because the paper drops the Jacobian (eq. (10)) and the fluctuation
    factor.  The minimum action is subtracted before exponentiating (no underflow)."""
    t, t0 = _times(t, t0)
    v0 = _finite("v0", v0)
    v = _velocities(v)
    if v.ndim != 1 or v.size < 2 or not np.all(np.diff(v) > 0):
        raise ValueError("v must be a 1-D strictly increasing grid with at least 2 points")
    A = cast(np.ndarray, action(model, v, t, v0, t0))  # v is a 1-D grid: an array comes back
    f = np.exp(-model.gamma * (A - A.min()))
    out: np.ndarray = f / trapezoid(f, v)
    return out


# The work large deviations (section V) live in their own module; re-exported here so that
# ``analogue.theory.weak_noise`` is the one entry point to the paper's weak-noise theory.
from .weak_noise_work import rate_function, fluctuation_relation, work_optimal_path  # noqa: E402
