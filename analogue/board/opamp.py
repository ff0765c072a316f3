"""Our own parameterised op-amp macromodel (no vendor model is shipped).

The subcircuit (pins ``inp inn vcc vee out``) is a one-pole voltage-feedback amplifier:

- input offset voltage ``vos`` in series with the non-inverting input; input bias currents
  ``ib +- ios/2`` drawn out of each input pin; differential input resistance ``rin``;
- a transconductance stage ``I = i_max tanh(gm v_d / i_max)`` into a gain node ``g`` loaded by
  ``r1 || c1``: DC gain ``a0 = gm r1``, unity-gain bandwidth ``gbw = gm / (2 pi c1)``, slew rate
  ``i_max / c1`` (the tanh is the input pair running out of tail current);
- rail clamps: diodes from ``g`` to ``vcc - headroom`` and ``vee + headroom``, referenced to the
  *supply pins*, so the output follows the rails it is given;
- a unity buffer and the open-loop output resistance ``rout`` behind a current limit ``i_sc``
  (``I = clip(V/rout, -i_sc, i_sc)``): the output swing against a load current ``I`` is
  ``headroom + rout I`` from the rail, and a short draws at most ``i_sc``
  (:func:`output_swing` is that law; a test checks the subcircuit against it);
- the input common-mode range ``[V- + cm_neg, V+ - cm_pos]`` (issue 21): beyond it a current
  that grows by twice the tail current per 50 mV overrides the input stage, driving the output
  to the positive rail below the negative limit of a part with ``phase_reversal`` (TL07x: the
  output inverts) and to the negative rail otherwise (the inputs no longer control it).  The
  range is read at the non-inverting pin (in closed loop both inputs sit within microvolts of
  each other).

The parameter sets are "class" values read off typical and guaranteed (min/max) datasheet
columns for a JFET-input TL072 and a JFET-input precision OPA2140 at +-15 V, 25 C.  They are
not the manufacturers' models; a user who wants a vendor model downloads it and points
:func:`vendor_model_path` at it (the file is checked, never copied into this repository).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, fields, replace
from pathlib import Path

from .. import checks

__all__ = [
    "OPAMPS",
    "OpAmp",
    "forbidden_deck_lines",
    "get_opamp",
    "output_swing",
    "subcircuit",
    "vendor_model_path",
]

# The input stage's transconductance (S): the gain-node resistance a0/GM and capacitance
# GM/(2 pi gbw) follow.  0.2 S for every part (the TL072's value at R1 = 1 MOhm): with R1 fixed
# instead, the OPA2197's 3 S stage carried amperes inside the model and cost 2x the CPU per
# time point (measured on the stick board, same accepted points).
GM = 0.2
CLAMP_MODEL = "dclampx"


@dataclass(frozen=True)
class OpAmp:
    """Op-amp macromodel parameters (SI units).

    a0: open-loop DC gain (V/V); gbw: gain-bandwidth product (Hz); slew: slew rate (V/s);
    vos: input offset voltage (V); vos_drift: its temperature coefficient (V/K);
    ib: input bias current (A) at 25 C; ios: input offset current (A); ib_doubling: the
    temperature rise (K) that doubles ib (JFET inputs: about 10 K); rin: differential input
    resistance (ohm); rout: open-loop output resistance (ohm); headroom: how close the output
    gets to either rail at no load (V); cm_neg / cm_pos: the input common-mode range reaches
    ``V- + cm_neg`` and ``V+ - cm_pos`` (V; negative: beyond the rail); phase_reversal:
    the output inverts beyond the negative common-mode limit; i_sc: output short-circuit
    current (A).
    """

    name: str
    a0: float
    gbw: float
    slew: float
    vos: float
    vos_drift: float
    ib: float
    ios: float
    ib_doubling: float
    rin: float
    rout: float
    headroom: float
    source: str = ""
    cm_neg: float = 4.0
    cm_pos: float = 4.0
    phase_reversal: bool = False
    i_sc: float = 0.02

    def __post_init__(self):
        checks.identifier("op-amp name", self.name)
        for f in fields(self):
            if f.name in ("name", "source", "phase_reversal"):
                continue
            value = getattr(self, f.name)
            if f.name in ("vos", "vos_drift", "ib", "ios", "cm_neg", "cm_pos"):
                object.__setattr__(self, f.name, checks.finite(f.name, value))
            else:
                object.__setattr__(self, f.name, checks.positive(f.name, value))

    @property
    def gm(self) -> float:
        return GM

    @property
    def r1(self) -> float:
        return self.a0 / GM

    @property
    def c1(self) -> float:
        return self.gm / (2.0 * math.pi * self.gbw)

    @property
    def i_max(self) -> float:
        return self.slew * self.c1

    def at_temperature(self, celsius: float) -> OpAmp:
        """The same part at ``celsius``: offset drifts linearly, bias currents double every
        ``ib_doubling`` kelvin (JFET gate leakage)."""
        dt = checks.finite("celsius", celsius) - 25.0
        k = 2.0 ** (dt / self.ib_doubling)
        return replace(self, vos=self.vos + self.vos_drift * dt, ib=self.ib * k, ios=self.ios * k)

    def replace(self, **changes) -> OpAmp:
        return replace(self, **changes)

    def common_mode_range(self, rails: float) -> tuple[float, float]:
        """(lowest, highest) input common-mode voltage at symmetric supplies ``+-rails``."""
        return -rails + self.cm_neg, rails - self.cm_pos

    @property
    def guaranteed(self) -> OpAmp:
        """The part's guaranteed-limits set (``NAME_worst``), or itself when it is one."""
        return OPAMPS.get(self.name.split("_")[0] + "_worst", self)


def output_swing(p: OpAmp, rails: float, load: float) -> float:
    """Largest output magnitude (V) into ``load`` ohms to ground at supplies ``+-rails``:
    ``V = rails - headroom - rout I`` with ``I = V/load``, capped by ``i_sc load``."""
    v = (rails - p.headroom) / (1.0 + p.rout / load)
    return min(v, p.i_sc * load)


# Datasheet "class" values (typical column / worst-case column), +-15 V, 25 C.  Output stage:
# headroom and rout fitted to the swing at 10 kOhm and 2 kOhm (TL072: 13.5/12 V typical,
# 12/10 V guaranteed -> rout 320/530 Ohm, no-load headroom 1.07/2.36 V).  Common-mode range:
# TL072 -12 to +15 V typical, +-11 V guaranteed, phase reversal beyond the negative limit;
# OPA2140 (V-) - 0.1 to (V+) - 3.5 V; OPA2197 (V-) - 0.1 to (V+) + 0.1 V (rail-to-rail input,
# no phase reversal).
OPAMPS: dict[str, OpAmp] = {
    "TL072": OpAmp("TL072", a0=2e5, gbw=3e6, slew=13e6, vos=3e-3, vos_drift=18e-6, ib=65e-12,
                   ios=5e-12, ib_doubling=10.0, rin=1e12, rout=320.0, headroom=1.07,
                   source="TL072-class typical values (JFET input, +-15 V)", cm_neg=3.0,
                   cm_pos=0.0, phase_reversal=True, i_sc=0.04),
    "TL072_worst": OpAmp("TL072_worst", a0=2.5e4, gbw=2e6, slew=8e6, vos=10e-3, vos_drift=30e-6,
                         ib=200e-12, ios=100e-12, ib_doubling=10.0, rin=1e11, rout=530.0,
                         headroom=2.36, source="TL072-class guaranteed limits (min gain, max offset)",
                         cm_neg=4.0, cm_pos=4.0, phase_reversal=True, i_sc=0.01),
    "OPA2140": OpAmp("OPA2140", a0=2e6, gbw=11e6, slew=20e6, vos=30e-6, vos_drift=0.35e-6,
                     ib=0.5e-12, ios=0.5e-12, ib_doubling=10.0, rin=1e13, rout=20.0, headroom=0.2,
                     source="OPA2140-class typical values (precision JFET, rail-to-rail output)",
                     cm_neg=-0.1, cm_pos=3.5, i_sc=0.036),
    "OPA2140_worst": OpAmp("OPA2140_worst", a0=1e6, gbw=8e6, slew=15e6, vos=120e-6,
                           vos_drift=1e-6, ib=10e-12, ios=10e-12, ib_doubling=10.0, rin=1e12,
                           rout=40.0, headroom=0.35,
                           source="OPA2140-class guaranteed limits", cm_neg=0.0, cm_pos=3.5,
                           i_sc=0.02),
    "OPA2197": OpAmp("OPA2197", a0=3e6, gbw=10e6, slew=20e6, vos=25e-6, vos_drift=0.5e-6,
                     ib=5e-12, ios=2e-12, ib_doubling=10.0, rin=1e13, rout=40.0, headroom=0.1,
                     source="OPA2197-class typical values (rail-to-rail input and output, 36 V)",
                     cm_neg=-0.1, cm_pos=-0.1, i_sc=0.065),
    "OPA2197_worst": OpAmp("OPA2197_worst", a0=1e6, gbw=8e6, slew=15e6, vos=250e-6,
                           vos_drift=2.5e-6, ib=20e-12, ios=20e-12, ib_doubling=10.0, rin=1e12,
                           rout=80.0, headroom=0.3, source="OPA2197-class guaranteed limits",
                           cm_neg=0.0, cm_pos=0.0, i_sc=0.03),
}


def get_opamp(name: str) -> OpAmp:
    try:
        return OPAMPS[name]
    except (KeyError, TypeError):
        raise ValueError(f"op-amp must be one of {sorted(OPAMPS)}, got {name!r}") from None


_n = checks.spice_number  # a deck number: _n(name, value)


def subcircuit(p: OpAmp, name: str | None = None, rails: float = 15.0) -> str:
    """SPICE text of the macromodel ``.subckt NAME inp inn vcc vee out`` (see module doc);
    ``rails``: the symmetric supply the common-mode limits refer to.

    The clamp diodes use the model ``dclampx`` (emitted here, once per subcircuit: a model
    inside a ``.subckt`` is local to it)."""
    if not isinstance(p, OpAmp):
        raise TypeError(f"p must be an OpAmp, got {type(p).__name__}")
    name = checks.identifier("subcircuit name", name or p.name)
    # the clamp diode's own forward drop at the full transconductance current (N = 0.2:
    # 0.15 V for a TL072), added to the clamp voltage so that the swing is ``headroom``
    clamp = 0.2 * 0.025852 * math.log(p.i_max / 1e-14)
    return "\n".join([
        f".subckt {name} inp inn vcc vee out",
        f"Vos inp ip1 dc {_n('vos', p.vos)}",
        f"Ibp ip1 0 dc {_n('ib', p.ib + 0.5 * p.ios)}",
        f"Ibn inn 0 dc {_n('ib', p.ib - 0.5 * p.ios)}",
        f"Rin ip1 inn {_n('rin', p.rin)}",
        # transconductance with slew limiting (tail current i_max), times the common-mode
        # factor: -1 (phase reversal) or 0 (gain collapse) beyond the input range
        f"Bgm 0 g i={_n('i_max', p.i_max)}*tanh({_n('gm / i_max', p.gm / p.i_max)}*(v(ip1)-v(inn)))",
        *_cm_lines(p, rails),
        f"R1 g 0 {_n('R1', p.r1)}",
        f"C1 g 0 {_n('c1', p.c1)}",
        # rail clamps referenced to the supply pins
        f"Vhp vcc chp dc {_n('headroom', p.headroom + clamp)}",
        f"Vhn chn vee dc {_n('headroom', p.headroom + clamp)}",
        f"Dhp g chp {CLAMP_MODEL}",
        f"Dhn chn g {CLAMP_MODEL}",
        f".model {CLAMP_MODEL} D(IS=1e-14 N=0.2)",
        "Ebuf o1 0 g 0 1",
        # open-loop output resistance behind the short-circuit current limit
        # a hard clip: measured 2.0x the CPU time of a plain resistor with a smooth
        # x/(1+|x/i_sc|^6)^(1/6) law, 1.17x with min/max
        (f"Bout o1 out i=min(max((v(o1)-v(out))/{_n('rout', p.rout)},{_n('i_sc', -p.i_sc)}),"
         f"{_n('i_sc', p.i_sc)})"),
        f".ends {name}",
    ])


def _cm_lines(p: OpAmp, rails: float) -> list[str]:
    """Outside the input common-mode range a current ``2 i_max`` per 50 mV beyond the limit
    overrides the input stage: towards the positive rail below the negative limit of a part
    with phase reversal (the TL07x's output inverts there), towards the negative rail
    otherwise (the output is no longer controlled by the inputs).  Zero inside the range, so
    a board whose inputs stay inside pays nothing for it (a multiplying factor on the input
    stage cost 2x the CPU per time point, measured)."""
    k = _n("k", 2.0 * p.i_max / 0.05)
    # limits at the nominal rails, not at v(vcc)/v(vee): ngspice's source stepping ramps the
    # supplies from 0 V, which put every input beyond a supply-referenced limit and latched the
    # phase-reversing integrator at the rail (measured: the operating point then missed .ic)
    lo, hi = p.common_mode_range(rails)
    below = f"max({_n('cm low', lo)}-v(inp),0)"
    above = f"max(v(inp)-({_n('cm high', hi)}),0)"
    sign = "" if p.phase_reversal else "-"
    # a limit at or beyond a rail is left out: no node of the board leaves the rails (tested)
    return ([f"Bcml 0 g i={sign}{k}*{below}"] if p.cm_neg > 0 else []) + \
        ([f"Bcmh 0 g i=-{k}*{above}"] if p.cm_pos > 0 else [])


# ---------------------------------------------------------------------- vendor models
_FORBIDDEN = re.compile(r"^\s*(\.control|\.endc|\.exec|\.include|\.lib|shell|!)", re.IGNORECASE | re.MULTILINE)
_SAFE_PATH = re.compile(r"[A-Za-z0-9_./+-]+")


def forbidden_deck_lines(text: str) -> list[str]:
    """Lines that would make ngspice run commands or read other files (``.control``, ``.exec``,
    ``shell``, ``.include``/``.lib``): a vendor file containing any of them is refused."""
    return [m.group(0).strip() for m in _FORBIDDEN.finditer(text)]


def vendor_model_path(path, subckt: str) -> Path:
    """Validate a vendor op-amp model the user downloaded: an existing regular file under 1 MB,
    with a safe path (letters, digits, ``_ . / + -``), containing ``.subckt SUBCKT`` with
    five pins, and no ``.control``/``.exec``/``shell``/``.include``/``.lib`` lines.  Returns
    the resolved path; the deck writer inlines the checked text into decks built on the user's
    machine (nothing of it enters this repository)."""
    if not isinstance(path, (str, Path)):
        raise TypeError(f"vendor model path must be a str or Path, got {type(path).__name__}")
    subckt = checks.identifier("vendor subcircuit name", subckt)
    p = Path(path).expanduser().resolve()
    if _SAFE_PATH.fullmatch(str(p)) is None:
        raise ValueError(f"vendor model path must contain only letters, digits and _ . / + -, "
                         f"got {str(p)!r}")
    if not p.is_file():
        raise ValueError(f"vendor model path {str(p)!r} is not an existing file")
    if p.stat().st_size > 1_000_000:
        raise ValueError(f"vendor model file {str(p)!r} is larger than 1 MB")
    text = p.read_text(errors="replace")
    bad = forbidden_deck_lines(text)
    if bad:
        raise ValueError(f"vendor model file {str(p)!r} contains forbidden lines "
                         f"(.control/.exec/shell/.include/.lib): {bad[:3]}")
    m = re.search(rf"^\s*\.subckt\s+{re.escape(subckt)}\s+(.*)$", text, re.IGNORECASE | re.MULTILINE)
    if m is None:
        raise ValueError(f"vendor model file {str(p)!r} defines no .subckt {subckt}")
    pins = [t for t in m.group(1).split() if "=" not in t]
    if len(pins) != 5:
        raise ValueError(f".subckt {subckt} in {str(p)!r} has {len(pins)} pins; the board needs "
                         f"five (in+ in- V+ V- out, in that order)")
    return p
