"""Nonlinear dynamic-friction elements: the cubic viscous law and the Stribeck law.

Circuit convention (force-current analogy, :mod:`analogue.circuit.mapping`): a friction
acceleration ``f(v)`` is the current ``I = (C kappa/theta) f(V/kappa)`` drawn from the velocity
node ``V = kappa v`` to ground.

Cubic viscous law ``cubic v^3`` (issue 9): the conductance ``I = g3 V^3`` with
``g3 = cubic C/(theta kappa^2)``.  Two realisations:

- ``behavioural``: a B-source ``I = g3 V^3`` (exact up to the simulator's tolerances).
- ``diode-network``: a diode-resistor breakpoint network, the way analogue computers shaped
  nonlinearities (e.g. Korn & Korn, *Electronic Analog and Hybrid Computers*, ch. 6).  Per
  polarity, K branches ``node -- R_k -- diode -- E_k -- ground``; branch k conducts once
  ``|V|`` exceeds its bias ``E_k`` plus the diode's forward drop, adding the conductance
  ``1/(R_k + RS)``, so the network is an odd, convex, piecewise-linear law with rounded corners
  (the diodes' exponential knees).  Branch law (exact for the Shockley diode, solved with the
  Wright omega function): ``V - E_k = (R_k + RS) i + N V_T ln(1 + i/IS)``.  The values
  ``(R_k, E_k)`` are fitted (least squares, diode law included) to ``g3 V^3`` over the
  stationary swing ``|V| <= V_max``, the resistors then rounded to E96 values and the biases
  refitted and set to 0.1 mV; the remaining error is reported in the mapping's budget
  (``cubic_force``: max |I - g3 V^3| over the swing relative to ``g3 V_max^3``;
  ``cubic_variance``: relative change of the stationary velocity variance under
  ``p_s ~ exp(-gamma U)`` with the network's law in U, when that law applies).  The vendor
  models' GOhm parallel resistors are left out (reverse leakage ~1e-9 A against mA branch
  currents).  Beyond ``V_max`` the network grows linearly, not cubically; the swing is where
  the stationary density has fallen to 1e-14 of its peak.

Stribeck law ``Delta(v) sgn v``, ``Delta(v) = Delta + (delta_s - Delta) exp(-|v|/v_s)``:

- ``behavioural``: a B-source ``I = I_unit Delta(V) tanh(V/eps_V)`` (``sgn`` for the
  ``behavioural-sgn`` element).
- ``diode-bridge``: the four-diode bridge of the Coulomb element (its ``tanh`` is the real
  diodes') around a *controlled* current source ``I_unit Delta(V_terminal) - 2 IS``: the
  bridge gives ``I0(V) tanh(V/(2 N V_T))`` for any source value, so the law is exact in the
  same sense as for constant Delta.  The controlled source is behavioural.

Is a real-part realisation of the Stribeck law reasonable?  Only partly.  The sign part is
the diode bridge (real).  The velocity-weakening amplitude needs a current source whose value
falls as ``exp(-|V|/V_s)``: a precision full-wave rectifier (two op-amps) feeding an
exponential (antilog) BJT stage, ``I_C = I_S exp(V_BE/V_T)``, with an attenuator setting
``V_s``.  This is standard analogue-computer practice but (i) the exponential's scale is the
transistor's V_T, which drifts by 0.33 %/K, so v_s drifts with temperature unless the stage is
compensated (thermistor or matched pair in a log-ratio circuit), (ii) the op-amps' offsets
(~1 mV) shift the weakening curve by an amount comparable to ``eps_V`` at the kink, and
(iii) it adds four active parts per replica.  We therefore provide the behavioural source for
the weakening amplitude (and the real bridge for the sign), and no full real-part circuit.
A tunnel diode has a region of negative differential conductance, but its I-V curve
(peak-valley-rise) cannot be shaped to an exponential decay, so it is no substitute.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy import optimize, special

from .parts import DiodePart, thermal_voltage

__all__ = [
    "DiodeNetwork",
    "branch_current",
    "cubic_budget",
    "design_cubic_network",
    "e96",
    "network_current",
]


@dataclass(frozen=True)
class DiodeNetwork:
    """One polarity of the odd breakpoint network: branch resistors ``resistors`` (ohm, the
    physical resistor, excluding the diode's RS) and bias sources ``biases`` (V, >= the
    conduction threshold side), all for ``V > 0``; the negative side is the mirror image.

    ``part``: the diodes; ``g3``: the target ``I = g3 V^3``; ``v_max``: the fitted swing;
    ``max_error``: max |I - g3 V^3| / (g3 v_max^3) over ``|V| <= v_max``.
    """

    part: DiodePart
    g3: float
    v_max: float
    resistors: tuple
    biases: tuple
    max_error: float

    @property
    def branches(self) -> int:
        return len(self.resistors)

    def current(self, volts):
        """Terminal current of the whole (two-polarity) network at voltage ``volts``."""
        return network_current(self.part, self.resistors, self.biases, volts)

    def max_branch_current(self, volts: float) -> float:
        """Largest branch current (A) at |V| = volts: the first branch carries the most."""
        return float(max(branch_current(self.part, r, e, volts)
                         for r, e in zip(self.resistors, self.biases)))


def branch_current(part: DiodePart, resistor: float, bias: float, volts):
    """Current of one branch ``R -- diode -- E`` at terminal voltage ``V`` (forward for V > E).

    ``V - E = R_t i + N V_T ln(1 + i/IS)`` with ``R_t = R + RS``; with ``y = i + IS``:
    ``y = (N V_T/R_t) omega(ln(R_t IS/(N V_T)) + (V - E + R_t IS)/(N V_T))`` where omega is
    the Wright omega function (``W(e^z)``, no overflow for large arguments)."""
    v = np.asarray(volts, dtype=float)
    nvt = part.N * thermal_voltage()
    rt = resistor + part.RS
    z = math.log(rt * part.IS / nvt) + (v - bias + rt * part.IS) / nvt
    y = nvt / rt * np.real(special.wrightomega(z))
    return y - part.IS


def network_current(part: DiodePart, resistors, biases, volts):
    """Odd network: positive branches conduct for V > E_k, mirrored ones for V < -E_k."""
    v = np.asarray(volts, dtype=float)
    out = np.zeros_like(v)
    for r, e in zip(resistors, biases):
        out = out + branch_current(part, r, e, v) - branch_current(part, r, e, -v)
    return out


def e96(values):
    """Nearest values of the E96 (1 %) resistor series: ``round(10^(i/96), 2)`` per decade
    (this formula reproduces every E96 value)."""
    values = np.asarray(values, dtype=float)
    dec = np.floor(np.log10(values))
    mant = values / 10.0**dec
    grid = np.round(10.0 ** (np.arange(97) / 96.0), 2)
    pick = grid[np.argmin(np.abs(np.log(mant[..., None] / grid)), axis=-1)]
    return pick * 10.0**dec


def _forward_drop(part: DiodePart, current: float) -> float:
    return part.N * thermal_voltage() * math.log1p(current / part.IS) + part.RS * current


@functools.lru_cache(maxsize=64)
def design_cubic_network(part: DiodePart, g3: float, v_max: float, branches: int) -> DiodeNetwork:
    """Fit ``branches`` diode branches per polarity to ``I = g3 V^3`` on ``|V| <= v_max``.

    Start: the piecewise-linear interpolant of V^3 at nodes ``s_j = v_max (j/K)^(2/3)`` (nodes
    denser where the curvature 6 V is small, which equidistributes the interpolation error
    ``h^2 max|f''|/8``); branch k adds the slope increment at node ``s_(k-1)``, its bias is the
    node minus the diode's forward drop at a representative branch current.  Then a
    least-squares polish of ``(ln R_k, E_k)`` on the full diode law, with residuals relative to
    ``g3 v_max^3``.
    """
    if not (g3 > 0 and v_max > 0 and branches >= 1):
        raise ValueError("design_cubic_network needs g3 > 0, v_max > 0 and branches >= 1")
    k = int(branches)
    s = v_max * (np.arange(k + 1) / k) ** (2.0 / 3.0)
    slopes = g3 * (s[1:] ** 2 + s[1:] * s[:-1] + s[:-1] ** 2)
    dg = np.diff(np.concatenate([[0.0], slopes]))
    r0 = 1.0 / dg
    i_ref = g3 * v_max**3 / (4.0 * k)
    e0 = s[:-1] - _forward_drop(part, i_ref)
    grid = np.linspace(0.0, v_max, 161)
    target = g3 * grid**3
    scale = g3 * v_max**3

    def resid(p):
        r = np.exp(p[:k])
        e = p[k:]
        i = sum(branch_current(part, r[j], e[j], grid) for j in range(k))
        # (the mirrored branches carry ~IS at V >= 0: negligible, included in .current)
        return (i - target) / scale

    sol = optimize.least_squares(resid, np.concatenate([np.log(r0), e0]), method="lm",
                                 xtol=1e-12, ftol=1e-12, max_nfev=4000)
    # Real parts: resistors from the E96 (1 %) series, then the biases (trimmed voltages, as
    # on an analogue computer's potentiometers) refitted for those resistors and set to
    # 0.1 mV.  This also keeps the deck text independent of the last bits of the optimiser.
    r = e96(np.exp(sol.x[:k]))
    log_r = np.log(r)
    sol = optimize.least_squares(lambda e: resid(np.concatenate([log_r, e])), sol.x[k:],
                                 method="lm", xtol=1e-12, ftol=1e-12, max_nfev=4000)
    e = np.round(sol.x, 4)
    order = np.argsort(e)
    r, e = r[order], e[order]
    fine = np.linspace(-v_max, v_max, 2001)
    err = float(np.max(np.abs(network_current(part, r, e, fine) - g3 * fine**3)) / scale)
    return DiodeNetwork(part=part, g3=float(g3), v_max=float(v_max),
                        resistors=tuple(float(x) for x in r), biases=tuple(float(x) for x in e),
                        max_error=err)


def cubic_budget(network: DiodeNetwork, kappa: float, i_unit: float, potential_rest, gamma: float,
                 v_range: tuple) -> float | None:
    """Relative change of the stationary velocity variance when the cubic term of U is
    replaced by the network's law (p_s ~ exp(-gamma U), exact for the 1-D Gaussian members).

    ``potential_rest(v)``: U without its cubic term (model units); the cubic term's potential
    is ``integral_0^v f`` with ``f = I(kappa v)/i_unit`` (network) or ``cubic v^3``; computed on
    a grid over ``v_range``.  None when gamma is infinite (no Gaussian stationary law)."""
    if not math.isfinite(gamma):
        return None
    lo, hi = v_range
    v = np.linspace(lo, hi, 8001)
    v = np.unique(np.concatenate([v, [0.0]]))
    base = np.asarray(potential_rest(v), dtype=float)
    f_net = network.current(kappa * v) / i_unit
    f_cub = network.g3 * (kappa * v) ** 3 / i_unit
    out = []
    for f in (f_net, f_cub):
        # potential of the force, zero at v = 0
        u = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(v))])
        u -= u[np.searchsorted(v, 0.0)]
        w = base + u
        p = np.exp(-gamma * (w - w.min()))
        z = np.trapezoid(p, v)
        m = np.trapezoid(v * p, v) / z
        out.append(np.trapezoid((v - m) ** 2 * p, v) / z)
    return float(out[0] / out[1] - 1.0)
