"""Weak-noise theory for the model family: what of the paper's method carries over.

The paper's weak-noise results (sections III-IV) rest on three facts about
``dv = -U'(v) dt + sqrt(2/gamma) dW``: (i) one dimension with additive Gaussian noise, so
``p_s ~ exp(-gamma U)`` and the Onsager-Machlup action ``L = (v' + U'(v))^2/4`` governs
``f ~ exp(-gamma A*)``; (ii) U is piecewise quadratic, so the Euler-Lagrange equation
``v'' = U'(v) U''(v)`` is linear on each half line and the basic solutions (eq. (16)),
actions (eq. (20)) and gluing times (eqs. (31), (32), (25)) are closed forms;
(iii) the kink of U at ``v = 0`` (Coulomb friction) makes sticking free when
``|a| <= Delta``.

What survives, member by member
--------------------------------
* **Cubic viscous friction, Stribeck law (1-D, Gaussian noise).** (i) and (iii) hold:
  ``p_s ~ exp(-gamma U)`` is exact at every gamma with the generalised U of
  :meth:`analogue.Model.potential`, so the stationary quasi-potential is ``U - U_min``
  (:func:`quasi_potential`); the Euler-Lagrange equation on each half line is
  ``v'' = U'(v) U''(v)`` with the conserved "energy" ``H = (v'^2 - U'^2)/4``; the path kinds
  (direct; indirect = relax, stick, leave; crossing kinds) keep their meaning, sticking is free
  iff ``|a| <= Delta(0) = delta_s`` (the static value), and the indirect action is
  ``U(v) - U(0) = U(v)`` whenever the relax and leave times fit in t.  The time-reversal
  identity ``A(v, t | v0) - A(v0, t | v) = U(v) - U(v0)`` of a gradient system holds for direct
  paths.  (ii) does not: the basic solutions, actions and gluing times are no longer closed
  forms.  Here the direct path is a boundary-value problem solved numerically
  (:func:`direct_path`), the indirect action uses numerical relax/leave times; the crossing
  kinds (one or two crossings of v = 0 with gluing conditions) are not implemented for the
  family.  Stribeck's velocity weakening can make U double-welled (``U'' < 0`` near the
  slip state): then the weak-noise law is bimodal and the work rate function of the paper's
  closed form (eq. (64)) does not apply.
* **Shot noise.** No Gaussian weak-noise limit: the kicks are not small Gaussian increments,
  the path weight is not ``exp(-gamma A)`` with a quadratic Lagrangian (a large-deviation
  theory of jump processes has a Legendre-type Lagrangian ``sup_p [p v' - H(v, p)]`` with
  ``H = p f(v) + rate (E e^{p z} - 1)``), and without Gaussian noise the law has an atom at
  v = 0.  Only the diffusion limit (``rate -> inf``, ``rate mean^2`` fixed) returns to the
  Gaussian theory with ``1/gamma = rate mean^2``.  The exact numerics of
  :mod:`analogue.theory.family` are the reference.
* **Spring.** The state (x, v) is two-dimensional and the drift is not a gradient
  (``(v, -U'(v) - spring x)`` has a rotational part), so neither ``exp(-gamma U)`` nor the
  one-dimensional optimal-path construction applies; the quasi-potential would need the 2-D
  Hamilton-Jacobi equation.  Monte Carlo (:func:`analogue.montecarlo.simulate_sde`) is the
  reference.

The paper's own model keeps :func:`analogue.theory.weak_noise.action` unchanged; the
functions here work for it too (and are tested against it), for the exact sgn law
(``epsilon`` ignored, as in the paper's theory).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike
from scipy import integrate

from .. import checks
from ..model import Model

__all__ = ["quasi_potential", "direct_path", "direct_action", "indirect_action", "action",
           "DirectPath"]


def _check(model: object) -> Model:
    model = checks.instance("model", model, Model, description="an analogue.Model")
    if not (model.dimension == 1 and model.noise_kind.white_gaussian_only):
        raise ValueError("the weak-noise theory applies to one-dimensional members with Gaussian "
                         "noise only, white (spring = 0, shot = None, noise = None); see the "
                         "module docstring")
    return model


def quasi_potential(model: Model, v: ArrayLike) -> np.ndarray:
    """``U(v) - min U``: ``p_s ~ exp(-gamma (U - U_min))`` exactly, so this is the stationary
    quasi-potential of every 1-D Gaussian member (eq. (6) with the generalised U)."""
    _check(model)
    return model.potential(v) - float(model.potential(model.potential_minimum()))


def _u1(model: Model, v: np.ndarray, s: float) -> np.ndarray:
    """U'(v) on the half line of sign s (friction sign fixed)."""
    return (v / model.tau_m + model.cubic * v**3 + s * model.friction_magnitude(v) - model.a)


def _u2(model: Model, v: np.ndarray, s: float) -> np.ndarray:
    """U''(v) on the half line of sign s (no delta at 0)."""
    out = 1.0 / model.tau_m + 3.0 * model.cubic * v**2
    return model.friction.add_magnitude_curvature(out, v)


class DirectPath(NamedTuple):
    t: np.ndarray
    v: np.ndarray
    action: float


def direct_path(model: Model, v: float, t: float, v0: float, n: int = 400) -> DirectPath:
    """The direct optimal path from ``v0`` at time 0 to ``v`` at time ``t`` on one half line:
    the boundary-value problem ``v'' = U'(v) U''(v)`` (the Euler-Lagrange equation of
    ``L = (v' + U')^2/4``) solved with :func:`scipy.integrate.solve_bvp` (tolerance 1e-10), and
    its action ``int L dt``.  ``action`` is ``nan`` when the solution leaves the half line (no
    direct path; a crossing or sticking path is needed)."""
    _check(model)
    v, v0, t = float(v), float(v0), float(t)
    if not t > 0:
        raise ValueError(f"t must be > 0, got {t!r}")
    s = math.copysign(1.0, v0 if v0 != 0 else v)
    if v0 * v < 0:
        return DirectPath(np.array([0.0, t]), np.array([v0, v]), math.nan)

    def rhs(_t: np.ndarray, y: np.ndarray) -> np.ndarray:
        return np.vstack([y[1], _u1(model, y[0], s) * _u2(model, y[0], s)])

    def bc(ya: np.ndarray, yb: np.ndarray) -> np.ndarray:
        return np.array([ya[0] - v0, yb[0] - v])

    tt = np.linspace(0.0, t, 201)
    # initial guess: the straight line (velocity (v - v0)/t)
    guess = np.vstack([v0 + (v - v0) * tt / t, np.full_like(tt, (v - v0) / t)])
    sol = integrate.solve_bvp(rhs, bc, tt, guess, tol=1e-10, max_nodes=200_000)
    if not sol.success:
        raise RuntimeError(f"direct path v0={v0}, v={v}, t={t}: {sol.message}")
    ts = np.linspace(0.0, t, max(int(n), 2001))
    y = sol.sol(ts)
    lag = 0.25 * (y[1] + _u1(model, y[0], s)) ** 2
    act = float(integrate.simpson(lag, x=ts))
    if np.any(s * y[0] < -1e-12 * max(1.0, abs(v0), abs(v))):
        act = math.nan
    keep = np.linspace(0, ts.size - 1, int(n)).astype(int)
    return DirectPath(ts[keep], y[0][keep], act)


def direct_action(model: Model, v: float, t: float, v0: float) -> float:
    """Action of :func:`direct_path` (nan if there is no direct path)."""
    return direct_path(model, v, t, v0, n=2).action


def _time_to_zero(model: Model, v: float, sign_flow: float) -> float:
    """Duration of the monotone deterministic (sign_flow = +1) or time-reversed uphill
    (sign_flow = -1) motion between ``v`` and 0 on v's half line: ``int |dv| / |U'(v)|``; inf if
    U' vanishes or has the wrong sign in between."""
    if v == 0:
        return 0.0
    s = math.copysign(1.0, v)
    u = np.linspace(0.0, abs(v), 4001)[1:] * s
    du = _u1(model, u, s)
    # relaxation towards 0 needs s U' > 0 on the way (drift -U' points to 0); the reversed
    # uphill path from 0 needs the same sign (it climbs against the drift)
    if np.any(s * du <= 0):
        return math.inf
    val, _ = integrate.quad(lambda x: 1.0 / abs(float(_u1(model, s * x, s))), 0.0, abs(v),
                            limit=200, epsabs=0.0, epsrel=1e-10)
    return float(val)


def indirect_action(model: Model, v: float, t: float, v0: float) -> float:
    """Indirect path (eqs. (33)/(34) generalised): relax to 0 for free (time t_a), stick
    (free iff ``|a| <= Delta(0)``), climb to v along the time-reversed flow (time t_b); action
    ``U(v) - U(0) = U(v)`` if ``t_a + t_b <= t``, else inf."""
    _check(model)
    if abs(model.a) > model.static_friction:
        return math.inf
    ta = _time_to_zero(model, float(v0), +1.0)
    tb = _time_to_zero(model, float(v), -1.0)
    return float(model.potential(float(v))) if ta + tb <= t else math.inf


def action(model: Model, v: float, t: float, v0: float) -> float:
    """Minimal action over the path kinds implemented for the family (direct and indirect;
    see the module docstring for the crossing kinds)."""
    d = direct_action(model, v, t, v0)
    i = indirect_action(model, v, t, v0)
    cands = [x for x in (d, i) if not math.isnan(x)]
    return min(cands) if cands else math.nan
