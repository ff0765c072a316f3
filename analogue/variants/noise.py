"""The noise of the model family as types (issue 20, "model variants as types").

:class:`analogue.Model` builds one of these once (``model.noise``) from its parameters:

* :class:`Silent`: ``gamma = inf`` and no shot noise (the noise-free model);
* :class:`Gaussian`: white Gaussian velocity noise of intensity ``1/gamma`` (the paper's);
* :class:`Shot`: Poissonian kicks (:class:`analogue.ShotNoise`), with or without white
  Gaussian noise (``gamma`` finite or ``inf``);
* further kinds passed as ``Model(..., noise=...)`` and registered by name in
  :data:`analogue.variants.NOISE_KINDS` (the TOML and ``as_dict`` form is
  ``noise = {kind = "...", ...}``), e.g. :class:`analogue.variants.coloured.OrnsteinUhlenbeck`.

Each kind gives what differs downstream, found by dispatch: its diffusion-limit intensity, its
Monte Carlo step limit and kicks, its Monte Carlo integrator (:meth:`Noise.stepped`, the
Gaussian default injected by :mod:`analogue.montecarlo`), its circuit element
(:meth:`Noise.replica_elements`, the netlist fragment of one replica) and its ``as_dict``
entries.  The arithmetic is the one :mod:`analogue.montecarlo` and
:mod:`analogue.circuit.netlist` had before the split, call for call, so every number and
every committed netlist is bit-identical.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from .words import Phrase, gamma_words, num

#: the circuit paragraph's held Gaussian source (coloured noise adds its low-pass)
HELD_GAUSSIAN = ("a held Gaussian noise current (ngspice trrandom, reproducible with "
                 ".options seed; the vibrating plate)")

__all__ = ["Noise", "Silent", "Gaussian", "Shot", "build_noise"]


class Noise:
    """What every noise kind gives (the defaults are those of white Gaussian noise of
    intensity ``1/gamma``, none when gamma = inf)."""

    #: the paper's noise (white Gaussian only)
    paper: ClassVar[bool] = False
    #: additive white Gaussian noise or none: exp(-gamma U) is the stationary law (1-D)
    white_gaussian_only: ClassVar[bool] = False
    #: the kind's name in ``as_dict``/TOML (None: built from gamma and shot, no entry)
    kind: ClassVar[str | None] = None
    #: the exact solver of analogue.theory for this noise: "fokker-planck" (white Gaussian),
    #: "kolmogorov-feller" (kicks), or None (none yet: the theory refuses the model)
    exact_solver: ClassVar[str | None] = "fokker-planck"
    gamma: float
    #: the shot-noise parameters (analogue.ShotNoise) or None
    shot: Any = None

    #: the registry: every subclass that names a ``kind`` (analogue.variants.NOISE_KINDS)
    registry: ClassVar[dict[str, type[Noise]]] = {}

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        name = cls.__dict__.get("kind")
        if name is not None:
            if name in Noise.registry:
                raise TypeError(f"noise kind {name!r} is registered twice")
            Noise.registry[name] = cls

    @classmethod
    def from_mapping(cls, spec: Any) -> Noise:
        """A registered kind from its ``as_dict``/TOML table ``{kind = name, ...}``."""
        fields = dict(spec)
        kind = fields.pop("kind", None)
        if kind not in Noise.registry:
            raise ValueError(f"noise kind must be one of {sorted(Noise.registry)}, got {kind!r}")
        return Noise.registry[kind](**fields)

    @property
    def is_noisy(self) -> bool:
        return True

    @property
    def gaussian(self) -> bool:
        """Whether a white Gaussian source drives the velocity (gamma finite)."""
        return math.isfinite(self.gamma)

    @property
    def velocity_intensity(self) -> float:
        """Gaussian velocity-noise intensity of the diffusion limit (``1/gamma`` plus the
        kicks' ``rate mean^2``)."""
        return 1.0 / self.gamma

    @property
    def mean_force(self) -> float:
        """Mean acceleration the noise exerts (one-sided kicks: ``rate mean``; else 0)."""
        return 0.0

    @property
    def pure_kicks(self) -> bool:
        """Kicks only (no Gaussian part): the motion between kicks is noise-free."""
        return False

    @property
    def one_sided(self) -> bool:
        """Kicks that only push up (their mean force is ``rate mean``)."""
        return False

    def work_domain(self, scale: float) -> tuple[float, float]:
        """Where the work's SCGF ``lambda(k)`` is finite when a kick z adds ``scale z`` to the
        work (``scale = F tau_m``, linear viscous law): the whole line without kicks."""
        return -math.inf, math.inf

    def bind(self, gamma: float, shot: Any) -> Noise:
        """This kind for a model with these parameters (a built-in kind is rebuilt from them,
        so that ``Model.replace(gamma=..., shot=...)`` chooses the kind anew)."""
        return build_noise(gamma, shot)

    def typical_speed(self, v_typ: float) -> float:
        return v_typ

    def closed_form_variance(self, model: Any) -> float | None:
        """The stationary ``Var v`` of ``model`` in a closed form of this noise's own, or None
        (the exact numerics of analogue.theory give it where an exact solver exists)."""
        return None

    def start_model(self, model: Any) -> Any:
        """The model whose exact stationary law gives a stationary run its start states
        (analogue.study.members): ``model`` itself where this noise has an exact solver."""
        return model

    def widen_range(self, lo: float, hi: float, tau_m: float, level: float) -> tuple[float, float]:
        """The circuit's velocity range ``(lo, hi)`` widened by how far the noise's kicks
        reach (analogue.circuit.mapping.velocity_range; ``level``: jumps of ``level`` means)."""
        return lo, hi

    def sampled_model(self, model: Any) -> Any:
        """The model whose exact stationary law a circuit's ``v0 = "stationary"`` start draws
        from (analogue.circuit.decks): ``model`` itself."""
        return model

    def kick_reach(self, tau_m: float, level: float) -> float:
        """How far above its drift the kicks push the velocity (``level``: jumps of ``level``
        means): 0 without kicks."""
        return 0.0

    def circuit_meta(self, mapping: Any) -> dict[str, Any]:
        """This kind's entries of a circuit ensemble's meta (analogue.circuit.decks)."""
        return {}

    def deck_records(self, decks: Any) -> dict[str, Any]:
        """This kind's records of a circuit ensemble, from its decks (analogue.circuit.decks)."""
        return {}

    def jump_scales(self) -> list[float]:
        """Velocity scales of the kicks (the mean jump) for the circuit's smoothing."""
        return []

    def dt_limit(self, dt: float) -> float:
        return dt

    def pulses(self, charge: float, drift_max: Callable[[float], float], step: float,
               width: float | None, *, min_width: float, target: float, edge: float
               ) -> tuple[float, float, dict[str, float]]:
        """``(charge per unit jump, pulse width, budget terms)`` of the circuit's kick pulses
        (analogue.circuit.mapping): none without kicks."""
        return 0.0, 0.0, {}

    def kicker(self) -> Callable[[float, int, np.random.Generator], np.ndarray] | None:
        """``kicks(dt, rows, rng)``: the velocity kicks of one Monte Carlo step, or None when
        this noise has none."""
        return None

    def stepped(self, model: Any, v: np.ndarray, n_steps: int, per: int, dt: float,
                scheme: str, parts: Any, noise_rng: Any, kick_rng: Any,
                default: Callable[..., tuple[np.ndarray, np.ndarray, int]]
                ) -> tuple[np.ndarray, np.ndarray, int]:
        """The time-stepped Monte Carlo: ``default`` (analogue.montecarlo's white-noise
        schemes) unless the kind has its own state to integrate."""
        return default(model, v, n_steps, per, dt, scheme, parts, noise_rng, kick_rng)

    def replica_elements(self, sub: Any, mapping: Any, value: Callable[[str, float], str]) -> None:
        """Add this noise's elements to one replica's subcircuit ``sub`` (PySpice): a
        ``trrandom`` Gaussian voltage on node ``nz`` (the velocity noise in model units, held
        for ``noise_ts``) turned into the current ``noise_gain V(nz)`` into ``v``.  ``value``
        formats a deck number (analogue.checks.spice_number)."""
        if not mapping.gaussian_noise:  # gamma = inf, or a noise-free copy of the mapping
            return
        sub.VCCS("noise", sub.gnd, "v", "nz", sub.gnd, value("noise_gain", mapping.noise_gain))
        sub.V("noise", "nz", sub.gnd,
              f"dc 0 trrandom(2 {value('noise_ts', mapping.noise_ts)} 0 "
              f"{value('noise_stddev', mapping.noise_stddev)} 0)")

    def entries(self) -> dict[str, Any]:
        """This kind's keys of ``Model.as_dict``."""
        return {}

    def mc_meta(self, n_kicks: int, scheme: str) -> dict[str, Any]:
        """This kind's entries of a Monte Carlo ensemble's meta (``scheme``: the route)."""
        return {}

    # ------------------------------------------------------------- on a page
    def describe(self) -> list[str]:
        """The noise in a page's model sentence, with its numbers."""
        return [gamma_words(self.gamma)]

    def stated_values(self) -> dict[str, float]:
        """The kind's own parameters by the names a description may state them with."""
        return {}

    def page_phrases(self) -> list[Phrase]:
        """The noise's equation term and circuit element (slots: :mod:`.words`)."""
        if not math.isfinite(self.gamma):
            return []
        return [Phrase(5, "+ xi/m"), Phrase(15, HELD_GAUSSIAN)]

    def reference_phrases(self) -> list[Phrase]:
        """The reference of a family member's comparisons without a spring: the exact
        numerics of :attr:`exact_solver`."""
        return [Phrase(20, "the Fokker-Planck numerics of the member's own law")]

    def member_kind(self, friction: Any) -> str:
        """What a member without a spring is filed under: the friction law's, for noise
        that is no extension of the paper's."""
        return friction.member_kind()

    def side_words(self) -> str:
        """Which way the kicks go, in a member's physics text (no kicks: nothing to say)."""
        return ""


@dataclass(frozen=True)
class Silent(Noise):
    """No noise at all (gamma = inf, no kicks)."""

    gamma: float = math.inf
    white_gaussian_only: ClassVar[bool] = True

    @property
    def is_noisy(self) -> bool:
        return False


@dataclass(frozen=True)
class Gaussian(Noise):
    """White Gaussian velocity noise of intensity ``1/gamma`` (paper, eq. (4))."""

    gamma: float
    paper: ClassVar[bool] = True
    white_gaussian_only: ClassVar[bool] = True


@dataclass(frozen=True)
class Shot(Noise):
    """Poissonian kicks (``shot``: an :class:`analogue.ShotNoise`), plus white Gaussian noise
    of intensity ``1/gamma`` when gamma is finite."""

    shot: Any
    gamma: float = math.inf
    exact_solver: ClassVar[str | None] = "kolmogorov-feller"

    @property
    def velocity_intensity(self) -> float:
        return 1.0 / self.gamma + self.shot.intensity

    @property
    def mean_force(self) -> float:
        return float(self.shot.mean_force)

    @property
    def pure_kicks(self) -> bool:
        return not self.gaussian

    @property
    def one_sided(self) -> bool:
        return not self.shot.two_sided

    def work_domain(self, scale: float) -> tuple[float, float]:
        """Below the pole of the kicks' moment generating function ``M(c)``, ``c = k scale``:
        ``1/(1 - c mean)`` one-sided, ``1/(1 - c^2 mean^2)`` two-sided (analogue.theory.family
        .scgf_domain)."""
        pole = 1.0 / (scale * self.shot.mean)
        if self.shot.two_sided:
            return -abs(pole), abs(pole)
        return (-math.inf, pole) if pole > 0 else (pole, math.inf)

    def typical_speed(self, v_typ: float) -> float:
        return max(v_typ, self.shot.mean)

    def widen_range(self, lo: float, hi: float, tau_m: float, level: float) -> tuple[float, float]:
        reach = self.kick_reach(tau_m, level)
        hi = max(hi, 0.0) + reach
        if self.shot.two_sided:
            lo = min(lo, 0.0) - reach
        return lo, hi

    def jump_scales(self) -> list[float]:
        return [self.shot.mean]

    def dt_limit(self, dt: float) -> float:
        return min(dt, 0.05 / self.shot.rate)

    def kicker(self) -> Callable[[float, int, np.random.Generator], np.ndarray]:
        return self.step_kicks

    def pulses(self, charge: float, drift_max: Callable[[float], float], step: float,
               width: float | None, *, min_width: float, target: float, edge: float
               ) -> tuple[float, float, dict[str, float]]:
        """Each kick a flat-topped current pulse of ``charge`` per unit jump and width ``w``:
        ``width`` when given (refused below ``min_width`` of the largest solver ``step``:
        ngspice then integrates the velocity between kicks wrongly), else ``target mean /
        drift_max`` and at least that floor, with ``drift_max(mean)`` the largest drift over
        the velocity range.  Budget terms: ``shot_pulse = drift_max w/mean`` (the drift
        during a pulse against the jump), ``shot_overlap = rate w``, ``shot_edge = edge/2``
        (the ramps' share of the charge, integrated to first order)."""
        sh = self.shot
        dmax = drift_max(sh.mean)
        w_min = min_width * step
        if width is not None and width < w_min * (1 - 1e-12):
            raise ValueError(f"shot_width={width:.3g} is below {w_min:.3g} ({min_width:g} of "
                             f"the largest solver step {step:.3g}): ngspice then integrates "
                             "the velocity between kicks wrongly; raise shot_width or lower "
                             "max_step")
        w = width if width is not None else max(target * sh.mean / dmax, w_min)
        return charge, w, {"shot_pulse": dmax * w / sh.mean, "shot_overlap": sh.rate * w,
                           "shot_edge": edge / 2.0}

    def step_kicks(self, dt: float, rows: int, rng: np.random.Generator) -> np.ndarray:
        """The exact compound-Poisson sum of one step: count ~ Poisson(rate dt), the sum of
        that many exponentials a Gamma variable (two-sided: a Binomial split of the count)."""
        shot = self.shot
        counts = rng.poisson(shot.rate * dt, rows)
        if not shot.two_sided:
            return rng.gamma(counts, shot.mean) if counts.any() else np.zeros(rows)
        up = rng.binomial(counts, 0.5)
        return rng.gamma(up, shot.mean) - rng.gamma(counts - up, shot.mean)

    def kick(self, size: int, rng: np.random.Generator) -> np.ndarray:
        """``size`` single kicks (the event-driven scheme)."""
        z = rng.exponential(self.shot.mean, size)
        if self.shot.two_sided:
            z = np.where(rng.random(size) < 0.5, z, -z)
        return z

    def entries(self) -> dict[str, Any]:
        return {"shot": self.shot.as_dict()}

    def mc_meta(self, n_kicks: int, scheme: str) -> dict[str, Any]:
        return {"kicks": int(n_kicks), "shot_scheme": scheme}

    def sampled_model(self, model: Any) -> Any:
        # The exact (Kolmogorov-Feller) law of the tanh-smoothed member needs a grid resolving
        # epsilon (45k states for epsilon = 0.01, refused); the sgn law's differs from it only
        # within the mapping's smoothing budget.
        return model.replace(epsilon=0.0) if model.epsilon > 0 else model

    def kick_reach(self, tau_m: float, level: float) -> float:
        sh = self.shot
        return sh.rate * tau_m * sh.mean + level * sh.mean

    def circuit_meta(self, mapping: Any) -> dict[str, Any]:
        return {"shot_width": mapping.shot_width}

    def deck_records(self, decks: Any) -> dict[str, Any]:
        return {"kicks": [k for d in decks for k in d.kicks]}

    def describe(self) -> list[str]:
        side = ("two-sided (each kick's sign +/- with probability 1/2)" if self.shot.two_sided
                else "one-sided (every kick pushes up)")
        return [*super().describe(),
                f"shot noise: kicks at rate {num(self.shot.rate)} per unit time, "
                f"exponentially distributed jumps of mean {num(self.shot.mean)}, {side}"]

    def stated_values(self) -> dict[str, float]:
        return {"rate": self.shot.rate, "mean": self.shot.mean}

    def page_phrases(self) -> list[Phrase]:
        return [*super().page_phrases(), Phrase(7, "+ shot kicks"),
                Phrase(16, "shot-noise kicks drawn in numpy from the deck seed and delivered "
                           "as narrow flat-topped current pulses (PWL source)"),
                Phrase(32, "shot pulse width and edges")]

    def member_kind(self, friction: Any) -> str:
        return "shot"

    def side_words(self) -> str:
        return ("two-sided: up or down with probability 1/2" if self.shot.two_sided
                else "one-sided: every kick pushes up")

    def reference_phrases(self) -> list[Phrase]:
        return [Phrase(21, "the Kolmogorov-Feller numerics for shot noise")]


def build_noise(gamma: float, shot: Any) -> Noise:
    """The noise of a model's (validated) ``gamma`` and ``shot``: chosen here, once."""
    if shot is not None:
        return Shot(shot, gamma)
    return Gaussian(gamma) if math.isfinite(gamma) else Silent()
