"""Drift and diffusion of the object under a bias: mobility, D_x and their ratio (issue 23
item 3).  Exact at every parameter from the project's stationary numerics, and closed forms
for pure dry friction.

Notation: ``D = 1/gamma`` is the velocity-noise intensity (``dv = -U' dt + sqrt(2 D) dW``,
:attr:`analogue.Model.noise_intensity`); ``<v>`` the drift (mean sliding velocity), ``D_x``
the Green-Kubo diffusion coefficient of the position (``Var x(t) ~ 2 D_x t``), both from
:func:`analogue.theory.exact.stationary_moments`.

**Mobility is a variance.**  For every gradient member (Gaussian noise only) the force enters
the stationary law ``p_s ~ exp(-gamma U_0(v) + gamma a v)`` as an exponential tilt, so

    mu(a) = d<v>/da = gamma Var(v)       (exactly, at every a, tau_m, Delta, gamma):

the differential mobility is the static response of the tilted law (:func:`mobility`).

**Pure dry friction** (``tau_m -> inf``, ``|a| < Delta``).  ``U = Delta |v| - a v``, so
``p_s`` is a two-sided exponential with decay lengths ``x_+ = D/(Delta - a)`` (v > 0) and
``x_- = D/(Delta + a)`` (v < 0), ``Z = x_+ + x_-``:

    <v>    = x_+ - x_- = 2 a D / (Delta^2 - a^2)
    <v^2>  = 2 (x_+^2 - x_+ x_- + x_-^2),        Var v = x_+^2 + x_-^2
    mu     = gamma Var v = 2 D (Delta^2 + a^2) / (Delta^2 - a^2)^2      (-> 2 D/Delta^2, a -> 0)
    D_x    = gamma int G^2/p_s dv,  G(v) = int_{-inf}^v (u - <v>) p_s(u) du
           = [x_-^3 (2 x_-^2 + 2 x_+ x_- + x_+^2) + x_+^3 (2 x_+^2 + 2 x_+ x_- + x_-^2)] / (D Z)

(on v < 0, ``G = (x_-/Z) e^{v/x_-} (v - x_+)``; on v > 0, ``G = -(x_+/Z) e^{-v/x_+}
(v + x_-)``; each half line is then ``int_0^inf e^{-w/x} (w + c)^2 dw = 2x^3 + 2 c x^2 +
c^2 x``).  At a = 0: ``D_x = 5 D^3/Delta^4``, ``Var v = 2 D^2/Delta^2``.

**Einstein-like ratio.**  In equilibrium (Delta = 0, an Ornstein-Uhlenbeck velocity)
``D_x = tau_m^2 D`` and ``mu = tau_m``, so ``D_x/mu = tau_m D = Var v`` (Einstein's relation
``D_x = mu k T/m`` with ``k T/m = <v^2>``).  In general ``D_x/mu = D tau_c`` with the
integrated correlation time ``tau_c = D_x/Var v``.  Pure dry friction at ``a -> 0``:

    D_x/mu = 5 D^2 / (2 Delta^2) = (5/4) Var v,

i.e. dry friction breaks the Einstein relation by the factor 5/4 (the correlation time
``5 D/(2 Delta^2)`` is 5/4 of ``Var v/D``); at finite a the factor is
:attr:`DryFrictionTransport.einstein_factor`.  Scaling with the noise: at fixed ``a, Delta``
every length ``x_+-`` is proportional to D, so ``D_x ~ D^3`` (local exponent 3) for dry
friction and ``D_x ~ D`` (exponent 1) for viscous friction; the exact model crosses over
from 3 (weak noise: dry friction dominates, ``D tau_m << Delta^2 tau_m^2``) to 1
(:func:`diffusion_exponent`).

Accuracy (tests/unit/test_theory_bias_transport.py; measured at Delta = 1, D = 0.1,
a = 0, 0.3, -0.6): the exact numerics at finite tau_m approach the closed forms as
``-c D/((Delta - |a|)^2 tau_m)`` with c = 2.4 - 5.3 for <v> and Var v (exactly 5 for Var v at
a = 0) and 12 - 13.8 for D_x; extrapolated in 1/tau_m from tau_m = 2e3, 4e3 they agree to
<= 9e-6.  The exact ``d<v>/da`` by central differences equals ``gamma Var v`` to 5e-9 (sgn,
Stribeck).  The local exponent at tau_m = 1, Delta = 1, a = 0.3 is 1.62, 2.24, 2.81, 2.98 at
gamma = 1, 10, 100, 1000 (Goohpattader, Mettu & Chaudhury, Langmuir 2009, measured 1.61).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from .. import checks
from ..model import Model
from .exact import stationary_moments as _moments

__all__ = ["DryFrictionTransport", "pure_dry_friction", "mobility", "einstein_ratio",
           "diffusion_exponent"]


@dataclass(frozen=True)
class DryFrictionTransport:
    """Closed-form stationary transport of pure dry friction (``tau_m -> inf``, module
    docstring).  ``einstein_ratio = diffusion/mobility``; ``einstein_factor =
    einstein_ratio/variance`` (1 for an equilibrium Ornstein-Uhlenbeck velocity, 5/4 here at
    a = 0); ``correlation_time = diffusion/variance``."""

    mean: float
    second_moment: float
    variance: float
    mobility: float
    diffusion: float
    einstein_ratio: float
    einstein_factor: float
    correlation_time: float

    def as_dict(self) -> dict[str, float]:
        return asdict(self)


def pure_dry_friction(delta: float, a: float, gamma: float) -> DryFrictionTransport:
    """Closed forms for ``dv = (a - Delta sgn v) dt + sqrt(2/gamma) dW`` (module docstring);
    needs ``|a| < Delta`` (else there is no stationary law without viscous friction)."""
    d = checks.positive("delta", delta)
    f = checks.finite("a", a)
    g = checks.positive("gamma", gamma)
    if not abs(f) < d:
        raise ValueError(f"pure dry friction has a stationary law only for |a| < delta, got "
                         f"a={f!r}, delta={d!r}")
    noise = 1.0 / g
    xp, xm = noise / (d - f), noise / (d + f)
    z = xp + xm
    mean = xp - xm
    second = 2.0 * (xp * xp - xp * xm + xm * xm)
    var = xp * xp + xm * xm
    mob = g * var
    dx = (xm**3 * (2 * xm * xm + 2 * xp * xm + xp * xp)
          + xp**3 * (2 * xp * xp + 2 * xp * xm + xm * xm)) / (noise * z)
    return DryFrictionTransport(mean=mean, second_moment=second, variance=var, mobility=mob,
                                diffusion=dx, einstein_ratio=dx / mob,
                                einstein_factor=dx / (mob * var), correlation_time=dx / var)


def _gradient(model: Model) -> Model:
    checks.instance("model", model, Model, description="an analogue.Model")
    if not model.is_gradient:
        raise ValueError("mobility = gamma Var v holds for the 1-D Gaussian-noise members only "
                         "(spring = 0, shot = None, finite gamma)")
    return model


def mobility(model: Model) -> float:
    """Exact differential mobility ``d<v>/da = gamma Var v`` (module docstring)."""
    m = _gradient(model)
    return m.gamma * float(_moments(m).variance)


def einstein_ratio(model: Model, h: float | None = None) -> float:
    """Exact ``D_x / mu`` (``mu = d<v>/da``); equals ``Var v`` in equilibrium (Delta = 0)."""
    m = _gradient(model)
    mom = _moments(m, h=h)
    return float(mom.diffusion) / (m.gamma * float(mom.variance))


def diffusion_exponent(model: Model, rel_step: float = 0.05, h: float | None = None) -> float:
    """Local exponent ``d ln D_x / d ln D`` (``D = 1/gamma``) of the exact D_x at this model,
    by a central difference in ``ln gamma`` with steps ``+-rel_step`` (error O(rel_step^2)):
    1 for viscous friction, 3 for pure dry friction (module docstring)."""
    m = _gradient(model)
    step = checks.in_range("rel_step", rel_step, 0.0, 0.5, closed=False)
    up = _moments(m.replace(gamma=m.gamma * math.exp(step)), h=h).diffusion
    down = _moments(m.replace(gamma=m.gamma * math.exp(-step)), h=h).diffusion
    return -(math.log(up) - math.log(down)) / (2.0 * step)
