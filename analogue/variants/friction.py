"""Friction laws of the model family as types (issue 20, "model variants as types").

The velocity-dependent part of the drift, ``-v/tau_m - Delta(v) sgn(v) [- cubic v^3]``, is one
object built once by :class:`analogue.Model` (``model.friction``) and found by dispatch
downstream, as scipy.stats gives each distribution its own class:

* :class:`Coulomb`: the paper's law, constant ``Delta`` (eq. (4); ``tanh(v/epsilon)`` for
  ``epsilon > 0``): closed forms for the attractor (eq. (14)), the normaliser of
  ``exp(-gamma U)`` (eq. (6)) and the noise-free flow;
* :class:`Stribeck`: ``Delta(v) = Delta + (delta_s - Delta) exp(-|v|/v_s)``;
* :class:`Cubic`: a cubic viscous term ``-cubic v^3`` added to another law (a Coulomb or a
  Stribeck law: the two extensions compose, as diffrax's terms do).

Each law gives its drift pieces, its part of the potential ``U`` (module docstring of
:mod:`analogue.model`), its Monte Carlo step limit and its entries of ``Model.as_dict``.  The
arithmetic is the one :mod:`analogue.model` had before the split, operation for operation,
so every number is bit-identical (tests/unit/test_family_model.py and the netlist test).

Calling a law, ``law(v)``, is the dry-friction acceleration ``Delta(v) sgn(v)`` (what
``Model.friction(v)`` returned when it was an alias of ``Model.coulomb``).
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from .words import Phrase, num

__all__ = ["FrictionLaw", "Coulomb", "Stribeck", "Cubic", "build_friction"]


def _logcosh(x: ArrayLike) -> np.ndarray:
    """ln cosh(x) without overflow."""
    ax = np.abs(x)
    return ax + np.log1p(np.exp(-2.0 * ax)) - math.log(2.0)


# Composite Gauss-Legendre rule on [0, 1] for the Stribeck-tanh integral (20 panels x 16
# nodes over 40 epsilon: tanh's poles sit 1.57 epsilon off the axis, panel half-width is
# epsilon, so the error is ~3.4^-32, below double precision).
_GL_X, _GL_W = np.polynomial.legendre.leggauss(16)
_PANELS = 20
_GL_NODES = ((np.arange(_PANELS)[:, None] + 0.5 * (_GL_X[None, :] + 1.0)) / _PANELS).ravel()
_GL_WEIGHTS = np.tile(0.5 * _GL_W / _PANELS, _PANELS)


class FrictionLaw:
    """What every friction law gives (the generic numerics live here; :class:`Coulomb`
    overrides them with the paper's closed forms)."""

    #: the paper's law (linear viscous term, constant Delta): closed-form flow and normaliser
    closed_form: ClassVar[bool] = False
    #: the cubic coefficient (0 unless the law is :class:`Cubic`)
    cubic: float = 0.0
    #: a kick's displacement ``int v dt`` stays bounded however large the kick (a cubic term);
    #: with the linear viscous law it grows like ``tau_m z`` (analogue.theory.family.scgf_domain)
    bounded_kick_displacement: ClassVar[bool] = False
    #: (delta_s, v_s) or None
    stribeck: tuple[float, float] | None = None
    delta: float
    epsilon: float

    # -------------------------------------------------------------- the law
    @property
    def static(self) -> float:
        """``Delta(0)``: the threshold |force| that keeps a resting object stuck."""
        raise NotImplementedError

    @property
    def peak(self) -> float:
        """``max_v Delta(v)``."""
        return max(self.delta, self.static)

    @property
    def velocity_length(self) -> float:
        """The law's own velocity scale (Stribeck's ``v_s``; ``inf`` for the others)."""
        return math.inf

    def magnitude(self, v: ArrayLike) -> np.ndarray:
        """``Delta(v)``."""
        raise NotImplementedError

    def dry(self, v: ArrayLike) -> np.ndarray:
        """Dry-friction acceleration ``Delta(v) sgn(v)`` (or ``Delta(v) tanh(v/epsilon)``)."""
        v = np.asarray(v, dtype=float)
        shape = np.tanh(v / self.epsilon) if self.epsilon > 0 else np.sign(v)
        return self.magnitude(v) * shape

    def __call__(self, v: ArrayLike) -> np.ndarray:
        return self.dry(v)

    def dry_potential(self, v: ArrayLike) -> np.ndarray:
        """``integral_0^v Delta(u) sgn(u) du`` (or with tanh)."""
        av = np.abs(np.asarray(v, dtype=float))
        d, eps = self.delta, self.epsilon
        return d * eps * _logcosh(av / eps) if eps > 0 else d * av

    def add_drift(self, out: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``out`` plus the law's drift beyond ``-v/tau_m - dry(v)`` (the cubic term)."""
        return out

    def add_magnitude_curvature(self, out: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``out + d Delta(v)/d|v|`` (the dry law's part of U'' on a half line; 0 for a
        constant Delta)."""
        return out

    def add_potential(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``u`` plus the law's potential beyond ``v^2/(2 tau_m) + dry_potential``."""
        return u

    def dt_limit(self, dt: float, v_typ: float) -> float:
        """The Monte Carlo step this law allows at the typical speed ``v_typ``."""
        return dt

    def smoothing_budget(self, epsilon: float) -> dict[str, float]:
        """The law's terms of the circuit's bias budget for the tanh width ``epsilon``."""
        return {}

    def entries(self) -> dict[str, Any]:
        """The law's keys of ``Model.as_dict`` (none for the paper's law)."""
        return {}

    # ------------------------------------------------ circuit (analogue.circuit.netlist)
    def amplitude_factor(self, m: Any, node: str, value: Callable[[str, float], str]) -> str:
        """The friction amplitude as a factor of a B-source expression of V(node) (mapping
        ``m``; ``value`` formats a deck number): ``I_Delta``."""
        return value("I_Delta", m.i_delta)

    def bridge_source(self, sub: Any, m: Any, value: Callable[[str, float], str]) -> None:
        """The diode bridge's amplitude source between its nodes p and n: ``I_Delta``."""
        sub.I("delta", "p", "n", value("I_Delta", m.i_delta))

    def bridge_node_voltages(self, m: Any, volts: np.ndarray,
                             nodes: Callable[[Any, np.ndarray], tuple[np.ndarray, np.ndarray]]
                             ) -> tuple[np.ndarray, np.ndarray]:
        """Consistent starting voltages of the bridge's inner nodes at terminal ``volts``
        (``nodes(i_delta, volts)``: analogue.circuit.parts.bridge_node_voltages)."""
        return nodes(m.i_delta, volts)

    def replica_elements(self, sub: Any, m: Any, value: Callable[[str, float], str]) -> None:
        """The law's elements of one replica beyond the Coulomb element: none."""

    # ------------------------------------------------------ Monte Carlo step
    def fast_dry(self) -> Callable[[np.ndarray], np.ndarray]:
        """:meth:`dry` as a function of an array (analogue.montecarlo's reference loop)."""
        return self.dry

    def force_into(self, a: np.ndarray, rows: int) -> Callable[[np.ndarray, np.ndarray], None]:
        """``f(v, out)``: ``out[:] = a - dry(v)`` (minus the cubic term), written in place
        for analogue.montecarlo's fast loop (``a``: the force as an array of ``rows``)."""
        subtract, dry = np.subtract, self.dry

        def force(v: np.ndarray, out: np.ndarray) -> None:
            subtract(a, dry(v), out)
        return force

    # ------------------------------------------------- generic numerics (by model)
    def attractor(self, model: Any) -> float:
        """Zero of the drift reached from rest when ``|a| > Delta(0)`` (no spring)."""
        sgn = math.copysign(1.0, model.a)
        # outward speed g(u) = sgn * drift(sgn u): > 0 at u = 0 (|a| > Delta(0)) and <= 0 at
        # u = |a| tau_m (there the drift is -Delta(v) - cubic v^3 <= 0); take the first zero.
        def g(u: float) -> float:
            return sgn * float(model.drift(sgn * u))
        grid = np.linspace(0.0, abs(model.a) * model.tau_m, 2049)
        vals = sgn * model.drift(sgn * grid[1:])
        idx = int(np.flatnonzero(vals <= 0)[0]) + 1
        if vals[idx - 1] == 0:
            return sgn * float(grid[idx])
        from scipy import optimize  # scipy on first use: `import analogue` starts fast
        return sgn * optimize.brentq(g, grid[idx - 1], grid[idx], xtol=1e-15, rtol=1e-15)

    def potential_minimum(self, model: Any) -> float:
        """Global minimum of U: the kink v = 0 or a zero of the drift (Stribeck's velocity
        weakening can make U double-welled)."""
        # U(0) = 0 and U >= v^2/(2 tau_m) - |a||v|, so the minimum lies in |v| <= 2 tau_m |a|.
        r = 2.0 * model.tau_m * abs(model.a)
        if r == 0:
            return 0.0
        # Candidates: the kink v = 0 and every zero of the drift -U' (bracketed on a grid
        # that has 0 as a node, so no bracket straddles the jump of the sgn law).
        from scipy import optimize
        grid = np.linspace(-r, r, 8001)
        f = model.drift(grid)
        cands = [0.0]
        for i in np.flatnonzero(np.sign(f[:-1]) * np.sign(f[1:]) <= 0):
            lo, hi = grid[i], grid[i + 1]
            if model.epsilon == 0 and (lo == 0.0 or hi == 0.0):
                continue
            if f[i] == 0:
                cands.append(float(lo))
            elif f[i + 1] == 0:
                cands.append(float(hi))
            else:
                cands.append(optimize.brentq(lambda v: float(model.drift(v)), lo, hi,
                                             xtol=1e-15, rtol=1e-15))
        u = [float(model.potential(c)) for c in cands]
        return cands[int(np.argmin(u))]

    def log_normaliser(self, model: Any) -> float:
        """``ln integral exp(-gamma U)`` by quadrature over the support bound."""
        r = model._support_bound()
        return _quad_log_normaliser(model, -r, r)

    # ------------------------------------------------------------- on a page
    def describe(self) -> list[str]:
        """The law's own parameters in a page's model sentence (Coulomb's Delta is the
        model's, said with it)."""
        return []

    def stated_values(self) -> dict[str, float]:
        """The law's own parameters by the names a description may state them with."""
        return {}

    def page_phrases(self) -> list[Phrase]:
        """The law's circuit element and equation term (slots: analogue.report.prose)."""
        return [Phrase(2, "- Delta sgn(v)")]

    def sweep_parameters(self) -> dict[str, tuple[float, float, str]]:
        """The law's own parameters a sweep may vary, ``{name: (low, high, rule)}``
        (analogue.study.sweep.sweep_parameters); the Coulomb law's Delta is the model's."""
        return {}

    def member_kind(self) -> str:
        """What a family member's text is filed under when neither its spring nor its noise
        decides (analogue.report.beyond): the cubic term's (so is a Coulomb law alone, a
        noise-free member)."""
        return "cubic"


def _quad_log_normaliser(model: Any, lo: float, hi: float,
                         v_star: float | None = None) -> float:
    g = model.gamma
    if v_star is None:
        v_star = model.potential_minimum()
    u_star = float(model.potential(v_star))
    pts = sorted({v_star, 0.0, -model.epsilon, model.epsilon})
    pts = [p for p in pts if lo < p < hi]
    from scipy import integrate
    val, _ = integrate.quad(lambda v: math.exp(-g * (float(model.potential(v)) - u_star)),
                            lo, hi, points=pts or None, limit=400, epsabs=0, epsrel=1e-12)
    return math.log(val) - g * u_star


@dataclass(frozen=True)
class Coulomb(FrictionLaw):
    """The paper's law: constant ``Delta`` (``delta``), ``sgn`` or ``tanh(v/epsilon)``."""

    delta: float
    epsilon: float = 0.0
    closed_form: ClassVar[bool] = True

    @property
    def static(self) -> float:
        return self.delta

    @property
    def peak(self) -> float:
        return self.delta

    def magnitude(self, v: ArrayLike) -> np.ndarray:
        return np.full_like(np.asarray(v, dtype=float), self.delta)

    def attractor(self, model: Any) -> float:
        """``v_ss = (a - Delta sgn a) tau_m`` (eq. (14) and its mirror)."""
        return (model.a - math.copysign(self.delta, model.a)) * model.tau_m

    def fast_dry(self) -> Callable[[np.ndarray], np.ndarray]:
        """The same floating-point operations as :meth:`dry` (``Delta * sgn(v)``, ``Delta *
        tanh(v/epsilon)``) without its per-call conversions (``asarray``, ``full_like``), which
        cost about as much as a Monte Carlo step itself (measured: 400 000 calls, 8 s of 20 s)."""
        delta, eps = self.delta, self.epsilon
        if eps > 0:
            return lambda v: delta * np.tanh(v / eps)
        return lambda v: delta * np.sign(v)

    def force_into(self, a: np.ndarray, rows: int) -> Callable[[np.ndarray, np.ndarray], None]:
        # ufuncs with a positional output: the cheapest call (keywords cost ~10 %); numpy 2's
        # ufuncs take an array operand faster than a Python float
        delta, eps = np.full(rows, self.delta), np.full(rows, self.epsilon)
        scaled = np.empty(rows)
        multiply, subtract, divide, tanh, sign = (np.multiply, np.subtract, np.divide, np.tanh,
                                                  np.sign)
        if self.epsilon > 0:
            def force(v: np.ndarray, out: np.ndarray) -> None:
                # tanh out of place, as np.tanh(v / eps) was (its SIMD loop is chosen by the
                # operands' overlap: no reliance on in-place taking the same one)
                divide(v, eps, scaled)
                tanh(scaled, out)
                multiply(delta, out, out)
                subtract(a, out, out)
            return force

        def force_sgn(v: np.ndarray, out: np.ndarray) -> None:
            sign(v, out)
            multiply(delta, out, out)
            subtract(a, out, out)
        return force_sgn

    def potential_minimum(self, model: Any) -> float:
        """U is strictly convex (U'' >= 1/tau_m): the attractor, or with tanh the drift's
        one zero."""
        if self.epsilon == 0:
            return model.attractor
        from scipy import optimize
        lo = (model.a - self.delta) * model.tau_m - 1.0
        hi = (model.a + self.delta) * model.tau_m + 1.0
        return optimize.brentq(lambda v: -float(model.drift(v)), lo, hi, xtol=1e-15, rtol=1e-15)

    def log_normaliser(self, model: Any) -> float:
        g, tau = model.gamma, model.tau_m
        if self.epsilon == 0:
            # integral_0^inf exp(-v^2/(2 s^2) - b v) dv = s sqrt(2 pi) exp(b^2 s^2/2) Phi(-b s)
            from scipy import special
            s = math.sqrt(tau / g)
            def half(b: float) -> float:
                return (math.log(s * math.sqrt(2 * math.pi)) + 0.5 * (b * s) ** 2
                        + float(special.log_ndtr(-b * s)))
            return float(np.logaddexp(half(g * (self.delta - model.a)),
                                      half(g * (self.delta + model.a))))
        # Smooth law: U'' >= 1/tau_m, so the density is log-concave with width <=
        # sqrt(tau/g); integrating 40 widths either side of the mode captures everything.
        v_star = model.potential_minimum()
        w = 40.0 * math.sqrt(tau / g)
        return _quad_log_normaliser(model, v_star - w, v_star + w, v_star)


@dataclass(frozen=True)
class Stribeck(FrictionLaw):
    """``Delta(v) = Delta + (delta_s - Delta) exp(-|v|/v_s)`` (static ``delta_s``, dynamic
    ``Delta``)."""

    delta: float
    delta_s: float
    v_s: float
    epsilon: float = 0.0

    @property
    def stribeck(self) -> tuple[float, float]:  # type: ignore[override]
        return (self.delta_s, self.v_s)

    @property
    def static(self) -> float:
        return self.delta_s

    @property
    def velocity_length(self) -> float:
        return self.v_s

    def magnitude(self, v: ArrayLike) -> np.ndarray:
        v = np.asarray(v, dtype=float)
        return self.delta + (self.delta_s - self.delta) * np.exp(-np.abs(v) / self.v_s)

    def dry_potential(self, v: ArrayLike) -> np.ndarray:
        base = super().dry_potential(v)
        av = np.abs(np.asarray(v, dtype=float))
        d, eps, ds, vs = self.delta, self.epsilon, self.delta_s, self.v_s
        if eps == 0:
            return base + (ds - d) * vs * -np.expm1(-av / vs)
        # integral_0^|v| e^{-u/v_s} tanh(u/eps) du: quadrature up to min(|v|, 40 eps), where
        # tanh = 1 to double precision, then the closed form of the exponential.
        cut = np.minimum(av, 40.0 * eps)
        flat = cut.ravel()
        head = np.empty_like(flat)
        for i in range(0, flat.size, 4096):  # chunks: 4096 x 320 nodes (10 MB) at a time
            u = flat[i:i + 4096, None] * _GL_NODES
            head[i:i + 4096] = flat[i:i + 4096] * np.sum(_GL_WEIGHTS * np.exp(-u / vs)
                                                        * np.tanh(u / eps), axis=-1)
        head = head.reshape(cut.shape)
        tail = vs * (np.exp(-cut / vs) - np.exp(-av / vs))
        return base + (ds - d) * (head + tail)

    def add_magnitude_curvature(self, out: np.ndarray, v: np.ndarray) -> np.ndarray:
        ds, vs = self.delta_s, self.v_s
        return out - (ds - self.delta) / vs * np.exp(-np.abs(v) / vs)

    def _amplitude(self, m: Any, node: str, value: Callable[[str, float], str]) -> str:
        return (f"{value('I_Delta', m.i_delta)}+{value('I_Stribeck', m.i_stribeck)}"
                f"*exp(-abs(V({node}))/{value('V_s', m.stribeck_volts)})")

    def amplitude_factor(self, m: Any, node: str, value: Callable[[str, float], str]) -> str:
        """``(I_Delta + I_s exp(-|V|/V_s))``."""
        return f"({self._amplitude(m, node, value)})"

    def bridge_source(self, sub: Any, m: Any, value: Callable[[str, float], str]) -> None:
        # the source follows Delta(V_t) (behavioural: see analogue.circuit.nonlinear)
        sub.BehavioralSource("delta", "p", "n", current_expression=self._amplitude(m, "t", value))

    def bridge_node_voltages(self, m: Any, volts: np.ndarray,
                             nodes: Callable[[Any, np.ndarray], tuple[np.ndarray, np.ndarray]]
                             ) -> tuple[np.ndarray, np.ndarray]:
        # the amplitude differs per replica (Delta(V) at each start): one call each
        i0 = m.i_delta + m.i_stribeck * np.exp(-np.abs(volts) / m.stribeck_volts)
        vpn = [nodes(i0[i], volts[i:i + 1]) for i in range(volts.size)]
        return np.array([a[0] for a, _ in vpn]), np.array([b[0] for _, b in vpn])

    def smoothing_budget(self, epsilon: float) -> dict[str, float]:
        # the tanh must switch well inside the Stribeck decay length
        return {"stribeck_smoothing": epsilon / self.v_s} if epsilon > 0 else {}

    def dt_limit(self, dt: float, v_typ: float) -> float:
        # resolve the Stribeck length crossed at the typical speed (6 of them)
        return min(dt, self.v_s / (50.0 * 6.0 * v_typ))

    def entries(self) -> dict[str, Any]:
        return {"stribeck": [self.delta_s, self.v_s]}

    def describe(self) -> list[str]:
        return [f"Stribeck delta_s = {num(self.delta_s)}, v_s = {num(self.v_s)}"]

    def stated_values(self) -> dict[str, float]:
        return {"delta_s": self.delta_s, "v_s": self.v_s}

    def page_phrases(self) -> list[Phrase]:
        # Delta(v) covers the constant Delta of a Coulomb member on the same page
        return [Phrase(2, "- Delta(v) sgn(v)", covers=1),
                Phrase(12, "a Stribeck excess current that decays with |V| (velocity weakening)")]

    def member_kind(self) -> str:
        return "stribeck"

    def sweep_parameters(self) -> dict[str, tuple[float, float, str]]:
        return {"delta_s": (0.0, math.inf, ">="), "v_s": (0.0, math.inf, ">")}


@dataclass(frozen=True)
class Cubic(FrictionLaw):
    """``-cubic v^3`` added to the law ``inner`` (a :class:`Coulomb` or :class:`Stribeck`)."""

    inner: FrictionLaw
    cubic: float
    bounded_kick_displacement: ClassVar[bool] = True

    @property
    def delta(self) -> float:  # type: ignore[override]
        return self.inner.delta

    @property
    def epsilon(self) -> float:  # type: ignore[override]
        return self.inner.epsilon

    @property
    def stribeck(self) -> tuple[float, float] | None:  # type: ignore[override]
        return self.inner.stribeck

    @property
    def static(self) -> float:
        return self.inner.static

    @property
    def peak(self) -> float:
        return self.inner.peak

    @property
    def velocity_length(self) -> float:
        return self.inner.velocity_length

    def magnitude(self, v: ArrayLike) -> np.ndarray:
        return self.inner.magnitude(v)

    def dry(self, v: ArrayLike) -> np.ndarray:
        return self.inner.dry(v)

    def dry_potential(self, v: ArrayLike) -> np.ndarray:
        return self.inner.dry_potential(v)

    def add_drift(self, out: np.ndarray, v: np.ndarray) -> np.ndarray:
        return self.inner.add_drift(out, v) - self.cubic * v**3

    def add_potential(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        return self.inner.add_potential(u, v) + 0.25 * self.cubic * v**4

    def add_magnitude_curvature(self, out: np.ndarray, v: np.ndarray) -> np.ndarray:
        return self.inner.add_magnitude_curvature(out, v)

    def fast_dry(self) -> Callable[[np.ndarray], np.ndarray]:
        return self.inner.fast_dry()

    def force_into(self, a: np.ndarray, rows: int) -> Callable[[np.ndarray, np.ndarray], None]:
        inner, cubic, subtract = self.inner.force_into(a, rows), self.cubic, np.subtract

        def force(v: np.ndarray, out: np.ndarray) -> None:
            inner(v, out)
            subtract(out, cubic * v**3, out)
        return force

    def smoothing_budget(self, epsilon: float) -> dict[str, float]:
        return self.inner.smoothing_budget(epsilon)

    def amplitude_factor(self, m: Any, node: str, value: Callable[[str, float], str]) -> str:
        return self.inner.amplitude_factor(m, node, value)

    def bridge_source(self, sub: Any, m: Any, value: Callable[[str, float], str]) -> None:
        self.inner.bridge_source(sub, m, value)

    def bridge_node_voltages(self, m: Any, volts: np.ndarray,
                             nodes: Callable[[Any, np.ndarray], tuple[np.ndarray, np.ndarray]]
                             ) -> tuple[np.ndarray, np.ndarray]:
        return self.inner.bridge_node_voltages(m, volts, nodes)

    def replica_elements(self, sub: Any, m: Any, value: Callable[[str, float], str]) -> None:
        """The cubic conductance ``g3 V^3`` from v to ground: a B-source, or the diode-resistor
        breakpoint network (subcircuit ``cubicnet``, analogue.circuit.nonlinear)."""
        self.inner.replica_elements(sub, m, value)
        if m.cubic_element == "behavioural":
            sub.BehavioralSource("cubic", "v", sub.gnd,
                                 current_expression=f"{value('g3', m.g3)}*V(v)*V(v)*V(v)")
        elif m.cubic_element == "diode-network":
            sub.X("cubic", "cubicnet", "v")

    def dt_limit(self, dt: float, v_typ: float) -> float:
        # keep the explicit cubic term stable: dt * 3 cubic v^2 <= 1/50 at 6 typical speeds
        dt = self.inner.dt_limit(dt, v_typ)
        return min(dt, 1.0 / (50.0 * 3.0 * self.cubic * (6.0 * v_typ) ** 2))

    def entries(self) -> dict[str, Any]:
        return {"cubic": self.cubic, **self.inner.entries()}

    def describe(self) -> list[str]:
        return [f"cubic = {num(self.cubic)}", *self.inner.describe()]

    def stated_values(self) -> dict[str, float]:
        return self.inner.stated_values()

    def page_phrases(self) -> list[Phrase]:
        return [Phrase(1, "- cubic v^3"),
                Phrase(13, "a cubic conductance g3 V^3 (cubic viscous friction)"),
                Phrase(30, "cubic network approximation"),
                *self.inner.page_phrases()]

    def sweep_parameters(self) -> dict[str, tuple[float, float, str]]:
        return self.inner.sweep_parameters()   # cubic itself is a model parameter, always swept

    def member_kind(self) -> str:
        return self.inner.member_kind()   # Stribeck with a cubic term files as Stribeck


def build_friction(delta: float, epsilon: float, cubic: float,
                   stribeck: tuple[float, float] | None) -> FrictionLaw:
    """The law of a model's (validated) parameters: chosen here, once."""
    law: FrictionLaw = (Coulomb(delta, epsilon) if stribeck is None
                        else Stribeck(delta, stribeck[0], stribeck[1], epsilon))
    return Cubic(law, cubic) if cubic != 0 else law
