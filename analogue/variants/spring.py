"""The optional spring of the model family as a type (issue 20): :class:`Free` (the
one-dimensional members, state v) or :class:`Spring` (``-spring x`` with ``dx/dt = v``, state
(x, v)), built once by :class:`analogue.Model` (``model.restoring``)."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from .words import Phrase, num

__all__ = ["Restoring", "Free", "Spring", "build_restoring"]


class Restoring:
    """What a restoring force gives: dimension, drift term, step limit, attractor."""

    dimension: ClassVar[int] = 1
    #: the noise-free flow is the closed form of the paper's law (no position feedback)
    closed_form: ClassVar[bool] = True
    spring: float = 0.0
    x0: float

    def add_force(self, out: np.ndarray, x: Any) -> np.ndarray:
        return out

    def velocity_stand_in(self, model: Any) -> Any:
        """The 1-D member whose velocity law stands in for this model's in estimates (the
        circuit's bias budget): the model itself."""
        return model

    def dt_limit(self, dt: float) -> float:
        return dt

    def kick_drift(self, model: Any, delta_max: float, jump: float, swing: float) -> float:
        """What the restoring force adds to the largest drift a kick's pulse must outrun
        (analogue.circuit.mapping: shot pulse width), for kicks of mean ``jump``, friction
        at most ``delta_max`` and a Gaussian velocity swing ``swing``: nothing without one."""
        return 0.0

    def attractor(self, model: Any) -> float:
        """Deterministic attractor from rest: 0 if |a| <= Delta(0), else the friction law's."""
        if abs(model.a) <= model.static_friction:
            return 0.0
        return float(model.friction.attractor(model))

    def entries(self) -> dict[str, Any]:
        return {"x0": self.x0} if self.x0 != 0 else {}

    def replica_elements(self, sub: Any, m: Any, value: Any) -> None:
        """This force's elements of one replica's subcircuit (analogue.circuit.netlist): none."""

    def mc_meta(self) -> dict[str, Any]:
        """This force's entries of a Monte Carlo ensemble's meta."""
        return {}

    def energy_reach(self, model: Any) -> float:
        """How far the start's spring energy lets the velocity swing beyond the free motion's
        bound (analogue.circuit.decks.value_limits): 0 without a spring."""
        return 0.0

    def describe(self) -> list[str]:
        """The restoring force in a page's model sentence."""
        return []

    def page_phrases(self, noise: Any) -> list[Phrase]:
        """Its circuit element and equation term, and the reference of the family's
        comparisons (``noise``'s exact theory without a spring)."""
        return noise.reference_phrases()

    def member_kind(self, model: Any) -> str:
        """What a family member's text is filed under (analogue.report.beyond): the spring
        first (its analysis, Monte Carlo reference, no exact P(v = 0), whatever the noise),
        else the noise's or the friction law's."""
        return model.noise_kind.member_kind(model.friction)


@dataclass(frozen=True)
class Free(Restoring):
    """No spring (``x0`` only offsets the reported position)."""

    x0: float = 0.0


@dataclass(frozen=True)
class Spring(Restoring):
    """``-spring x``, position from ``x(0) = x0``."""

    spring: float
    x0: float = 0.0
    dimension: ClassVar[int] = 2
    closed_form: ClassVar[bool] = False

    def add_force(self, out: np.ndarray, x: Any) -> np.ndarray:
        return out - self.spring * np.asarray(x, dtype=float)

    def velocity_stand_in(self, model: Any) -> Any:
        """The force a is balanced by the spring on average (<v> = 0): the a = 0, spring-free
        member."""
        return model.replace(a=0.0, spring=0.0, x0=0.0)

    def dt_limit(self, dt: float) -> float:
        # resolve the spring period
        return min(dt, 2.0 * math.pi / math.sqrt(self.spring) / 500.0)

    def attractor(self, model: Any) -> float:
        """With a spring every motion ends at rest."""
        return 0.0

    def kick_drift(self, model: Any, delta_max: float, jump: float, swing: float) -> float:
        """``spring (|x0| + Delta_max/spring + 8 jump + swing)``: the spring force over the
        position's reach (the release, the stick band, 8 mean jumps, the Gaussian swing)."""
        return self.spring * (abs(self.x0) + delta_max / self.spring + 8.0 * jump + swing)

    def entries(self) -> dict[str, Any]:
        return {"spring": self.spring, **super().entries()}

    def mc_meta(self) -> dict[str, Any]:
        return {"position": "model.x0 + x (x = integral of v, x[:, 0] = 0)"}

    def replica_elements(self, sub: Any, m: Any, value: Any) -> None:
        """The inductor ``Lspring`` from v (initial current = the spring force at x0) -- R_L --
        a 0 V sense source -- ground; a CCVS turns the sensed current into node ``xs`` = the
        position in model units."""
        end = "ls" if m.inductor_rs > 0 else "lg"
        sub.raw_spice += (f"Lspring v {end} {value('L', m.inductance)} "
                          f"ic={value('I_L0', m.inductor_ic)}\n")
        if m.inductor_rs > 0:
            sub.R("leak", "ls", "lg", value("R_L", m.inductor_rs))
        sub.V("sense", "lg", sub.gnd, "0")
        sub.CCVS("xs", "xs", sub.gnd, "vsense", value("H_x", m.x_spring_gain))

    def energy_reach(self, model: Any) -> float:
        # the energy v^2/2 + (spring x - a)^2/(2 spring) of the start, all of it kinetic
        return abs(self.spring * self.x0 - model.a) / math.sqrt(self.spring)

    def describe(self) -> list[str]:
        return [f"spring = {num(self.spring)}, released from x0 = {num(self.x0)}"]

    def page_phrases(self, noise: Any) -> list[Phrase]:
        return [Phrase(3, "- spring x"),
                Phrase(14, "an inductor from v to ground (the spring; its current is the "
                           "position)"),
                Phrase(22, "the Monte Carlo for a spring"),
                Phrase(31, "inductor series resistance")]

    def member_kind(self, model: Any) -> str:
        return "spring"


def build_restoring(spring: float, x0: float) -> Restoring:
    return Spring(spring, x0) if spring > 0 else Free(x0)
