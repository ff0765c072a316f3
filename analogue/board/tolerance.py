"""Seeded tolerance Monte Carlo of boards, and what each tolerance does to the observables.

:func:`draw_board` draws one physical board from :class:`Tolerances` with numpy's PCG64
seeded by ``SeedSequence(seed, spawn_key=(board,))`` (same seed -> identical boards; spicelib's
Monte Carlo is unseeded, so it is not used).  Classes of tolerance (one ``draws`` key each):

- ``resistors`` (E96 metal film, uniform within +-r_tol) and their tempco;
- ``capacitors`` (C0G, uniform within +-c_tol; Bessel/AC-coupling parts +-5 %/+-10 %);
- ``references`` (the two 2.5 V sense references and the force voltage, +-ref_tol);
- ``opamp_offsets`` (offset voltage normal with the part's typical value as sigma, clipped at
  the worst-case value) and ``opamp_bias`` (bias current log-normal around typical);
- ``diodes`` (IS of the four bridge diodes, log-normal sigma ``diode_is``);
- ``temperature`` (uniform in ``temperature +- temp_range``: V_T, tempcos, offset drift,
  bias-current doubling).

:func:`effective_model` predicts, to first order, the model a drawn board implements
(derivation in the docstring); the Monte Carlo in ngspice checks it, and
:func:`sensitivities` turns it into the answer to "which tolerance must be trimmed": the
standard deviation each class alone induces in every observable (exact theory at the drawn
effective models).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from .. import checks
from ..circuit.parts import get_part, thermal_voltage
from ..model import Model
from ..theory.stationary import stationary_std
from . import opamp
from .design import BoardDesign
from .netlist import ROLES, BoardInstance, nominal_instance, role_part

__all__ = [
    "CLASSES",
    "PARAMS",
    "Tolerances",
    "draw_board",
    "effective_model",
    "gradients",
    "offset_limit",
    "readout_offset",
    "sensitivities",
]

CLASSES = ("resistors", "capacitors", "references", "opamp_offsets", "opamp_bias", "diodes",
           "temperature")


@dataclass(frozen=True)
class Tolerances:
    r_tol: float = 0.01          # E96 metal film +-1 %
    r_tempco: float = 50e-6      # 1/K
    c_tol: float = 0.01          # mass capacitor C0G/polypropylene +-1 %
    c_tempco: float = 30e-6      # C0G
    filter_c_tol: float = 0.05   # Bessel capacitors
    ac_c_tol: float = 0.10       # AC-coupling capacitor
    ref_tol: float = 0.001       # 2.5 V references (0.1 % grade)
    diode_is: float = 0.10       # sigma of ln IS between the four bridge diodes
    temperature: float = 27.0    # C, centre
    temp_range: float = 5.0      # C, half-width (a lab bench)
    enabled: tuple = CLASSES

    def __post_init__(self):
        for name in ("r_tol", "r_tempco", "c_tol", "c_tempco", "filter_c_tol", "ac_c_tol",
                     "ref_tol", "diode_is", "temp_range"):
            object.__setattr__(self, name, checks.nonnegative(name, getattr(self, name)))
        object.__setattr__(self, "temperature", checks.finite("temperature", self.temperature))
        bad = [c for c in self.enabled if c not in CLASSES]
        if bad:
            raise ValueError(f"enabled must be a subset of {CLASSES}, got {bad}")

    def only(self, *classes) -> Tolerances:
        return replace(self, enabled=tuple(classes))


def draw_board(design: BoardDesign, tol: Tolerances, seed: int, board: int) -> BoardInstance:
    """Board number ``board`` of the Monte Carlo with master seed ``seed``."""
    checks.instance("tol", tol, Tolerances, description="Tolerances")
    seed = checks.integer("seed", seed, minimum=0)
    board = checks.integer("board", board, minimum=0)
    rng = np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(int(board), 13)))
    on = set(tol.enabled)
    nom = nominal_instance(design)
    # every class draws its numbers whether enabled or not, so that switching one class off
    # leaves the others' draws unchanged (one-at-a-time sensitivities use the same boards)
    u_r = rng.uniform(-1, 1, 16)
    u_c = rng.uniform(-1, 1, 8)
    u_ref = rng.uniform(-1, 1, 3)
    z_vos = rng.standard_normal(len(ROLES))
    z_ib = rng.standard_normal(len(ROLES))
    z_d = rng.standard_normal(4)
    u_t = rng.uniform(-1, 1)
    temp = tol.temperature + (tol.temp_range * u_t if "temperature" in on else 0.0)
    dT = temp - 27.0 if "temperature" in on else 0.0
    values = dict(nom.values)
    draws = {}
    r_keys = [k for k in values if k.startswith("R") and math.isfinite(values[k])]
    for i, k in enumerate(sorted(r_keys)):
        f = (1.0 + tol.r_tol * u_r[i] if "resistors" in on else 1.0) * (1.0 + tol.r_tempco * dT)
        values[k] = values[k] * f
        draws[k] = f - 1.0
    c_keys = sorted(k for k in values if k.startswith("C"))
    for i, k in enumerate(c_keys):
        t = tol.c_tol if k == "C" else (tol.ac_c_tol if k == "C_AC" else tol.filter_c_tol)
        f = (1.0 + t * u_c[i] if "capacitors" in on else 1.0) * (1.0 + tol.c_tempco * dT)
        values[k] = values[k] * f
        draws[k] = f - 1.0
    ref = (1.0 + tol.ref_tol * u_ref) if "references" in on else np.ones(3)
    amps = {}
    for i, role in enumerate(ROLES):
        amp0 = opamp.get_opamp(role_part(design, role))
        worst = amp0.guaranteed
        a = amp0.at_temperature(temp) if "temperature" in on else amp0.at_temperature(27.0)
        vos = float(np.clip(z_vos[i] * amp0.vos, -worst.vos, worst.vos)) if "opamp_offsets" in on else 0.0
        vos += (a.vos - amp0.vos) if "temperature" in on else 0.0  # drift only
        k_ib = a.ib / amp0.ib if amp0.ib > 0 else 1.0
        ib = amp0.ib * math.exp(0.5 * z_ib[i]) * k_ib if "opamp_bias" in on else 0.0
        amps[role] = amp0.replace(vos=vos, ib=ib, ios=0.0)
        draws[f"vos_{role}"] = vos
        draws[f"ib_{role}"] = ib
    dis = tuple(float(math.exp(tol.diode_is * z)) if "diodes" in on else 1.0 for z in z_d)
    draws["diode_is"] = dis
    draws["temperature"] = temp
    return nom.replace(values=values, v_set_top=design.spec.v_set * ref[0],
                       v_set_bot=design.spec.v_set * ref[1], v_force=nom.v_force * ref[2],
                       opamps=amps, diode_is=dis, temperature=temp, label=f"board{board}",
                       draws=draws)


def effective_model(design: BoardDesign, b: BoardInstance) -> Model:
    """The model a board implements, to first order in its tolerances.

    Integrator U1 (offset ``vos`` in series with its grounded + input) holds the virtual
    ground at ``V(sj) = -vos``; its inverting input draws ``ib``.  The force resistor then
    carries ``(V_F + vos)/R_F``.  The sourcing current source forces ``v_set_top + vos_st``
    across its sense resistor, the sinking one ``v_set_bot - vos_sb``: ``I_top``, ``I_bot``;
    friction on the v > 0 side is ``I_bot + 2 IS``, on the v < 0 side ``I_top + 2 IS``, i.e.
    ``Delta = (I_top + I_bot)/2 + 2 IS`` and an extra force ``(I_top - I_bot)/2``.  Noise
    intensity ``(s_dac/R_N)^2 TS/2`` (the chain's pass band has unit gain); tanh width
    ``2 N V_T(T) + RS I``.  (The readout offset ``vos/kappa`` is :func:`readout_offset`.)
    """
    v, th, k = b.values, design.theta, design.kappa
    part = get_part(design.spec.diode)
    ck = v["C"] * k
    amp = b.opamps
    i_top = (b.v_set_top + amp["st"].vos) / v["R_S_top"]
    i_bot = (b.v_set_bot - amp["sb"].vos) / v["R_S_bot"]
    is_mean = part.IS * float(np.mean(b.diode_is))
    i_f = (b.v_force + amp["int"].vos) / v["R_F"] if math.isfinite(v["R_F"]) else 0.0
    i_f -= amp["int"].ib
    if "C_AC" not in v:
        # DC-coupled noise resistor: the Bessel buffer's output (-vos_bf with the DAC at
        # mid-scale, the same series offset as U1's) against V(sj) = -vos drives
        # (vos - vos_bf)/R_N into the virtual ground
        i_f += (amp["int"].vos - amp["bf"].vos) / v["R_N"]
    r_tot = 1.0 / (1.0 / v["R"] + (2.0 / part.rp if part.rp else 0.0))
    temp_k = b.temperature + 273.15
    eps_v = 2.0 * part.N * thermal_voltage(temp_k) + part.RS * 0.5 * (i_top + i_bot)
    d_i = (design.spec.dac_rms / v["R_N"]) ** 2 * design.noise_ts / 2.0
    return design.model.replace(
        tau_m=r_tot * v["C"] / th, delta=th * (0.5 * (i_top + i_bot) + 2.0 * is_mean) / ck,
        a=th * (i_f + 0.5 * (i_top - i_bot)) / ck, gamma=ck ** 2 / (th * d_i),
        epsilon=eps_v / k)


def readout_offset(design: BoardDesign, b: BoardInstance) -> float:
    """Model-velocity offset of the read-out: the output is ``-(u + vos)``, so v_read = v +
    vos/kappa... with u the capacitor voltage and V(sj) = -vos: ``V(out) = V(sj) - u``."""
    return b.opamps["int"].vos / design.kappa


PARAMS = ("tau_m", "delta", "a", "gamma", "epsilon", "offset")


def _vector(design: BoardDesign, m: Model, offset: float) -> np.ndarray:
    return np.array([m.tau_m, m.delta, m.a, m.gamma, m.epsilon, offset])


def gradients(design: BoardDesign, observe, rel: float = 0.01) -> tuple[dict, dict]:
    """(base, grads): observables of the realised model and their derivatives with respect to
    (tau_m, Delta, a, gamma, epsilon, read-out offset), by central differences of ``observe``
    (exact theory; steps ``rel`` of each parameter, ``rel * std`` for the offset)."""
    real = design.realised
    base = observe(real, 0.0)
    x0 = _vector(design, real, 0.0)
    steps = rel * np.where(x0 != 0, np.abs(x0), stationary_std(real))
    grads = {k: np.zeros(len(PARAMS)) for k in base}
    for j in range(len(PARAMS)):
        vals = []
        for sgn in (1.0, -1.0):
            x = x0.copy()
            x[j] += sgn * steps[j]
            m = real.replace(tau_m=x[0], delta=x[1], a=x[2], gamma=x[3], epsilon=x[4])
            vals.append(observe(m, x[5]))
        for k in base:
            grads[k][j] = (vals[0][k] - vals[1][k]) / (2.0 * steps[j])
    return base, grads


def sensitivities(design: BoardDesign, tol: Tolerances, *, boards: int, seed: int, grads: dict,
                  ) -> dict:
    """For each tolerance class alone, and all together: the standard deviation and mean
    shift, over ``boards`` drawn boards, of every observable, propagated linearly through
    ``grads`` (:func:`gradients`) from the boards' effective models and read-out offsets."""
    x0 = _vector(design, design.realised, 0.0)
    out: dict[str, dict[str, Any]] = {}
    for cls in (*CLASSES, "all"):
        t = tol if cls == "all" else tol.only(cls)
        dx = np.array([_vector(design, effective_model(design, b), readout_offset(design, b)) - x0
                       for b in (draw_board(design, t, seed, i) for i in range(boards))])
        out[cls] = {k: {"std": float(np.std(dx @ g, ddof=1)), "mean_shift": float(np.mean(dx @ g))}
                    for k, g in grads.items()}
        out[cls]["_params_std"] = {p: float(np.std(dx[:, j], ddof=1)) for j, p in enumerate(PARAMS)}
        # each parameter's share: the spread its deviation alone causes in each observable
        out[cls]["_param_contrib"] = {k: {p: float(np.std(dx[:, j] * g[j], ddof=1))
                                          for j, p in enumerate(PARAMS)}
                                      for k, g in grads.items()}
    return out


def offset_limit(design: BoardDesign, grads: dict, se_ref: dict, fraction: float,
                 tol: Tolerances | None = None) -> dict:
    """The largest guaranteed input offset the integrator's op-amp (U1: A the integrator, B the
    Bessel buffer, one part) may have, and whether ``design.spec.opamp`` meets it.

    Offsets enter as a force ``theta (vos_int (1/R_F + 1/R_N) - vos_bf/R_N)/(C kappa)`` and a
    read-out shift ``vos_int/kappa`` (:func:`effective_model`, :func:`readout_offset`); with
    both halves at the datasheet maximum ``V`` and opposite signs, observable ``k`` moves by
    ``V (s_int + s_bf)`` (``s``: its linear sensitivity per volt through ``grads``).  The limit
    is the ``V`` that keeps every shift below ``fraction`` of the full job's standard error
    ``se_ref[k]`` (the matching rule of :func:`analogue.board.job.recommend_matching`,
    applied to the worst case instead of the spread).  ``guaranteed_V``: the part's
    guaranteed offset plus its guaranteed drift over the warmest bench temperature of
    ``tol`` (measured on the stick design: limit 466 uV, set by P(v>0); OPA2140 127 uV,
    TL072 10.2 mV)."""
    tol = Tolerances() if tol is None else tol
    nom = nominal_instance(design)
    x0 = _vector(design, design.realised, 0.0)
    step = 1e-4

    def slope(role: str, g: np.ndarray) -> float:
        b = nom.replace(opamps={**nom.opamps, role: nom.opamps[role].replace(vos=step)})
        dx = _vector(design, effective_model(design, b), readout_offset(design, b)) - x0
        return abs(float(dx @ g)) / step

    per = {}
    for k, g in grads.items():
        if se_ref.get(k):
            per[k] = fraction * se_ref[k] / (slope("int", g) + slope("bf", g))
    binding = min(per, key=lambda k: per[k])
    worst = opamp.get_opamp(design.spec.opamp).guaranteed
    hottest = tol.temperature + tol.temp_range
    guaranteed = abs(worst.vos) + abs(worst.vos_drift) * abs(hottest - 25.0)
    return {"limit_V": per[binding], "binding": binding, "per_observable_V": per,
            "part": worst.name, "guaranteed_V": guaranteed, "meets": guaranteed < per[binding],
            "fraction_of_se": fraction}
