"""Coloured noise: an Ornstein-Uhlenbeck force of correlation time ``tau_c`` (issue 20's
demonstration of a new member: this module plus its line in
:data:`analogue.variants.NOISE_KINDS`).

Model (reduced units, as :mod:`analogue.model`)::

    dv   = (-v/tau_m - Delta(v) sgn v [- cubic v^3 - spring x] + a + eta) dt,
    deta = -eta/tau_c dt + (sqrt(2/gamma)/tau_c) dW,          eta(0) = 0,

so ``eta`` is white noise of intensity ``1/gamma`` passed through a first-order low-pass of
time constant ``tau_c``: its stationary variance is ``1/(gamma tau_c)``, its correlation
``<eta(t) eta(t')> = exp(-|t - t'|/tau_c)/(gamma tau_c)``, and as ``tau_c -> 0`` it tends to
the paper's white noise (``<xi xi'> = (2/gamma) delta``).  ``Model(tau_m, delta, a, gamma,
noise=OrnsteinUhlenbeck(tau_c))``; gamma keeps its meaning (the white noise's intensity at
the filter's input).  Not a gradient system: no ``exp(-gamma U)``; exact theory may follow.

Closed form at ``Delta = 0`` (linear 2-D OU; alpha = 1/tau_m, beta = 1/tau_c, k^2 = 2/(gamma
tau_c^2)): ``v`` responds to ``dW`` with the kernel ``g(s) = (e^{-beta s} - e^{-alpha s})/(alpha
- beta)``, so ``Var v = k^2 int_0^inf g^2 = k^2/(2 alpha beta (alpha + beta))``, i.e.

    Var v = tau_m^2 / (gamma (tau_m + tau_c))          (:func:`stationary_velocity_variance`),

which is ``tau_m/gamma`` (the white-noise value, eq. (6) at Delta = 0) at ``tau_c = 0``.

Monte Carlo (:meth:`OrnsteinUhlenbeck.stepped`): the linear part (v, eta) is integrated
exactly over each step with the friction (and cubic, spring) force held at its start value,
as the white-noise exponential scheme does: ``eta' = e^{-dt/tau_c} eta + L11 xi_1``,
``v' = r v + tau_m (1 - r) force + g(dt) eta + L21 xi_1 + L22 xi_2`` with ``L`` the Cholesky
factor of the exact covariance of the step's noise (Gauss-Legendre on ``[0, dt]`` of the
smooth kernels ``g = s e^{-alpha s} phi((alpha - beta) s)``, ``phi(x) = expm1(x)/x``, which has
no cancellation when tau_c is near tau_m).  At Delta = 0 it is exact (no time-step error); the
test compares it with the closed form within standard errors.  Two standard normals per
replica and step from the seeded stream.  Given noise (``noise=``, ``noise_hold=``: the filter's
white input held over a step or a hold, as the circuit holds it) is integrated exactly with the
input held (:meth:`OrnsteinUhlenbeck._held_input`): the report's held-noise pair (bandwidth).

Circuit (:meth:`OrnsteinUhlenbeck.replica_elements`): the white source of the Gaussian member
(``trrandom`` on node ``nz``, model units) feeds an RC low-pass ``R_ou`` (nz -> ou), ``C_ou``
(ou -> ground) with ``R_ou C_ou = tau_c`` in circuit time, and the noise current into the
velocity node is ``noise_gain V(ou)`` instead of ``noise_gain V(nz)``; ``ou`` starts at 0
(``uic``), as ``eta`` does.  The noise hold must be short against ``tau_c``: the held noise
lowers the filtered variance by about ``noise_dt/(3 tau_c)`` to first order (as it lowers an
OU velocity's by ``noise_dt/(3 tau_m)``, analogue.circuit.mapping), so decks with
``noise_dt > tau_c/10`` are refused naming noise_dt.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from .. import checks
from .noise import HELD_GAUSSIAN, Noise
from .words import Phrase, num

__all__ = ["OrnsteinUhlenbeck", "stationary_velocity_variance"]

_GL_X, _GL_W = np.polynomial.legendre.leggauss(32)
_MAX_HOLD = 0.1  # largest circuit noise hold, as a fraction of tau_c


def stationary_velocity_variance(tau_m: float, gamma: float, tau_c: float) -> float:
    """``Var v = tau_m^2/(gamma (tau_m + tau_c))``: the linear model (Delta = 0, no cubic, no
    spring) driven by the OU force (module docstring)."""
    return tau_m * tau_m / (gamma * (tau_m + tau_c))


def _kernel(s: np.ndarray, alpha: float, beta: float) -> np.ndarray:
    """``g(s) = (e^{-beta s} - e^{-alpha s})/(alpha - beta)`` without cancellation."""
    x = (alpha - beta) * s
    with np.errstate(invalid="ignore", divide="ignore"):
        phi = np.where(x == 0, 1.0, np.expm1(x) / np.where(x == 0, 1.0, x))
    return s * np.exp(-alpha * s) * phi


@dataclass(frozen=True)
class OrnsteinUhlenbeck(Noise):
    """Coloured noise: the white noise of intensity ``1/gamma`` low-pass filtered with time
    constant ``tau_c`` (> 0).  Give ``OrnsteinUhlenbeck(tau_c)`` to ``Model(noise=...)``;
    the model binds its ``gamma``."""

    tau_c: float
    gamma: float = math.inf
    kind: ClassVar[str | None] = "ornstein-uhlenbeck"
    exact_solver: ClassVar[str | None] = None  # exact theory may follow (issue 20)

    def __post_init__(self) -> None:
        tau_c = checks.positive("noise.tau_c", self.tau_c)
        if tau_c > 1e30 or tau_c < 1e-30:
            raise ValueError(f"noise.tau_c must be within [1e-30, 1e30], got {tau_c!r}")
        object.__setattr__(self, "tau_c", tau_c)

    def bind(self, gamma: float, shot: Any) -> Noise:
        if shot is not None:
            raise ValueError("noise=OrnsteinUhlenbeck(...) takes shot=None (one noise kind "
                             f"per model), got shot={shot!r}")
        if not math.isfinite(gamma):
            raise ValueError("noise=OrnsteinUhlenbeck(...) needs a finite gamma (the intensity "
                             f"1/gamma of the white noise it filters), got gamma={gamma!r}")
        return OrnsteinUhlenbeck(self.tau_c, gamma)

    @property
    def force_variance(self) -> float:
        """Stationary ``Var eta = 1/(gamma tau_c)``."""
        return 1.0 / (self.gamma * self.tau_c)

    def closed_form_variance(self, model: Any) -> float | None:
        """:func:`stationary_velocity_variance` where the model is linear (Delta = 0, no cubic,
        Stribeck or spring term), else None."""
        linear = (model.delta == 0 and model.cubic == 0 and model.stribeck is None
                  and model.dimension == 1)
        return stationary_velocity_variance(model.tau_m, self.gamma, self.tau_c) if linear else None

    def start_model(self, model: Any) -> Any:
        """The white-noise model of the same gamma (no exact stationary law here): the start
        states of a stationary run, which circuit and Monte Carlo reference share and the
        burn-in forgets (analogue.study.members)."""
        return model.replace(noise=None)

    def dt_limit(self, dt: float) -> float:
        # resolve the correlation time (the force is held over a step)
        return min(dt, self.tau_c / 50.0)

    def entries(self) -> dict[str, Any]:
        return {"noise": {"kind": self.kind, "tau_c": self.tau_c}}

    def mc_meta(self, n_kicks: int, scheme: str) -> dict[str, Any]:
        return {"noise_scheme": "exact 2-D OU step, friction held; eta(0) = 0"}

    # ------------------------------------------------------------ Monte Carlo
    def step_coefficients(self, tau_m: float, dt: float) -> dict[str, float]:
        """``r, push, rc, couple, l11, l21, l22`` of the exact step (module docstring)."""
        alpha, beta = 1.0 / tau_m, 1.0 / self.tau_c
        k2 = 2.0 / (self.gamma * self.tau_c**2)
        s = 0.5 * dt * (_GL_X + 1.0)
        w = 0.5 * dt * _GL_W
        g = _kernel(s, alpha, beta)
        h = np.exp(-beta * s)
        var_v = k2 * float(np.sum(w * g * g))
        cov = k2 * float(np.sum(w * g * h))
        var_e = k2 * -math.expm1(-2.0 * beta * dt) / (2.0 * beta)
        l11 = math.sqrt(var_e)
        l21 = cov / l11
        r = math.exp(-dt / tau_m)
        return {"r": r, "push": tau_m * (1.0 - r), "rc": math.exp(-dt / self.tau_c),
                "couple": float(_kernel(np.array(dt), alpha, beta)), "l11": l11, "l21": l21,
                "l22": math.sqrt(max(var_v - l21 * l21, 0.0))}

    def stepped(self, model: Any, v: np.ndarray, n_steps: int, per: int, dt: float,
                scheme: str, parts: Any, noise_rng: Any, kick_rng: Any,
                default: Callable[..., tuple[np.ndarray, np.ndarray, int]]
                ) -> tuple[np.ndarray, np.ndarray, int]:
        c = self.step_coefficients(model.tau_m, dt)
        if parts is not None:
            drive = self._held_input(c, dt, parts)
        else:
            rows = v.size

            def drive(k: int, v_det: np.ndarray, eta: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray]:
                # the exact 2-D OU step: (v, eta) increments drawn jointly (l11, l21, l22)
                xi = noise_rng.standard_normal((2, rows))
                return (v_det + c["l21"] * xi[0] + c["l22"] * xi[1],
                        c["rc"] * eta + c["l11"] * xi[0])
        return self._integrate(model, v, n_steps, per, dt, c, drive)

    def _held_input(self, c: dict[str, float], dt: float, parts: Any
                    ) -> Callable[[int, np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
        """Given noise (``simulate_sde(noise=..., noise_hold=...)``): the filter's white input
        held constant over each step (and over ``noise_hold`` steps), as the circuit's
        ``trrandom`` holds it over ``noise_dt``: ``u = sqrt(2/(gamma dt)) z`` (so that ``u dt``
        is the Wiener increment ``sqrt(2 dt/gamma) z``).  With ``u`` and the friction held, the
        step is exact: ``eta' = rc eta + (1 - rc) u``, ``v' = r v + push force + couple eta +
        (push - couple) u`` (``push - couple = int_0^dt e^{-alpha(dt-s)} (1 - e^{-beta s}) ds``).
        Held over one step this is the OU force up to a relative ``Var v`` error of about
        ``dt^2/(12 tau_m tau_c)`` (the held input's spectrum ``sinc^2(omega dt/2)`` through the
        two low-passes); the report's bandwidth term pairs it with a hold of ``noise_dt``."""
        ((noise, hold),) = parts
        held = c["push"] - c["couple"]
        amp = math.sqrt(2.0 / (self.gamma * dt))

        def drive(k: int, v_det: np.ndarray, eta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            u = amp * noise[:, k // hold]
            return v_det + held * u, c["rc"] * eta + (1.0 - c["rc"]) * u
        return drive

    @staticmethod
    def _integrate(model: Any, v: np.ndarray, n_steps: int, per: int, dt: float,
                   c: dict[str, float],
                   drive: Callable[[int, np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]
                   ) -> tuple[np.ndarray, np.ndarray, int]:
        """The step loop both inputs share: the friction (and spring) held over a step, the
        deterministic part ``r v + push force + couple eta`` and the input's part from
        ``drive(k, v_det, eta) -> (v', eta')``; x by the trapezium rule; every ``per``-th
        step recorded."""
        rows = v.size
        n_out = n_steps // per + 1
        v_out = np.empty((rows, n_out))
        x_out = np.empty((rows, n_out))
        v = v.copy()
        v_out[:, 0], x_out[:, 0] = v, 0.0
        x = np.zeros(rows)
        eta = np.zeros(rows)
        law, restoring = model.friction, model.restoring
        for k in range(n_steps):
            force = model.a - law.dry(v)
            force = restoring.add_force(law.add_drift(force, v), model.x0 + x)
            v_new, eta = drive(k, c["r"] * v + c["push"] * force + c["couple"] * eta, eta)
            x += 0.5 * dt * (v + v_new)
            v = v_new
            if (k + 1) % per == 0:
                v_out[:, (k + 1) // per] = v
                x_out[:, (k + 1) // per] = x
        return v_out, x_out, 0

    # --------------------------------------------------------------- circuit
    def replica_elements(self, sub: Any, mapping: Any, value: Callable[[str, float], str]) -> None:
        if not mapping.gaussian_noise:  # a noise-free copy of the mapping
            return
        if mapping.noise_dt > _MAX_HOLD * self.tau_c:
            raise ValueError(f"noise_dt={mapping.noise_dt!r} must be <= {_MAX_HOLD} tau_c = "
                             f"{_MAX_HOLD * self.tau_c!r} for the coloured noise (its held input "
                             f"lowers the filtered variance by ~noise_dt/(3 tau_c)); set the "
                             f"circuit's noise_dt")
        cap = mapping.capacitance
        res = self.tau_c * mapping.theta / cap
        sub.V("noise", "nz", sub.gnd,
              f"dc 0 trrandom(2 {value('noise_ts', mapping.noise_ts)} 0 "
              f"{value('noise_stddev', mapping.noise_stddev)} 0)")
        sub.R("ou", "nz", "ou", value("R_ou", res))
        sub.C("ou", "ou", sub.gnd, value("C_ou", cap))
        sub.VCCS("noise", sub.gnd, "v", "ou", sub.gnd, value("noise_gain", mapping.noise_gain))

    def describe(self) -> list[str]:
        return [f"gamma = {num(self.gamma)}, tau_c = {num(self.tau_c)} (coloured noise: white "
                f"noise of intensity 1/gamma = {num(1 / self.gamma)} through a low-pass of "
                "correlation time tau_c, an Ornstein-Uhlenbeck force)"]

    def stated_values(self) -> dict[str, float]:
        return {"tau_c": self.tau_c}

    def page_phrases(self) -> list[Phrase]:
        # its held source covers the white one's wording on a page that has both
        return [Phrase(6, "+ eta (coloured: d eta = -eta dt/tau_c + sqrt(2/gamma) dW/tau_c)"),
                Phrase(15, HELD_GAUSSIAN + ", for coloured noise through an RC low-pass "
                           "R_ou C_ou = tau_c", covers=1)]

    def reference_phrases(self) -> list[Phrase]:
        return [Phrase(23, "the Monte Carlo for coloured noise (no exact theory yet)")]

    def member_kind(self, friction: Any) -> str:
        return "coloured"   # the noise without exact theory: the Monte Carlo is the reference
