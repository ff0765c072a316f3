"""Model parameters of the stick-slip Langevin equation, its family of extensions, and its
noise-free facts.

The reduced equation (paper, eqs. (4) and (5)) is

    dv/dt = -U'(v) + xi(t)/m,   U(v) = v^2/(2 tau_m) + Delta |v| - a v,

with white noise of intensity ``<xi xi'> = 2 D delta``, so the velocity noise has
intensity ``1/gamma`` with ``gamma = m^2/D``:  ``dv = -U'(v) dt + sqrt(2/gamma) dW``.
With ``epsilon > 0`` the Coulomb term ``Delta sgn(v)`` is replaced by the smooth
``Delta tanh(v/epsilon)`` (the paper's suggested regularisation, and exactly what a
diode bridge of Shockley diodes does), whose potential is
``Delta epsilon ln cosh(v/epsilon)``.

The family (the extensions the paper's conclusion proposes; keyword-only fields whose
defaults give the paper's model exactly):

    dv/dt = -v/tau_m - cubic v^3 - Delta(v) sgn v - spring x + a
            + sqrt(2/gamma) xi_G + shot kicks,                        dx/dt = v,

* ``cubic >= 0``: cubic viscous friction;
* ``stribeck = (delta_s, v_s)``: ``Delta(v) = Delta + (delta_s - Delta) exp(-|v|/v_s)``, the
  Stribeck curve (static threshold ``Delta(0) = delta_s``, dynamic ``Delta``);
* ``spring >= 0``: a linear spring ``-spring x`` with ``x(0) = x0``;
* ``shot``: :class:`ShotNoise` (kicks at ``rate``, exponential sizes of mean ``mean``,
  one- or two-sided);
* ``gamma = inf`` switches the Gaussian noise off.  Decision: ``gamma = inf`` with
  ``shot=None`` is allowed and is the *noise-free* model (``is_noisy`` is False); theory
  that needs noise (stationary law, propagator) refuses it with a ValueError naming gamma.

For every one-dimensional member (``spring = 0``) the drift is a gradient, ``-U'(v)`` with

    U = v^2/(2 tau_m) + cubic v^4/4 + Delta |v| + (delta_s - Delta) v_s (1 - e^{-|v|/v_s}) - a v,

so with Gaussian noise only, ``p_s ~ exp(-gamma U)`` stays exact (``is_gradient``).

Bounds (to keep every derived quantity far from float overflow; ``Model`` refuses values
outside them naming the parameter): nonzero magnitudes of all parameters lie in
``[1e-30, 1e30]``; the derived velocity scales ``sqrt(tau_m/gamma)``, ``|a| tau_m``,
``Delta tau_m``, ``delta_s tau_m`` and ``rate mean tau_m`` are at most ``1e15``
(``VELOCITY_LIMIT``).  Then ``v^4``, ``cubic v^4`` and ``gamma U`` stay below ``1e150``.
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import KW_ONLY, dataclass, field, fields, replace
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from . import checks, noise_free
from .variants import (FrictionLaw, Noise, Restoring, build_friction, build_noise,
                       build_restoring, noise_from_mapping)

__all__ = ["LIMIT", "VELOCITY_LIMIT", "MechanicalParameters", "Model", "ShotNoise"]

#: Largest allowed magnitude of any parameter (see module docstring).
LIMIT = 1e30
#: Largest allowed derived velocity scale (see module docstring).
VELOCITY_LIMIT = 1e15


class MechanicalParameters(NamedTuple):
    """The paper's eq. (1) in mechanical units: m v' + alpha v + Delta_F sgn(v) = F + xi."""

    mass: float
    alpha: float
    delta_F: float
    F: float
    D: float


# ------------------------------------------------------------------ checks
def _bounded(name: str, value, *, lower: str = "any", allow_inf: bool = False) -> float:
    """A real number (analogue.checks: TypeError for a bool or a string) with the sign rule
    ``lower`` ("positive", "nonnegative", "any") and the magnitude bounds of the module
    docstring."""
    if lower == "positive":
        x = checks.positive(name, value, allow_inf=allow_inf)
    elif lower == "nonnegative":
        x = checks.nonnegative(name, value)
    else:
        x = checks.finite(name, value)
    if math.isinf(x):
        return x
    if abs(x) > LIMIT or (x != 0 and abs(x) < 1.0 / LIMIT):
        what = "within" if lower == "positive" else "0 or of magnitude within"
        raise ValueError(f"{name} must be {what} [1e-30, 1e30], got {x!r}")
    return x


@dataclass(frozen=True)
class ShotNoise:
    """Poissonian shot noise: velocity kicks at ``rate`` per unit time, each exponentially
    distributed with mean ``mean``; with ``two_sided`` each kick's sign is +/- with
    probability 1/2.  Its mean force is ``rate * mean`` (one-sided) or 0 (two-sided)."""

    rate: float
    mean: float
    two_sided: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "rate", _bounded("shot.rate", self.rate, lower="positive"))
        object.__setattr__(self, "mean", _bounded("shot.mean", self.mean, lower="positive"))
        object.__setattr__(self, "two_sided", checks.flag("shot.two_sided", self.two_sided))

    @property
    def mean_force(self) -> float:
        """Mean acceleration the kicks exert, ``rate * <z>``."""
        return 0.0 if self.two_sided else self.rate * self.mean

    @property
    def intensity(self) -> float:
        """``rate <z^2> / 2 = rate mean^2``: the Gaussian intensity ``1/gamma`` with the same
        velocity-variance growth (the diffusion limit of many small kicks)."""
        return self.rate * self.mean**2

    def as_dict(self) -> dict:
        return {"rate": self.rate, "mean": self.mean, "two_sided": self.two_sided}


@dataclass(frozen=True)
class Model:
    """Parameters of the reduced stick-slip model (paper, eqs. (4) and (5)) and its family.

    Parameters
    ----------
    tau_m : float
        Inertial (viscous) relaxation time ``m/alpha``; > 0.
    delta : float
        Dry-friction threshold acceleration ``Delta = Delta_F/m``; >= 0 (the dynamic value
        when ``stribeck`` is set).
    a : float
        External acceleration ``a = F/m``; any finite sign.
    gamma : float
        Inverse noise strength ``m^2/D``; > 0.  The weak-noise limit is gamma -> infinity;
        ``math.inf`` switches the Gaussian noise off.
    mass : float
        Mass ``m`` (only enters conversions to mechanical units and the work ``F = m a``); > 0.
    epsilon : float
        Width of the smooth friction law ``tanh(v/epsilon)``; 0 means the exact ``sgn``; >= 0.

    Keyword-only (the extensions; see the module docstring):
    cubic >= 0, stribeck = None or (delta_s >= 0, v_s > 0), spring >= 0, x0 (initial
    position), shot = None or :class:`ShotNoise` (a mapping with its fields is accepted),
    noise = None or a registered noise kind (:data:`analogue.variants.NOISE_KINDS`, e.g.
    ``analogue.variants.OrnsteinUhlenbeck(tau_c)``, or its ``as_dict`` mapping).

    The variants (issue 20) are built here, once, and validated here: ``model.friction``
    (:mod:`analogue.variants.friction`: Coulomb, Stribeck, Cubic), ``model.restoring``
    (:mod:`analogue.variants.spring`: Free, Spring) and ``model.noise``
    (:mod:`analogue.variants.noise`: Silent, Gaussian, Shot, or the kind given); what differs
    between the members is found on them by dispatch.
    """

    tau_m: float
    delta: float
    a: float
    gamma: float
    mass: float = 1.0
    epsilon: float = 0.0
    _: KW_ONLY
    cubic: float = 0.0
    stribeck: tuple[float, float] | None = None
    spring: float = 0.0
    x0: float = 0.0
    shot: ShotNoise | None = field(default=None)
    noise: Noise | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        s = object.__setattr__
        s(self, "tau_m", _bounded("tau_m", self.tau_m, lower="positive"))
        s(self, "delta", _bounded("delta", self.delta, lower="nonnegative"))
        s(self, "a", _bounded("a", self.a))
        s(self, "gamma", _bounded("gamma", self.gamma, lower="positive", allow_inf=True))
        s(self, "mass", _bounded("mass", self.mass, lower="positive"))
        s(self, "epsilon", _bounded("epsilon", self.epsilon, lower="nonnegative"))
        s(self, "cubic", _bounded("cubic", self.cubic, lower="nonnegative"))
        s(self, "spring", _bounded("spring", self.spring, lower="nonnegative"))
        s(self, "x0", _bounded("x0", self.x0))
        if self.stribeck is not None:
            st = self.stribeck
            if isinstance(st, (str, bytes)) or not hasattr(st, "__len__") or len(st) != 2:
                raise TypeError(f"stribeck must be None or a pair (delta_s, v_s), got {st!r}")
            s(self, "stribeck", (_bounded("stribeck delta_s", st[0], lower="nonnegative"),
                                 _bounded("stribeck v_s", st[1], lower="positive")))
        if isinstance(self.shot, Mapping):
            s(self, "shot", ShotNoise(**self.shot))
        elif self.shot is not None and not isinstance(self.shot, ShotNoise):
            raise TypeError(f"shot must be None or analogue.ShotNoise, got {self.shot!r}")
        # Derived scales (module docstring): refuse what would overflow downstream.
        tau = self.tau_m
        if math.isfinite(self.gamma) and tau / self.gamma > VELOCITY_LIMIT**2:
            raise ValueError(f"gamma={self.gamma!r} is too small for tau_m={tau!r}: the velocity "
                             f"scale sqrt(tau_m/gamma) exceeds {VELOCITY_LIMIT:g}")
        for name, val in (("a", self.a), ("delta", self.delta),
                          ("stribeck delta_s", self.stribeck[0] if self.stribeck else 0.0)):
            if abs(val) * tau > VELOCITY_LIMIT:
                raise ValueError(f"{name}={val!r} with tau_m={tau!r} gives the velocity "
                                 f"{name} tau_m beyond {VELOCITY_LIMIT:g}; reduce {name} or tau_m")
        if self.shot is not None and max(self.shot.rate * tau, 1.0) * self.shot.mean > VELOCITY_LIMIT:
            raise ValueError(f"shot.mean * max(1, shot.rate tau_m) exceeds {VELOCITY_LIMIT:g}; "
                             f"reduce shot.mean or shot.rate")
        # The variants, chosen once (analogue.variants): a given noise kind is bound to gamma
        # and shot (and refuses what it cannot take); otherwise both choose the built-in kind.
        spec = self.noise
        if isinstance(spec, Mapping):
            spec = noise_from_mapping(spec)
        elif spec is not None and not isinstance(spec, Noise):
            raise TypeError(f"noise must be None or a noise kind of analogue.variants, got {spec!r}")
        s(self, "noise", (spec.bind(self.gamma, self.shot) if spec is not None
                          else build_noise(self.gamma, self.shot)))
        s(self, "_friction", build_friction(self.delta, self.epsilon, self.cubic, self.stribeck))
        s(self, "_restoring", build_restoring(self.spring, self.x0))

    def __repr__(self) -> str:
        # the dataclass fields, and the noise kind only where one was given (a built-in kind is
        # a function of gamma and shot, already shown)
        names = [f.name for f in fields(self) if f.name != "noise"]
        body = ", ".join(f"{n}={getattr(self, n)!r}" for n in names)
        if self.noise_kind.kind is not None:
            body += f", noise={self.noise_kind!r}"
        return f"{type(self).__name__}({body})"

    # ------------------------------------------------------------------ family flags
    @property
    def friction(self) -> FrictionLaw:
        """The friction law (:mod:`analogue.variants.friction`); ``model.friction(v)`` is the
        dry-friction acceleration, as :meth:`coulomb`."""
        return self.__dict__["_friction"]

    @property
    def restoring(self) -> Restoring:
        """The restoring force (:mod:`analogue.variants.spring`): Free or Spring."""
        return self.__dict__["_restoring"]

    @property
    def dimension(self) -> int:
        """1 for the velocity-only members, 2 with a spring (state (x, v))."""
        return self.restoring.dimension

    @property
    def is_paper(self) -> bool:
        """True for the paper's model (no extension field set; Gaussian noise on)."""
        return self.friction.closed_form and self.dimension == 1 and self.noise_kind.paper

    @property
    def noise_kind(self) -> Noise:
        """``self.noise``, typed (always a variant after construction)."""
        assert self.noise is not None
        return self.noise

    @property
    def is_noisy(self) -> bool:
        return self.noise_kind.is_noisy

    @property
    def is_gradient(self) -> bool:
        """Drift ``-U'(v)`` in one dimension with (only) Gaussian additive noise, so that
        ``p_s ~ exp(-gamma U)`` is the exact stationary law and the weak-noise theory of
        the paper (optimal paths of a 1-D gradient system) applies."""
        return self.dimension == 1 and self.noise_kind.paper

    @property
    def closed_form(self) -> bool:
        """The paper's law without a spring: the noise-free flow has the closed form of
        :meth:`deterministic` (epsilon = 0) and needs no numerical integration."""
        return self.friction.closed_form and self.restoring.closed_form

    # ------------------------------------------------------------------ units
    @classmethod
    def from_mechanical(cls, mass, alpha, delta_F, F, D, epsilon=0.0) -> Model:
        """Build from the paper's eq. (1) parameters: tau_m = m/alpha, Delta = Delta_F/m,
        a = F/m, gamma = m^2/D."""
        mass = checks.positive("mass", mass)
        alpha = checks.positive("alpha", alpha)
        delta_F = checks.nonnegative("delta_F", delta_F)
        F = checks.finite("F", F)
        D = checks.positive("D", D)
        return cls(tau_m=mass / alpha, delta=delta_F / mass, a=F / mass, gamma=mass**2 / D,
                   mass=mass, epsilon=epsilon)

    def mechanical(self) -> MechanicalParameters:
        """Inverse of :meth:`from_mechanical` (the paper's model parameters only)."""
        m = self.mass
        return MechanicalParameters(mass=m, alpha=m / self.tau_m, delta_F=m * self.delta,
                                    F=m * self.a, D=m**2 / self.gamma)

    def replace(self, **changes) -> Model:
        """A copy with some parameters changed (validated again)."""
        return replace(self, **changes)

    def as_dict(self) -> dict:
        """JSON-ready parameters; ``Model(**m.as_dict()) == m``.  The extension fields appear
        only when they differ from their defaults, so the paper's model keeps its keys."""
        d: dict[str, Any] = {"tau_m": self.tau_m, "delta": self.delta, "a": self.a,
                             "gamma": self.gamma, "mass": self.mass, "epsilon": self.epsilon}
        d.update(self.friction.entries())
        d.update(self.restoring.entries())
        d.update(self.noise_kind.entries())
        return d

    # ------------------------------------------------------------- derived
    @property
    def force(self) -> float:
        """External force ``F = m a`` (the work is ``W = F * integral v``)."""
        return self.mass * self.a

    @property
    def noise_intensity(self) -> float:
        """Gaussian velocity-noise intensity ``1/gamma`` (0 when gamma = inf)."""
        return 1.0 / self.gamma

    @property
    def velocity_scale(self) -> float:
        """Thermal-like velocity scale ``sqrt(tau_m/gamma)`` (the Delta = 0 stationary std);
        with shot noise the scale ``sqrt(tau_m rate mean^2)`` of its diffusion limit is added
        in quadrature."""
        return math.sqrt(self.tau_m * self.noise_kind.velocity_intensity)

    @property
    def static_friction(self) -> float:
        """``Delta(0)``: the threshold |force| that keeps a resting object stuck."""
        return self.friction.static

    @property
    def regime(self) -> str:
        """``"stick"`` if |a| < Delta(0) (v = 0 attracts, eq. (13) case a), else ``"slip"``."""
        return "stick" if abs(self.a) < self.static_friction else "slip"

    @property
    def attractor(self) -> float:
        """Deterministic attractor: 0 if |a| <= Delta(0), else ``v_ss = (a - Delta sgn a) tau_m``
        (eq. (14), and its mirror for a < -Delta); for the family, the zero of the drift
        reached from rest.  With a spring every motion ends at rest: 0."""
        return self.restoring.attractor(self)

    # ---------------------------------------------------------- friction law
    def friction_magnitude(self, v: ArrayLike) -> np.ndarray:
        """``Delta(v)``: Delta, or the Stribeck curve ``Delta + (delta_s - Delta) e^{-|v|/v_s}``."""
        return self.friction.magnitude(v)

    def coulomb(self, v: ArrayLike) -> np.ndarray:
        """Dry-friction acceleration ``Delta(v) sgn(v)`` (or ``Delta(v) tanh(v/epsilon)``)."""
        return self.friction.dry(v)

    def drift(self, v: ArrayLike, x: ArrayLike = 0.0) -> np.ndarray:
        """The force law ``-v/tau_m - cubic v^3 - Delta(v) sgn(v) - spring x + a`` (eq. (13)
        for the paper's model, where it is ``-U'(v)``)."""
        v = np.asarray(v, dtype=float)
        out = -v / self.tau_m - self.coulomb(v) + self.a
        return self.restoring.add_force(self.friction.add_drift(out, v), x)

    def _dry_potential(self, v: ArrayLike) -> np.ndarray:
        """``integral_0^v Delta(u) sgn(u) du`` (or with tanh)."""
        return self.friction.dry_potential(v)

    def potential(self, v: ArrayLike) -> np.ndarray:
        """Effective potential U(v) (eq. (5)) of the velocity equation; with epsilon > 0 the
        term Delta|v| becomes ``Delta epsilon ln cosh(v/epsilon)``.  For the family:
        ``+ cubic v^4/4 + (delta_s - Delta) v_s (1 - e^{-|v|/v_s})`` (the spring force is not
        a function of v: for spring > 0 this is U at x = 0 and the motion is not gradient)."""
        v = np.asarray(v, dtype=float)
        u = v * v / (2.0 * self.tau_m) + self._dry_potential(v) - self.a * v
        return self.friction.add_potential(u, v)

    def _support_bound(self, level: float = 800.0) -> float:
        """R with ``gamma (U(v) - min U) > level`` for |v| > R: U >= v^2/(2 tau_m) - |a||v|
        and min U <= U(0) = 0."""
        ta = self.tau_m * abs(self.a)
        return ta + math.sqrt(ta * ta + 2.0 * self.tau_m * level / self.gamma)

    def potential_minimum(self) -> float:
        """Location of the (global) minimum of U.  For the paper's model U is strictly convex
        (U'' >= 1/tau_m); Stribeck's velocity weakening can make it double-welled."""
        return self.friction.potential_minimum(self)

    def _require_gradient(self, what: str) -> None:
        if not (self.dimension == 1 and self.noise_kind.white_gaussian_only):
            raise ValueError(f"{what} = exp(-gamma U)/Z holds only for one-dimensional members "
                             f"with white Gaussian noise (spring=0, shot=None, noise=None); use "
                             f"analogue.theory.exact for this model")
        if not math.isfinite(self.gamma):
            raise ValueError(f"{what} needs noise: gamma must be finite, got {self.gamma!r}")

    def log_normaliser(self) -> float:
        """``ln Z`` with ``Z = integral exp(-gamma U(v)) dv`` (so ``p_s = exp(-gamma U)/Z``)."""
        self._require_gradient("log_normaliser")
        # cached per instance (frozen: the parameters cannot change); the family's quadrature
        # would otherwise run on every stationary_pdf call
        cached = self.__dict__.get("_log_z_cache")
        if cached is None:
            cached = self._log_normaliser()
            self.__dict__["_log_z_cache"] = cached
        return cached

    def _log_normaliser(self) -> float:
        return self.friction.log_normaliser(self)

    def stationary_pdf(self, v: ArrayLike) -> np.ndarray:
        """Normalised stationary density ``p_s = exp(-gamma U)/Z`` (eq. (6)); exact at every
        gamma for the 1-D additive-Gaussian-noise members."""
        log_z = self.log_normaliser()  # refuses non-gradient members and gamma = inf first
        return np.exp(-self.gamma * self.potential(v) - log_z)

    # ------------------------------------------------------- deterministic
    def stick_time(self, v0: float) -> float:
        """Time for the noise-free motion from v0 to reach v = 0 (``t_a`` of eq. (31)), or
        ``inf`` if it never does.  Exact sgn law (epsilon = 0) only; for the family
        (cubic, Stribeck) the ODE is integrated numerically."""
        v0 = checks.finite("v0", v0)
        if v0 == 0:
            return 0.0
        s = 1.0 if v0 > 0 else -1.0
        if not self.closed_form:
            return noise_free.stick_time(self, v0)
        b = (self.delta - s * self.a) * self.tau_m  # relaxation offset on v0's half line
        if b <= 0:
            return math.inf
        return self.tau_m * math.log1p(abs(v0) / b)

    def deterministic(self, v0: float, t: ArrayLike) -> np.ndarray:
        """Noise-free solution of eq. (13) from ``v(0) = v0`` at times ``t >= 0``.

        On each half line the motion is the basic solution
        ``v(t) = (v0 + (Delta - a) tau_m) e^{-t/tau_m} - (Delta - a) tau_m`` (v > 0) and its
        mirror; v = 0 is reached in the finite time ``t_a`` (eq. (31)) when |a| < Delta and
        the object then sticks; for |a| > Delta it crosses v = 0 with a kink and relaxes to
        ``v_ss`` (eq. (14)).  With epsilon > 0 the smooth ODE is integrated numerically, and
        so is every extension (from ``x(0) = x0`` with a spring; velocity returned).
        """
        v0 = checks.finite("v0", v0)
        t = np.asarray(t, dtype=float)
        if np.any(t < 0) or not np.all(np.isfinite(t)):
            raise ValueError("t must be finite and >= 0")
        if not self.closed_form:
            return noise_free.flow(self, v0, self.x0, t)[0]
        if self.epsilon > 0:
            return self._deterministic_smooth(v0, t)
        if v0 < 0 or (v0 == 0 and self.a < 0):
            return -self.replace(a=-self.a)._deterministic_upper(-v0, t)
        return self._deterministic_upper(v0, t)

    def _deterministic_upper(self, v0: float, t: np.ndarray) -> np.ndarray:
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

    def _deterministic_smooth(self, v0: float, t: np.ndarray) -> np.ndarray:
        t_end = float(t.max()) if t.size else 0.0
        if t_end == 0:
            return np.full_like(t, v0)
        # Stiff near v = 0 when epsilon is small: use an implicit method with the exact Jacobian.
        def jac(s: float, v: np.ndarray) -> list[list[float]]:
            sech2 = 1.0 - np.tanh(v[0] / self.epsilon) ** 2  # no overflow, unlike 1/cosh^2
            return [[-1.0 / self.tau_m - self.delta / self.epsilon * sech2]]
        from scipy import integrate
        sol = integrate.solve_ivp(lambda s, v: self.drift(v), (0.0, t_end), [v0], method="Radau",
                                  jac=jac, dense_output=True, rtol=1e-10, atol=1e-12 * max(1.0, abs(v0)))
        return sol.sol(t.ravel())[0].reshape(t.shape)
