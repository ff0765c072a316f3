"""Optimal-path pieces on one half plane of the velocity-time plane (paper, section III).

On the half plane ``sigma v > 0`` (``sigma = +1`` upper, ``-1`` lower) the Euler-Lagrange
equations (15a)/(15b) are linear.  With the shifted coordinate

    y = |v| + b tau_m,     b = b_sigma = Delta - sigma a,

both half planes become the same Ornstein-Uhlenbeck problem ``L = (y' + y/tau_m)^2 / 4`` and
the basic solutions (eq. (16)) are ``y(s) = P e^{s/tau} + Q e^{-s/tau}``.  ``v = 0`` is
``y = b tau_m``; a piece is *admissible* if ``y(s) >= b tau_m`` all along it (it stays on its
own half plane).  ``b > 0`` means v = 0 attracts from that side, ``b < 0`` that the side holds
the slip attractor ``|v| = -b tau_m`` (``y = 0``).

Along a piece the "energy" ``E = y'^2 - y^2/tau_m^2`` is conserved (``E = 4 H`` with the
Hamiltonian ``H = p^2 - p U'``), and ``dLambda/dT = -E/4``.  Optimal switching times at a
crossing of ``v = 0`` are the times at which the energies of the adjoining pieces agree
(the stationarity conditions eq. (25) and the minimisation behind eq. (36)).

Everything here is pure, vectorised numpy on broadcastable arrays; times are durations
``T > 0`` of a piece.
"""
from __future__ import annotations

import numpy as np

# the pieces are vectorised: every argument is a float or an array (broadcast together)
FloatOrArray = float | np.ndarray

__all__ = ["ou_action", "ou_action_rate", "bridge", "bridge_min", "monotone_time"]


def _e(T: FloatOrArray, tau: float) -> np.ndarray:
    return np.exp(-np.asarray(T, dtype=float) / tau)


def ou_action(y0: FloatOrArray, y1: FloatOrArray, T: FloatOrArray, tau: float) -> np.ndarray:
    """Action of the basic solution from ``y0`` to ``y1`` in time ``T`` (eq. (20)):

    ``Lambda = (y1 - y0 e^{-T/tau})^2 / (2 tau (1 - e^{-2T/tau}))``, i.e. eq. (20) divided
    through by ``e^{2t/tau}``, which never overflows.  ``Lambda_pm(v,t;v0,t0)`` is this with
    ``y = |v| + (Delta -+ a) tau_m``.
    """
    T = np.asarray(T, dtype=float)
    e = _e(T, tau)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        return (y1 - y0 * e) ** 2 / (2.0 * tau * -np.expm1(-2.0 * T / tau))


def ou_action_rate(y0: FloatOrArray, y1: FloatOrArray, T: FloatOrArray, tau: float) -> np.ndarray:
    """``dLambda/dT = (y1 - y0 e)(y0 - y1 e) e / (tau^2 (1 - e^2)^2)`` with ``e = e^{-T/tau}``
    (minus the Hamiltonian of the piece); used for the stationarity condition eq. (25)."""
    T = np.asarray(T, dtype=float)
    e = _e(T, tau)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.asarray((y1 - y0 * e) * (y0 - y1 * e) * e
                          / (tau**2 * np.expm1(-2.0 * T / tau) ** 2))


def bridge(y0: FloatOrArray, y1: FloatOrArray, T: FloatOrArray, tau: float, s: FloatOrArray) -> np.ndarray:
    """The basic solution (eq. (16) with eqs. (18), (19)) at times ``0 <= s <= T``:

    ``y(s) = [y0 sinh((T - s)/tau) + y1 sinh(s/tau)] / sinh(T/tau)``, written with decaying
    exponentials only.
    """
    s = np.asarray(s, dtype=float)
    den = -np.expm1(-2.0 * T / tau)
    left = y0 * np.exp(-s / tau) * -np.expm1(-2.0 * (T - s) / tau) / den
    right = y1 * np.exp(-(T - s) / tau) * -np.expm1(-2.0 * s / tau) / den
    return left + right


def bridge_min(y0: FloatOrArray, y1: FloatOrArray, T: FloatOrArray, tau: float) -> np.ndarray:
    """Minimum of the basic solution over ``[0, T]`` (vectorised).

    ``y = P e^{s/tau} + Q e^{-s/tau}`` with ``P = (y1 - y0 e) e/(1 - e^2)`` and
    ``Q = (y0 - y1 e)/(1 - e^2)``, ``e = e^{-T/tau}``; an interior minimum exists iff
    ``P, Q > 0`` and ``0 < s* < T`` with ``e^{2 s*/tau} = Q/P``, and equals ``2 sqrt(P Q)``.
    Written with ``sqrt(e) = e^{-T/(2 tau)}`` and logarithms so that nothing underflows to a
    wrong verdict when ``e`` itself is below the double range (``T > 745 tau``).
    """
    y0, y1, T = np.broadcast_arrays(np.asarray(y0, float), np.asarray(y1, float),
                                    np.asarray(T, float))
    e = _e(T, tau)
    one = -np.expm1(-2.0 * T / tau)
    p_ = y1 - y0 * e  # P up to the positive factor e/(1 - e^2)
    q_ = y0 - y1 * e  # Q up to the positive factor 1/(1 - e^2)
    ends = np.minimum(y0, y1)
    with np.errstate(divide="ignore", invalid="ignore"):
        s_star = 0.5 * tau * (np.log(q_) - np.log(p_) + T / tau)
        interior = (p_ > 0) & (q_ > 0) & (s_star > 0) & (s_star < T)
        inner = 2.0 * np.sqrt(np.where(interior, p_ * q_, 0.0)) * np.exp(-0.5 * T / tau) / one
    return np.where(interior, np.minimum(inner, ends), ends)


def monotone_time(y_start: FloatOrArray, y_end: FloatOrArray, E: FloatOrArray, tau: float) -> np.ndarray:
    """Duration of a piece that runs *monotonically* from ``y_start`` to ``y_end`` (same sign)
    on the orbit ``y'^2 - y^2/tau^2 = E``:

    ``T = tau |ln[(|y_end| + sqrt(y_end^2 + E tau^2)) / (|y_start| + sqrt(y_start^2 + E tau^2))]|``

    (arcsinh for ``E > 0``, arccosh for ``E < 0``, ``ln`` for ``E = 0`` in one formula).
    """
    def g(y: FloatOrArray) -> np.ndarray:
        ay = np.abs(y)
        return np.asarray(np.log(ay + np.sqrt(np.maximum(ay * ay + E * tau * tau, 0.0))))
    return np.asarray(tau * np.abs(g(y_end) - g(y_start)))
