"""Diode parts for the Coulomb-friction bridge, with their published SPICE models.

Sources of the real models (the manufacturers' published PSPICE models, Nexperia/NXP style:
a ``.subckt`` of one ``D`` element plus a parallel resistor ``R1`` which "does not reflect a
physical device" but improves the reverse characteristic; we keep it as ``rp``):

- 1N4148 (Nexperia "High-speed diodes", IFmax = 200 mA, VRmax = 100 V):
  IS=4.352E-9 N=1.906 BV=110 IBV=0.0001 RS=0.6458 CJO=7.048E-13 VJ=0.869 M=0.03 FC=0.5
  TT=3.48E-9, R1 = 5.827E+9 ohm.
- BAT54 (NXP/Nexperia Schottky barrier diode, IF = 200 mA, VR = 30 V):
  IS=2.117E-07 N=1.016 BV=36 IBV=1.196E-06 RS=2.637 CJO=1.114E-11 VJ=0.2013 M=0.3868 FC=0
  TT=0 EG=0.69 XTI=2, R1 = 3.6E+07 ohm.

What the non-ideal parameters do to the friction law of a bridge around a current source
``I0`` (derivation in :func:`bridge_voltage`):

- ``IS`` (reverse current): the Shockley bridge gives exactly ``(I0 + 2 IS) tanh(V/(2 N V_T))``,
  so the friction amplitude is ``I0 + 2 IS`` (compensated in the mapping).
- ``RS`` (series resistance): ``V = 2 N V_T atanh(I/(I0 + 2 IS)) + RS I``: the law is a tanh
  seen through a series resistor; its slope at 0 is that of a tanh of width
  ``2 N V_T + RS (I0 + 2 IS)`` (the mapping reports this as the smoothing width) and it
  reaches saturation more slowly.
- ``rp`` (the models' parallel resistor) and GMIN: once one diode pair is reverse biased the
  terminal sees about ``rp/2`` in parallel, i.e. extra viscous friction (compensated in ``R``).
- ``CJO``: junction capacitance of order ``CJO`` adds to the mass capacitor (reported as a
  fraction of ``C``; negligible for C ~ 100 nF).
- ``BV``: beyond the rated reverse voltage the reverse-biased pair breaks down and the
  friction law is destroyed; mappings whose voltage swing reaches the rating are refused.

The bridge's exact DC law with every DC parameter (IS, N, RS and rp) is
:func:`bridge_dc_current`; it matches ngspice DC sweeps to 6e-10 (1N4148) and 2e-8 (BAT54) of
I0 (tests/integration/test_real_diode_element.py), and the report books exact numerics on it
minus those on the tanh as the budget's element term (:func:`analogue.study.budget.real_diode_element`).

Measured with ngspice 39 (DC sweeps over +-5 eps_V, stick experiment defaults: I0 ~ 1.1 mA for
the 1N4148, 0.6 mA for the BAT54): the ideal bridge equals ``I0 tanh(V/(2 N V_T))`` to 2e-9 of
I0; the vendor bridges follow the series-resistance law to 1e-7 (1N4148) and 1e-5 (BAT54, its
36 Mohm parallel resistors) of I0, and depart from the slope-matched tanh by at most 8e-4
(1N4148) and 3.3e-3 (BAT54) of I0.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import special

from .. import checks

__all__ = ["DiodePart", "PARTS", "IDEAL_IS", "ideal_diode", "get_part", "thermal_voltage",
           "bridge_current", "bridge_voltage", "element_current", "bridge_dc_current",
           "REFERENCE_TEMPERATURE"]

# ngspice's physical constants (src/include/ngspice/const.h, CODATA 2014) and its default
# circuit temperature of 27 C; V_T must match them for the bridge to follow tanh to 1e-6.
_BOLTZMANN = 1.38064852e-23
_CHARGE = 1.6021766208e-19
REFERENCE_TEMPERATURE = 300.15  # K (27 C)


def thermal_voltage(temperature: float = REFERENCE_TEMPERATURE) -> float:
    """``V_T = k T / q`` in volts, with the constants ngspice uses (25.86 mV at 27 C)."""
    return _BOLTZMANN * temperature / _CHARGE


@dataclass(frozen=True)
class DiodePart:
    """A diode's SPICE parameters and the ratings the mapping checks.

    ``model`` holds the ``.model`` parameters (upper-case SPICE names, SI units);
    ``rp`` is the vendor model's parallel resistor (None: none); ``max_forward_current``
    and ``max_reverse_voltage`` are the datasheet ratings (inf for the ideal diode).
    """

    name: str
    source: str
    model: tuple  # ((PARAM, value), ...): a tuple keeps the dataclass hashable and frozen
    rp: float | None
    max_forward_current: float
    max_reverse_voltage: float

    def param(self, key: str, default: float = 0.0) -> float:
        return dict(self.model).get(key, default)

    @property
    def IS(self) -> float:
        return self.param("IS", 1e-14)

    @property
    def N(self) -> float:
        return self.param("N", 1.0)

    @property
    def RS(self) -> float:
        return self.param("RS", 0.0)

    @property
    def CJO(self) -> float:
        return self.param("CJO", 0.0)

    @property
    def ideal(self) -> bool:
        return self.name == "ideal"

    def smoothing_volts(self, i0: float, temperature: float = REFERENCE_TEMPERATURE) -> float:
        """Width (volts) of the tanh with the bridge law's slope at V = 0:
        ``2 N V_T + RS (I0 + 2 IS)``."""
        return 2.0 * self.N * thermal_voltage(temperature) + self.RS * (i0 + 2.0 * self.IS)


PARTS: dict[str, DiodePart] = {
    "1N4148": DiodePart(
        name="1N4148",
        source="Nexperia 1N4148 PSPICE model (High-speed diodes; IFmax 200 mA, VRmax 100 V)",
        model=(("IS", 4.352e-9), ("N", 1.906), ("BV", 110.0), ("IBV", 1e-4), ("RS", 0.6458),
               ("CJO", 7.048e-13), ("VJ", 0.869), ("M", 0.03), ("FC", 0.5), ("TT", 3.48e-9)),
        rp=5.827e9, max_forward_current=0.2, max_reverse_voltage=100.0),
    "BAT54": DiodePart(
        name="BAT54",
        source="NXP/Nexperia BAT54 Schottky PSPICE model (IF 200 mA, VR 30 V)",
        model=(("IS", 2.117e-7), ("N", 1.016), ("BV", 36.0), ("IBV", 1.196e-6), ("RS", 2.637),
               ("CJO", 1.114e-11), ("VJ", 0.2013), ("M", 0.3868), ("FC", 0.0), ("TT", 0.0),
               ("EG", 0.69), ("XTI", 2.0)),
        rp=3.6e7, max_forward_current=0.2, max_reverse_voltage=30.0),
}

IDEAL_IS = 1e-14  # A: the ideal diode's default saturation current


def ideal_diode(emission: float, saturation_current: float = IDEAL_IS) -> DiodePart:
    """A Shockley diode with ``RS = 0``, ``CJO = 0``, no breakdown, emission coefficient
    ``N = emission`` (any N > 0: it only sets the tanh width ``2 N V_T``) and
    ``IS = saturation_current`` (any IS > 0: the bridge amplitude is ``I0 + 2 IS``)."""
    emission = checks.positive("emission coefficient N", emission)
    saturation_current = checks.positive("saturation_current IS", saturation_current)
    return DiodePart(name="ideal", source="ideal Shockley diode (RS=0, CJO=0, no breakdown)",
                     model=(("IS", float(saturation_current)), ("N", float(emission))), rp=None,
                     max_forward_current=math.inf, max_reverse_voltage=math.inf)


def get_part(name: str) -> DiodePart:
    """A real part from the built-in table (names are never passed through to decks)."""
    try:
        return PARTS[name]
    except (KeyError, TypeError):
        raise ValueError(f"diode must be one of {['ideal', *PARTS]}, got {name!r}") from None


def _amplitude(part: DiodePart, i0: float) -> float:
    """Friction amplitude ``I0 + 2 IS`` of a bridge; the Shockley law needs it > 0 (the diode
    currents ``(I0 +- I)/2`` must stay above ``-IS``)."""
    i0 = float(i0)
    amp = i0 + 2.0 * part.IS
    if not (math.isfinite(i0) and amp > 0):
        raise ValueError(f"i0 (bridge current source) must be finite and > -2 IS = {-2.0 * part.IS:.3g} A "
                         f"for {part.name}, got {i0!r}")
    return amp


def bridge_current(part: DiodePart, i0: float, volts, temperature: float = REFERENCE_TEMPERATURE):
    """Terminal current of the four-diode bridge around ``I0`` at terminal voltage ``V``.

    Symmetry gives diode currents ``i1 = i4 = (I0 + I)/2`` and ``i2 = i3 = (I0 - I)/2``, and
    ``V = v_d(i1) - v_d(i2)`` with ``v_d(i) = N V_T ln(1 + i/IS) + RS i``; for RS = 0 this is
    ``I = (I0 + 2 IS) tanh(V / (2 N V_T))`` (the paper's regularisation of sgn, eq. (5) with
    Delta|v| -> Delta eps ln cosh(v/eps)).  With RS > 0 it is solved by bisection.  The
    parallel resistor ``rp`` and GMIN are not included.
    """
    v = np.asarray(volts, dtype=float)
    amp = _amplitude(part, i0)
    width = 2.0 * part.N * thermal_voltage(temperature)
    if part.RS == 0:
        return amp * np.tanh(v / width)
    lo = -amp * np.ones_like(v)
    hi = amp * np.ones_like(v)
    for _ in range(200):  # vectorised bisection on the monotone V(I)
        mid = 0.5 * (lo + hi)
        below = bridge_voltage(part, i0, mid, temperature) < v
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    return 0.5 * (lo + hi)


def bridge_voltage(part: DiodePart, i0: float, current, temperature: float = REFERENCE_TEMPERATURE):
    """Inverse of :func:`bridge_current`: ``V = 2 N V_T atanh(I/(I0 + 2 IS)) + RS I``."""
    i = np.asarray(current, dtype=float)
    amp = _amplitude(part, i0)
    width = 2.0 * part.N * thermal_voltage(temperature)
    with np.errstate(divide="ignore"):  # |I| = amplitude maps to |V| = inf, as it should
        return width * np.arctanh(np.clip(i / amp, -1.0, 1.0)) + part.RS * i


def bridge_node_voltages(part: DiodePart, i0: float, volts, temperature: float = REFERENCE_TEMPERATURE):
    """Voltages ``(V_p, V_n)`` of the bridge's inner nodes at terminal voltage ``V`` (DC):
    ``V_p = V - v_d(i1)``, ``V_n = v_d(i1)`` with ``i1 = (I0 + I)/2`` (see
    :func:`bridge_current`).  Used as consistent ``.ic`` values for ``uic`` starts."""
    v = np.asarray(volts, dtype=float)
    # Work with |V| (where i1 >= I0/2 and the logarithm is well conditioned) and mirror:
    # the bridge maps V -> -V with p <-> -n.
    av = np.abs(v)
    i = bridge_current(part, i0, av, temperature)
    i1 = 0.5 * (i0 + i)
    vd = part.N * thermal_voltage(temperature) * np.log1p(i1 / part.IS) + part.RS * i1
    vp, vn = av - vd, vd
    neg = v < 0
    return np.where(neg, -vn, vp), np.where(neg, -vp, vn)


def element_current(part: DiodePart, volts, temperature: float = REFERENCE_TEMPERATURE):
    """DC current of one vendor element at voltage ``v`` across it: the Shockley diode with its
    series resistance, ``v = RS i_d + N V_T ln(1 + i_d/IS)``, solved in closed form with the
    Wright omega function, ``i_d = (N V_T/RS) omega(ln(IS RS/(N V_T)) + (v + IS RS)/(N V_T)) -
    IS`` (``IS (exp(v/(N V_T)) - 1)`` for RS = 0), plus the parallel resistor, ``v/rp``.
    Junction and diffusion capacitances carry no DC current; GMIN (1e-12 S) is left out."""
    v = np.asarray(volts, dtype=float)
    nvt = part.N * thermal_voltage(temperature)
    if part.RS > 0:
        z = math.log(part.IS * part.RS / nvt) + (v + part.IS * part.RS) / nvt
        i_d = nvt / part.RS * np.real(special.wrightomega(z)) - part.IS
    else:
        with np.errstate(over="ignore"):
            i_d = part.IS * np.expm1(v / nvt)
    return i_d + (v / part.rp if part.rp else 0.0)


def bridge_dc_current(part: DiodePart, i0: float, volts, temperature: float = REFERENCE_TEMPERATURE,
                      iterations: int = 80):
    """Terminal current of the four-element bridge around ``I0`` at terminal voltage ``V``, with
    every DC parameter of the part's model (IS, N, RS and the parallel resistor rp).

    By symmetry the elements carry ``i1 = i4`` and ``i2 = i3`` with ``i1 + i2 = I0`` and
    ``V = v1 - v2`` (voltages across the elements), so for each V one monotone equation in
    ``v2``: ``g(v2) = f(v2 + V) + f(v2) - I0 = 0`` (``f`` = :func:`element_current`,
    increasing), solved by vectorised bisection on a bracket where g changes sign; the terminal
    current is ``f(v2 + V) - f(v2)``.  Without rp this is :func:`bridge_current` (to the
    bisection's precision, ~1e-15 of I0); the rp term adds about ``2 V/rp`` once a pair is
    reverse biased, which the mapping takes off the viscous resistor."""
    v = np.asarray(volts, dtype=float)
    _amplitude(part, i0)
    # bracket: with w the diode's forward voltage at I0 (f(w) >= I0), g > 0 at
    # w + |V| + 1 (both elements forward) and g < -I0 at the mirror point (both reverse)
    w = _forward_voltage(part, float(i0), temperature) + np.abs(v) + 1.0
    lo, hi = -w, w
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        g = element_current(part, mid + v, temperature) + element_current(part, mid, temperature) - i0
        lo = np.where(g < 0, mid, lo)
        hi = np.where(g < 0, hi, mid)
    v2 = 0.5 * (lo + hi)
    return element_current(part, v2 + v, temperature) - element_current(part, v2, temperature)


def _forward_voltage(part: DiodePart, current: float, temperature: float) -> float:
    """Voltage at which the diode alone (RS included, rp left out) carries ``current`` > 0."""
    return part.N * thermal_voltage(temperature) * math.log1p(current / part.IS) + part.RS * current
