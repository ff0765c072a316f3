"""Noise-free motion of every member of the model family (cubic, Stribeck, spring).

The paper's model has the closed form of :meth:`analogue.Model.deterministic`; the
extensions are integrated numerically.  With the exact sgn law the motion is split at
``v = 0``: on each half line the friction sign is fixed, so the ODE is smooth and an
8th-order Runge-Kutta with the event ``v = 0`` locates the arrival exactly.  At rest the
object sticks for good (without noise) if the net static force obeys
``|a - spring x| <= Delta(0)``, else it leaves in the direction of that force.

The numbers live here, below :mod:`analogue.model` (whose ``stick_time`` and ``deterministic``
call them for the family) and :mod:`analogue.theory.deterministic` (which re-exports them), so
that the model does not import the theory above it.  The model is read through the
:class:`NoiseFreeMember` protocol, so this module imports nothing of the package.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["flow", "stick_time", "NoiseFreeMember"]


class NoiseFreeMember(Protocol):
    """What the noise-free flow reads of a model (:class:`analogue.Model` has all of it)."""

    @property
    def tau_m(self) -> float: ...

    @property
    def a(self) -> float: ...

    @property
    def epsilon(self) -> float: ...

    @property
    def cubic(self) -> float: ...

    @property
    def spring(self) -> float: ...

    @property
    def x0(self) -> float: ...

    @property
    def static_friction(self) -> float: ...

    def coulomb(self, v: ArrayLike) -> np.ndarray: ...

    def friction_magnitude(self, v: ArrayLike) -> np.ndarray: ...


_RTOL = 1e-11


def _branch_rhs(model: NoiseFreeMember, s: float) -> Callable[[float, np.ndarray], list[float]]:
    """Right-hand side of (v, x) with the friction sign fixed to ``s`` (or tanh if smooth)."""
    def rhs(_t: float, y: np.ndarray) -> list[float]:
        v, x = y
        if s == 0:  # smooth law
            fr = float(model.coulomb(v))
        else:
            fr = s * float(model.friction_magnitude(v))
        return [-v / model.tau_m - model.cubic * v**3 - fr - model.spring * x + model.a, v]
    return rhs


def _leave_direction(model: NoiseFreeMember, x: float) -> float:
    """Sign in which a resting object at position x starts to move (0: stays stuck)."""
    f0 = model.a - model.spring * x
    return 0.0 if abs(f0) <= model.static_friction else math.copysign(1.0, f0)


def _segments(model: NoiseFreeMember, v0: float, x0: float, t_end: float
              ) -> Iterator[tuple[float, float, tuple[str, Any]]]:
    """Yield (t_start, t_stop, dense(t) -> (v, x) or None for rest at x) up to t_end."""
    # scipy where it is used: `import analogue` (which loads this module with the model) loads
    # no scipy (tests/unit/test_startup_imports.py, issue 22 item 3)
    from scipy import integrate
    t0, v, x = 0.0, float(v0), float(x0)
    smooth = model.epsilon > 0
    scale = max(abs(v0), model.tau_m * (abs(model.a) + model.static_friction), 1e-300)
    for _ in range(10_000):
        if t0 >= t_end:
            return
        if smooth:
            s = 0.0
        else:
            s = math.copysign(1.0, v) if v != 0 else _leave_direction(model, x)
            if s == 0:
                yield t0, t_end, ("rest", x)
                return
        ev: Any = None  # solve_ivp's event: a function carrying terminal/direction attributes
        if not smooth:
            def ev(_t: float, y: np.ndarray, s: float = s) -> float:
                return float(y[0])
            ev.terminal = True
            ev.direction = -s
        sol = integrate.solve_ivp(_branch_rhs(model, s), (t0, t_end), [v, x], method="DOP853",
                                  events=ev, dense_output=True, rtol=_RTOL,
                                  atol=1e-13 * scale)
        t1 = float(sol.t[-1])
        yield t0, t1, ("ode", sol.sol)
        if sol.status != 1:  # reached t_end
            return
        t0, v, x = t1, 0.0, float(sol.y_events[0][0][1])
    raise RuntimeError("too many crossings of v = 0 in the noise-free flow")


def flow(model: NoiseFreeMember, v0: float, x0: float, t: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Noise-free ``(v(t), x(t))`` from ``(v0, x0)`` at the times ``t >= 0`` (any shape)."""
    t = np.asarray(t, dtype=float)
    v_out = np.empty(t.shape)
    x_out = np.empty(t.shape)
    flat_t = t.ravel()
    fv, fx = v_out.reshape(-1), x_out.reshape(-1)
    t_end = float(flat_t.max()) if flat_t.size else 0.0
    if t_end == 0:
        fv[:], fx[:] = v0, x0
        return v_out, x_out
    for ta, tb, (kind, obj) in _segments(model, v0, x0, t_end):
        sel = (flat_t >= ta) & (flat_t <= tb)
        if not sel.any():
            continue
        if kind == "rest":
            fv[sel], fx[sel] = 0.0, obj
        else:
            y = obj(flat_t[sel])
            fv[sel], fx[sel] = y[0], y[1]
    return v_out, x_out


def stick_time(model: NoiseFreeMember, v0: float) -> float:
    """First time the noise-free motion from ``v0`` (and ``x0``) reaches ``v = 0``; inf if it
    does not within ``10^4 tau_m`` (it has then settled on a slip state)."""
    if v0 == 0:
        return 0.0
    if model.epsilon > 0:
        return math.inf
    t_end = 1e4 * model.tau_m
    for _, tb, _ in _segments(model, v0, model.x0, t_end):
        return tb if tb < t_end else math.inf  # the first segment's end: the first stop
    return math.inf
