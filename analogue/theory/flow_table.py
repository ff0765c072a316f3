"""The noise-free flow of a one-dimensional member, tabulated once: ``v(s)`` and ``int_0^s v``
for any start and duration by interpolation (for event-driven shot-noise Monte Carlo).

Between kicks the velocity obeys the autonomous 1-D ODE ``dv/dt = f(v)`` (``f`` =
:meth:`analogue.Model.drift`, spring = 0).  Its zeros and, for the exact sgn law, the kink at
``v = 0`` cut the line into intervals on which ``f`` has one sign, so the flow is monotone
there and is one trajectory: ``v = V(t)``, ``x = X(t)``, solved once per interval (DOP853,
rtol 1e-12) from its source end (an unstable zero, the kink, or the end of the table) to its
target (a stable zero, or the kink, reached in finite time).  A start ``v0`` is mapped to its
time on that trajectory ``t0 = V^{-1}(v0)``; then ``v(s) = V(t0 + s)`` and
``int_0^s v = X(t0 + s) - X(t0)``.  All three are cubic Hermite interpolants with exact
derivatives (``dV/dt = f(V)``, ``dt/dv = 1/f``, ``dX/dt = V``) on 4001 nodes per interval,
uniform in time, which keeps the error below ~1e-9 of the velocity scale (tests compare with
:func:`analogue.theory.deterministic.flow`).  Near a stable zero ``z`` the tabulated
trajectory stops at ``|v - z| = 1e-9 (scale)``; beyond, the linearised approach
``v - z ~ e^{f'(z) t}`` (error O((v - z)^2)).  At the kink the object sticks (``|a| <=
Delta(0)``) or crosses onto the other side's trajectory (at most once: the flow on the side of
``a`` leads away from 0).

This replaces RK4 substeps of ``dt`` for every replica between kicks (circuits/stribeck.toml
with shot noise: 200 replicas x 10 tau_m took 21 s).
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import integrate, optimize
from scipy.interpolate import CubicHermiteSpline

from ..model import Model

__all__ = ["FlowTable", "flow_table"]

_NODES = 4001
_RTOL = 1e-12


@dataclass(frozen=True)
class _Piece:
    """One monotone trajectory: from ``source`` (t = 0) towards ``target`` (reached at
    ``t_end`` when ``finite``; a stable zero approached exponentially with rate ``kappa``
    otherwise).  ``lo <= v <= hi`` is the interval it covers."""

    lo: float
    hi: float
    direction: float  # sign of f on the interval
    target: float
    finite: bool       # True: the target (kink or table end) is reached at t_end
    kappa: float       # -f'(target) for a stable zero, else 0
    t_end: float
    v_end: float
    x_end: float
    V: CubicHermiteSpline   # t -> v
    X: CubicHermiteSpline   # t -> int_0^t v
    T: CubicHermiteSpline   # v -> t (v increasing)

    def time_of(self, v: np.ndarray) -> np.ndarray:
        out: np.ndarray = np.clip(self.T(v), 0.0, self.t_end)
        return out

    def advance(self, t0: np.ndarray, s: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(v, x increment, time left over after reaching a finite target, reached) from
        times t0."""
        t1 = t0 + s
        inside = t1 <= self.t_end
        tc = np.minimum(t1, self.t_end)
        v = self.V(tc)
        dx = self.X(tc) - self.X(t0)
        over = np.where(inside, 0.0, t1 - self.t_end)
        if not self.finite:  # linearised approach to the stable zero
            e = np.exp(-self.kappa * over)
            dev = self.v_end - self.target
            v = np.where(inside, v, self.target + dev * e)
            dx = dx + np.where(inside, 0.0, self.target * over + dev * (1.0 - e) / self.kappa)
            over = np.zeros_like(over)
        else:
            v = np.where(inside, v, self.target)
        return np.asarray(v, dtype=float), np.asarray(dx, dtype=float), over, ~inside


@dataclass(frozen=True)
class FlowTable:
    """The tabulated flow of one member on ``[lo, hi]`` (module docstring); :meth:`flow`
    advances arrays of velocities by arrays of durations."""

    model: Model
    lo: float
    hi: float
    edges: np.ndarray            # interval boundaries, increasing
    pieces: tuple[_Piece, ...]   # one per interval
    kink: bool                   # the sgn law's kink at 0 is a boundary
    sticks: bool                 # at the kink: stick (True) or cross

    def covers(self, v: np.ndarray) -> np.ndarray:
        out: np.ndarray = (v >= self.lo) & (v <= self.hi)
        return out

    def _piece_index(self, v: np.ndarray) -> np.ndarray:
        idx = np.searchsorted(self.edges, v, side="right") - 1
        out: np.ndarray = np.clip(idx, 0, len(self.pieces) - 1)
        return out

    def flow(self, v: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(v(s), int_0^s v)`` for starts ``v`` (all inside :meth:`covers`) and durations
        ``s >= 0``."""
        v = np.asarray(v, dtype=float).copy()
        s = np.asarray(s, dtype=float).copy()
        dx = np.zeros_like(v)
        active = s > 0
        if self.kink:
            at_zero = v == 0.0
            if self.sticks:
                active &= ~at_zero
            else:  # leaves at once on the side of a: start of that side's piece
                v = np.where(at_zero & active, math.copysign(1e-300, self.model.a), v)
        for _ in range(3):  # a crossing at the kink continues on the other side (once)
            if not active.any():
                break
            idx = self._piece_index(v)
            nxt = np.zeros_like(active)
            for j in np.unique(idx[active]):
                sel = active & (idx == j)
                p = self.pieces[int(j)]
                t0 = p.time_of(v[sel])
                vn, d, over, reached = p.advance(t0, s[sel])
                dx[sel] += d
                s[sel] = over
                if p.finite and self.kink and p.target == 0.0:
                    # arrived at the kink: stick there, or cross and go on (marker +-1e-300
                    # puts the start on the other side's piece)
                    go = reached & (over > 0) & (not self.sticks)
                    vn = np.where(reached, np.where(go, math.copysign(1e-300, p.direction),
                                                    0.0), vn)
                    nxt[sel] = go
                v[sel] = vn
            active = nxt
        v = np.where(np.abs(v) <= 1e-300, 0.0, v)  # the +-1e-300 markers of the kink
        return v, dx

    def _departs_from_kink(self, p: _Piece) -> bool:
        return self.kink and (p.lo if p.direction > 0 else p.hi) == 0.0

    def _arrival(self, side: float) -> _Piece | None:
        """The piece on the side ``side`` of 0 whose flow reaches the kink (finite target)."""
        for p in self.pieces:
            if p.finite and p.target == 0.0 and math.copysign(1.0, p.lo + p.hi) == side:
                return p
        return None

    def backward(self, v: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(u, valid)``: the velocities ``u`` that the flow takes to ``v`` in the durations
        ``s >= 0`` (``v != 0``, inside :meth:`covers`).  Backwards each trajectory runs to its
        source; where ``s`` is longer than the time from the source, ``valid`` is False: the
        source is the end of the table (``u`` lies beyond it) or an unstable zero (``u``
        within 1e-9 of the scale of it, where the flow has no speed).  A trajectory that
        left the kink (slip regime) is continued backwards on the side it came from."""
        v = np.asarray(v, dtype=float)
        s = np.asarray(s, dtype=float)
        v, s = np.broadcast_arrays(v, s)
        u = np.full(v.shape, np.nan)
        valid = np.zeros(v.shape, dtype=bool)
        idx = self._piece_index(v)
        for j in np.unique(idx):
            sel = idx == j
            p = self.pieces[int(j)]
            t0 = p.time_of(v[sel]) - s[sel]
            ok = t0 >= 0.0
            uu = np.where(ok, p.V(np.maximum(t0, 0.0)), np.nan)
            if self._departs_from_kink(p) and not self.sticks and (~ok).any():
                q = self._arrival(-p.direction)
                if q is not None:
                    tq = q.t_end + t0  # t0 < 0: time left before leaving the kink
                    more = ~ok & (tq >= 0.0)
                    uu = np.where(more, q.V(np.maximum(tq, 0.0)), uu)
                    ok = ok | more
            u[sel], valid[sel] = uu, ok
        return u, valid

    def time_from_kink(self, v: np.ndarray) -> np.ndarray:
        """Time since the flow left the kink, for ``v`` on a trajectory that left it (slip
        regime, the side of a); inf elsewhere."""
        v = np.asarray(v, dtype=float)
        out = np.full(v.shape, math.inf)
        if not self.kink or self.sticks:
            return out
        idx = self._piece_index(v)
        for j in np.unique(idx):
            p = self.pieces[int(j)]
            if self._departs_from_kink(p):
                sel = idx == j
                out[sel] = p.time_of(v[sel])
        return out

    def time_to_kink(self, v0: float) -> float:
        """Time for the flow from ``v0`` to reach the kink v = 0 (inf if it never does)."""
        if not self.kink or v0 == 0.0:
            return 0.0 if v0 == 0.0 else math.inf
        p = self.pieces[int(self._piece_index(np.array([v0]))[0])]
        if not (p.finite and p.target == 0.0):
            return math.inf
        return float(p.t_end - p.time_of(np.array([v0]))[0])


def _zeros(model: Model, lo: float, hi: float) -> list[float]:
    """All zeros of the drift in (lo, hi) away from the kink, by a scan of 20001 points and
    brentq (tolerance 1e-15)."""
    v = np.linspace(lo, hi, 20001)
    f = model.drift(v)
    out = []
    for i in np.flatnonzero(np.sign(f[:-1]) != np.sign(f[1:])):
        a, b = float(v[i]), float(v[i + 1])
        if model.epsilon == 0 and model.static_friction > 0 and a <= 0.0 <= b:
            continue
        if f[i] == 0.0:
            out.append(a)
        elif f[i + 1] == 0.0:
            out.append(b)
        else:
            out.append(optimize.brentq(lambda u: float(model.drift(u)), a, b, xtol=1e-15,
                                       rtol=1e-15))
    return sorted(set(out))


def _rhs(model: Model, side: float) -> Callable[[float, np.ndarray], list[float]]:
    """(v, x)' with the friction sign fixed to ``side`` (0 for the smooth law)."""
    def rhs(_t: float, y: np.ndarray) -> list[float]:
        u = float(y[0])
        if side == 0:
            fr = float(model.coulomb(u))
        else:
            fr = side * float(model.friction_magnitude(u))
        return [model.a - u / model.tau_m - model.cubic * u ** 3 - fr, u]
    return rhs


def _drift(model: Model, v: np.ndarray, side: float) -> np.ndarray:
    if side == 0:
        return np.asarray(model.drift(v), dtype=float)
    fr = side * np.asarray(model.friction_magnitude(v), dtype=float)
    return np.asarray(model.a - v / model.tau_m - model.cubic * v ** 3 - fr, dtype=float)


def _piece(model: Model, lo: float, hi: float, lo_kind: str, hi_kind: str, side: float,
           scale: float) -> _Piece:
    """Trajectory across the interval [lo, hi]; kinds: "zero", "kink", "end"."""
    mid = 0.5 * (lo + hi)
    d = math.copysign(1.0, float(_drift(model, np.array([mid]), side)[0]))
    src, src_kind, tgt, tgt_kind = (lo, lo_kind, hi, hi_kind) if d > 0 else (hi, hi_kind, lo, lo_kind)
    gap = 1e-9 * scale
    start = src + d * gap if src_kind == "zero" else src
    if tgt_kind == "zero":
        stop_at = tgt - d * gap
        kappa = -float(optimize.approx_fprime(np.array([tgt]),
                                              lambda u: float(_drift(model, u, side)[0]),
                                              1e-7 * scale)[0])
        kappa = max(kappa, 1e-300)
    else:
        stop_at, kappa = tgt, 0.0

    def reach(_t: float, y: np.ndarray) -> float:
        return float(y[0] - stop_at)
    reach.terminal = True  # type: ignore[attr-defined]
    # a generous horizon: the target is reached in finite time in every case (a zero's
    # neighbourhood gap at rate kappa in ~ln(1e9)/kappa)
    rate = abs(float(_drift(model, np.array([start]), side)[0])) + 1e-300
    horizon = 50.0 * (abs(tgt - start) / rate + model.tau_m + (40.0 / kappa if kappa > 0 else 0))
    sol = integrate.solve_ivp(_rhs(model, side), (0.0, horizon), [start, 0.0], method="DOP853",
                              rtol=_RTOL, atol=1e-14 * scale, dense_output=True, events=reach)
    if sol.t_events[0].size == 0:
        raise RuntimeError(f"flow table: the trajectory from {start:g} did not reach {tgt:g}")
    t_end = float(sol.t_events[0][0])
    t = np.linspace(0.0, t_end, _NODES)
    y = sol.sol(t)
    vv, xx = y[0], y[1]
    vv[0], vv[-1] = start, stop_at
    ff = _drift(model, vv, side)
    if src_kind == "kink":
        ff[0] = _drift(model, np.array([math.copysign(1e-300, -d)]), side)[0]
    order = np.argsort(vv)
    vs, ts, fs = vv[order], t[order], ff[order]
    keep = np.r_[True, np.diff(vs) > 0]
    T = CubicHermiteSpline(vs[keep], ts[keep], 1.0 / fs[keep])
    return _Piece(lo, hi, d, tgt, tgt_kind != "zero", kappa, t_end, float(stop_at), float(xx[-1]),
                  CubicHermiteSpline(t, vv, ff), CubicHermiteSpline(t, xx, vv), T)


def flow_table(model: Model, lo: float, hi: float) -> FlowTable:
    """Tabulate the flow of ``model`` (spring = 0) for velocities in ``[lo, hi]`` (widened to
    contain every zero of the drift and 0)."""
    if model.spring > 0:
        raise ValueError("flow_table: spring > 0 (the flow is two-dimensional)")
    top = max(model.delta, model.static_friction)
    reach = model.tau_m * (abs(model.a) + top) * 1.01
    lo, hi = min(lo, -reach), max(hi, reach)
    scale = max(hi - lo, 1e-300)
    kink = model.epsilon == 0 and model.static_friction > 0
    zs = _zeros(model, lo, hi)
    bounds = [(lo, "end")] + [(z, "zero") for z in zs] + ([(0.0, "kink")] if kink else [])
    bounds.append((hi, "end"))
    bounds.sort()
    pieces = []
    for (a, ka), (b, kb) in zip(bounds[:-1], bounds[1:]):
        side = 0.0 if not kink else (1.0 if a >= 0.0 else -1.0)
        pieces.append(_piece(model, a, b, ka, kb, side, scale))
    edges = np.array([b for b, _ in bounds[:-1]])
    sticks = kink and abs(model.a) <= model.static_friction
    return FlowTable(model, lo, hi, edges, tuple(pieces), kink, sticks)
