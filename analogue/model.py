"""Model parameters of the stick-slip Langevin equation and its noise-free facts.

The reduced equation (paper, eqs. bm and U_pot) is

    dv/dt = -U'(v) + xi(t)/m,   U(v) = v^2/(2 tau_m) + Delta |v| - a v,

with white noise of intensity ``<xi xi'> = 2 D delta``, so the velocity noise has
intensity ``1/gamma`` with ``gamma = m^2/D``:  ``dv = -U'(v) dt + sqrt(2/gamma) dW``.
With ``epsilon > 0`` the Coulomb term ``Delta sgn(v)`` is replaced by the smooth
``Delta tanh(v/epsilon)`` (the paper's suggested regularisation, and exactly what a
diode bridge of Shockley diodes does), whose potential is
``Delta epsilon ln cosh(v/epsilon)``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np
from scipy import integrate, optimize, special

from .checks import finite as _finite, nonnegative as _nonnegative, positive as _positive

__all__ = ["Model", "MechanicalParameters"]


class MechanicalParameters(NamedTuple):
    """The paper's eq. (model) in mechanical units: m v' + alpha v + Delta_F sgn(v) = F + xi."""

    mass: float
    alpha: float
    delta_F: float
    F: float
    D: float





def _logcosh(x):
    """ln cosh(x) without overflow."""
    ax = np.abs(x)
    return ax + np.log1p(np.exp(-2.0 * ax)) - math.log(2.0)


@dataclass(frozen=True)
class Model:
    """Parameters of the reduced stick-slip model (paper, eqs. bm and U_pot).

    Parameters
    ----------
    tau_m : float
        Inertial (viscous) relaxation time ``m/alpha``; > 0.
    delta : float
        Dry-friction threshold acceleration ``Delta = Delta_F/m``; >= 0.
    a : float
        External acceleration ``a = F/m``; any finite sign.
    gamma : float
        Inverse noise strength ``m^2/D``; > 0.  The weak-noise limit is gamma -> infinity.
    mass : float
        Mass ``m`` (only enters conversions to mechanical units and the work ``F = m a``); > 0.
    epsilon : float
        Width of the smooth friction law ``tanh(v/epsilon)``; 0 means the exact ``sgn``; >= 0.
    """

    tau_m: float
    delta: float
    a: float
    gamma: float
    mass: float = 1.0
    epsilon: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "tau_m", _positive("tau_m", self.tau_m))
        object.__setattr__(self, "delta", _nonnegative("delta", self.delta))
        object.__setattr__(self, "a", _finite("a", self.a))
        object.__setattr__(self, "gamma", _positive("gamma", self.gamma))
        object.__setattr__(self, "mass", _positive("mass", self.mass))
        object.__setattr__(self, "epsilon", _nonnegative("epsilon", self.epsilon))

    # ------------------------------------------------------------------ units
    @classmethod
    def from_mechanical(cls, mass, alpha, delta_F, F, D, epsilon=0.0) -> "Model":
        """Build from the paper's eq. (model) parameters: tau_m = m/alpha, Delta = Delta_F/m,
        a = F/m, gamma = m^2/D."""
        mass = _positive("mass", mass)
        alpha = _positive("alpha", alpha)
        delta_F = _nonnegative("delta_F", delta_F)
        F = _finite("F", F)
        D = _positive("D", D)
        return cls(tau_m=mass / alpha, delta=delta_F / mass, a=F / mass, gamma=mass**2 / D,
                   mass=mass, epsilon=epsilon)

    def mechanical(self) -> MechanicalParameters:
        """Inverse of :meth:`from_mechanical`."""
        m = self.mass
        return MechanicalParameters(mass=m, alpha=m / self.tau_m, delta_F=m * self.delta,
                                    F=m * self.a, D=m**2 / self.gamma)

    def replace(self, **changes) -> "Model":
        """A copy with some parameters changed (validated again)."""
        return replace(self, **changes)

    def as_dict(self) -> dict:
        return {"tau_m": self.tau_m, "delta": self.delta, "a": self.a, "gamma": self.gamma,
                "mass": self.mass, "epsilon": self.epsilon}

    # ------------------------------------------------------------- derived
    @property
    def force(self) -> float:
        """External force ``F = m a`` (the work is ``W = F * integral v``)."""
        return self.mass * self.a

    @property
    def noise_intensity(self) -> float:
        """Velocity-noise intensity ``1/gamma``: ``dv = -U' dt + sqrt(2/gamma) dW``."""
        return 1.0 / self.gamma

    @property
    def velocity_scale(self) -> float:
        """Thermal-like velocity scale ``sqrt(tau_m/gamma)`` (the Delta = 0 stationary std)."""
        return math.sqrt(self.tau_m / self.gamma)

    @property
    def regime(self) -> str:
        """``"stick"`` if |a| < Delta (v = 0 attracts, eq. det_eq case a), else ``"slip"``."""
        return "stick" if abs(self.a) < self.delta else "slip"

    @property
    def attractor(self) -> float:
        """Deterministic attractor: 0 if |a| <= Delta, else ``v_ss = (a - Delta sgn a) tau_m``
        (eq. v_st, and its mirror for a < -Delta)."""
        if abs(self.a) <= self.delta:
            return 0.0
        return (self.a - math.copysign(self.delta, self.a)) * self.tau_m

    # ---------------------------------------------------------- friction law
    def coulomb(self, v):
        """Dry-friction acceleration ``Delta sgn(v)`` (or ``Delta tanh(v/epsilon)``)."""
        v = np.asarray(v, dtype=float)
        if self.epsilon > 0:
            return self.delta * np.tanh(v / self.epsilon)
        return self.delta * np.sign(v)

    def drift(self, v):
        """``-U'(v) = -v/tau_m - Delta sgn(v) + a`` (eq. det_eq)."""
        v = np.asarray(v, dtype=float)
        return -v / self.tau_m - self.coulomb(v) + self.a

    def potential(self, v):
        """Effective potential U(v) (eq. U_pot); with epsilon > 0 the term Delta|v| becomes
        ``Delta epsilon ln cosh(v/epsilon)``, whose derivative is ``Delta tanh(v/epsilon)``."""
        v = np.asarray(v, dtype=float)
        if self.epsilon > 0:
            dry = self.delta * self.epsilon * _logcosh(v / self.epsilon)
        else:
            dry = self.delta * np.abs(v)
        return v * v / (2.0 * self.tau_m) + dry - self.a * v

    def potential_minimum(self) -> float:
        """Location of the minimum of U (U is strictly convex: U'' >= 1/tau_m)."""
        if self.epsilon == 0:
            return self.attractor
        lo = (self.a - self.delta) * self.tau_m - 1.0
        hi = (self.a + self.delta) * self.tau_m + 1.0
        return optimize.brentq(lambda v: -float(self.drift(v)), lo, hi, xtol=1e-15, rtol=1e-15)

    def log_normaliser(self) -> float:
        """``ln Z`` with ``Z = integral exp(-gamma U(v)) dv`` (so ``p_s = exp(-gamma U)/Z``)."""
        g, tau = self.gamma, self.tau_m
        if self.epsilon == 0:
            # integral_0^inf exp(-v^2/(2 s^2) - b v) dv = s sqrt(2 pi) exp(b^2 s^2/2) Phi(-b s)
            s = math.sqrt(tau / g)
            def half(b):
                return (math.log(s * math.sqrt(2 * math.pi)) + 0.5 * (b * s) ** 2
                        + float(special.log_ndtr(-b * s)))
            return float(np.logaddexp(half(g * (self.delta - self.a)), half(g * (self.delta + self.a))))
        # Smooth law: U'' >= 1/tau_m, so the density is log-concave with width <= sqrt(tau/g);
        # integrating 40 widths either side of the mode captures everything.
        v_star = self.potential_minimum()
        u_star = float(self.potential(v_star))
        w = 40.0 * math.sqrt(tau / g)
        pts = sorted({v_star, 0.0, -self.epsilon, self.epsilon})
        pts = [p for p in pts if v_star - w < p < v_star + w]
        val, _ = integrate.quad(lambda v: math.exp(-g * (float(self.potential(v)) - u_star)),
                                v_star - w, v_star + w, points=pts or None, limit=400,
                                epsabs=0, epsrel=1e-12)
        return math.log(val) - g * u_star

    def stationary_pdf(self, v):
        """Normalised stationary density ``p_s = exp(-gamma U)/Z`` (eq. p_stat); exact at every
        gamma for this 1-D additive-noise model."""
        return np.exp(-self.gamma * self.potential(v) - self.log_normaliser())

    # ------------------------------------------------------- deterministic
    def stick_time(self, v0: float) -> float:
        """Time for the noise-free motion from v0 to reach v = 0 (``t_a`` of eq. tbar1), or
        ``inf`` if it never does.  Only for the exact sgn law."""
        v0 = _finite("v0", v0)
        if v0 == 0:
            return 0.0
        s = 1.0 if v0 > 0 else -1.0
        b = (self.delta - s * self.a) * self.tau_m  # relaxation offset on v0's half line
        if b <= 0:
            return math.inf
        return self.tau_m * math.log1p(abs(v0) / b)

    def deterministic(self, v0: float, t):
        """Noise-free solution of eq. (det_eq) from ``v(0) = v0`` at times ``t >= 0``.

        On each half line the motion is the basic solution
        ``v(t) = (v0 + (Delta - a) tau_m) e^{-t/tau_m} - (Delta - a) tau_m`` (v > 0) and its
        mirror; v = 0 is reached in the finite time ``t_a`` (eq. tbar1) when |a| < Delta and
        the object then sticks; for |a| > Delta it crosses v = 0 with a kink and relaxes to
        ``v_ss`` (eq. v_st).  With epsilon > 0 the smooth ODE is integrated numerically.
        """
        v0 = _finite("v0", v0)
        t = np.asarray(t, dtype=float)
        if np.any(t < 0) or not np.all(np.isfinite(t)):
            raise ValueError("t must be finite and >= 0")
        if self.epsilon > 0:
            return self._deterministic_smooth(v0, t)
        if v0 < 0 or (v0 == 0 and self.a < 0):
            return -self.replace(a=-self.a)._deterministic_upper(-v0, t)
        return self._deterministic_upper(v0, t)

    def _deterministic_upper(self, v0: float, t):
        """sgn law, v0 >= 0, and a >= 0 whenever v0 == 0."""
        tau, d, a = self.tau_m, self.delta, self.a
        bp = (d - a) * tau
        bm = (d + a) * tau
        if v0 == 0:
            if abs(a) <= d:
                return np.zeros_like(t)
            return -bp * (1.0 - np.exp(-t / tau))  # a > Delta: leaves 0 upwards
        upper = (v0 + bp) * np.exp(-t / tau) - bp
        t1 = self.stick_time(v0)
        if not math.isfinite(t1):
            return upper
        after = np.zeros_like(t)
        if a < -d:  # crosses into v < 0 and relaxes to (a + Delta) tau_m
            after = bm * (1.0 - np.exp(-(t - t1) / tau))
        return np.where(t < t1, upper, after)

    def _deterministic_smooth(self, v0, t):
        t_end = float(t.max()) if t.size else 0.0
        if t_end == 0:
            return np.full_like(t, v0)
        # Stiff near v = 0 when epsilon is small: use an implicit method with the exact Jacobian.
        def jac(s, v):
            sech2 = 1.0 - np.tanh(v[0] / self.epsilon) ** 2  # no overflow, unlike 1/cosh^2
            return [[-1.0 / self.tau_m - self.delta / self.epsilon * sech2]]
        sol = integrate.solve_ivp(lambda s, v: self.drift(v), (0.0, t_end), [v0], method="Radau",
                                  jac=jac, dense_output=True, rtol=1e-10, atol=1e-12 * max(1.0, abs(v0)))
        return sol.sol(t.ravel())[0].reshape(t.shape)
