"""Acquisition and calibration: recover tau_m, Delta, a and gamma of a built board.

ADC (:data:`ADC_SPEC`): DC-coupled, simultaneous sampling of the integrator output (and the
DAC monitor), +-10 V range, 16 bits, at the DAC rate (400 kS/s at theta = 1 ms, TS = 2.5 us;
a USB-6363-class DAQ, see the board page's bench procedure).

Procedure (each step a short ngspice run of the drawn board, exactly what the bench does):

1. **Step responses, friction off** (the friction enable low: both sources' drains steered to
   ground by the enable switch, so no threshold or servo swing leaves a residual current; noise DAC at
   mid-scale), force input at ``+V_t`` and ``-V_t`` (V_t = 10 V, the force DAC's full scale),
   from v = 0: ``v(t) = v_inf (1 - e^{-t/tau})`` fitted for ``tau`` and ``v_inf``.  With
   ``v_inf(+-) = tau (+-g V_t + o)``: the force gain ``g`` (per volt) and the offset force
   ``o`` (op-amp offset through R_F, bias current) follow; the experiment's force is
   ``a_off = g V_F + o``.
2. **Terminal velocities, friction on, noise off**, force at +-V_t: ``v_+ = tau (g V_t + o -
   Delta_bot)``, ``v_- = tau (-g V_t + o + Delta_top)`` (both sliding as long as g V_t > Delta).
   ``Delta = (Delta_top + Delta_bot)/2``; the friction asymmetry adds ``(Delta_top -
   Delta_bot)/2`` to the force: **a from the drift** ``a = a_off + (Delta_top - Delta_bot)/2``.
   Then **stuck velocities, friction on, noise off**, force at +-Delta/2: the bridge width
   ``epsilon`` from ``0 = -v/tau + F - Delta tanh(v/epsilon)`` (the bridge's tanh law; measured
   on the stick design: 1e-4 of epsilon on the nominal board, 9e-4 on a drawn one at 27 +- 5 C,
   where the vendor diode model's width moves by 0.33 %/K).
3. **OU run, friction off, noise on, force 0**: the velocity is an Ornstein-Uhlenbeck process
   driven by the *known* DAC sequence.  Regressing the measured v(t) on the response of
   ``dv = -v/tau dt + eta`` to that sequence through the nominal chain gives the noise gain
   ``k`` (``D = k^2 D_nominal``, gamma = gamma_nominal / k^2) with a precision no variance
   estimate of the same length reaches; the plain OU variance route (``gamma = tau F/Var``
   with the chain's coloured-noise factor F) is reported next to it with its standard error.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import optimize

from ..circuit import ngspice as ng
from ..model import Model
from . import noise_chain
from .design import BoardDesign
from .netlist import BoardInstance, build_board_deck

__all__ = ["ADC_SPEC", "NOISE_GAIN_RANGE", "V_TEST", "Calibration", "CalibrationError", "calibrate_board"]

ADC_SPEC = {"coupling": "DC", "sampling": "simultaneous (velocity, DAC monitor)",
            "range_V": 10.0, "bits": 16, "rate": "the DAC rate 1/TS (400 kS/s at TS = 2.5 us)",
            "anti_alias": "none needed beyond the integrator (the velocity is band-limited by "
                          "tau_m) - sample synchronously with the DAC clock"}
V_TEST = 10.0
STEP_T = 8.0
OU_T = 20.0


@dataclass(frozen=True)
class Calibration:
    tau_m: float
    delta: float
    delta_top: float
    delta_bot: float
    a: float
    gamma: float
    gamma_variance: float
    gamma_variance_se: float
    force_gain: float
    force_offset: float
    noise_gain: float
    epsilon: float = math.nan

    def model(self, template: Model, epsilon: float | None = None) -> Model:
        """``template`` at the calibrated parameters; ``epsilon`` (the bridge width) is the
        calibrated one unless given."""
        eps = self.epsilon if epsilon is None else epsilon
        return template.replace(tau_m=self.tau_m, delta=self.delta, a=self.a, gamma=self.gamma,
                                epsilon=eps)

    def as_dict(self) -> dict:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


def _run(design, board, *, t_end, noise, seed, noise_dir, v0=0.0):
    deck = build_board_deck(design, board, v0=[v0], t_end=t_end, sample_dt=0.01, seed=seed,
                            noise_dir=noise_dir, reltol=1e-4, noise_off=not noise)
    res = ng.run_deck(deck.text, t_stop=t_end * design.theta, files=deck.noise_files)
    t = np.arange(round(t_end / 0.01) + 1) * 0.01
    v = ng.resample(res.plot, deck.vectors["v"], t * design.theta)[0] * design.to_model_v
    return t, v


#: noise gains k (measured / nominal noise amplitude) a built board can show: its tolerances
#: (R_N, C, the DAC's gain and the chain's parts, a few % each) move k by a few %; outside
#: this range the noise source did not deliver its noise (a DAC file ngspice could not open
#: gave k ~ 0 and gamma = 1e11-1e15) and the calibration is refused, never passed on.
NOISE_GAIN_RANGE = (0.5, 2.0)


class CalibrationError(RuntimeError):
    """A board's calibration failed; its parameters must not be used."""


def _check_noise_gain(k: float, board: BoardInstance) -> None:
    lo, hi = NOISE_GAIN_RANGE
    if not (math.isfinite(k) and lo <= k <= hi):
        raise CalibrationError(
            f"calibration of board {board.label!r} failed: its noise source delivered "
            f"{k:.3g} times the nominal noise amplitude (a built board gives {lo:g}-{hi:g}); "
            f"the DAC noise did not reach the integrator, so no gamma is reported")


def _fit_step(t, v):
    def f(t, v_inf, tau):
        return v_inf * (1.0 - np.exp(-t / tau))
    (v_inf, tau), _ = optimize.curve_fit(f, t, v, p0=(v[-1], 1.0))
    return v_inf, tau


def calibrate_board(design: BoardDesign, board: BoardInstance, *, seed: int, noise_dir,
                    ou_t: float = OU_T) -> Calibration:
    """Run the calibration procedure (module docstring) on ``board``; ``ou_t``: length of the
    OU run (model time units)."""
    off = board.replace(enable=False)
    v_f = board.v_force  # the experiment's force voltage (as set on the board)
    v_nom_f = design.force_sign * design.spec.v_force  # what the experimenter dialled
    res = {}
    for name, b, vt in (("off+", off, V_TEST), ("off-", off, -V_TEST),
                        ("on+", board, V_TEST), ("on-", board, -V_TEST)):
        # the force reference is scaled by its own tolerance: v_f / v_nom_f
        res[name] = _run(design, b.replace(v_force=vt * v_f / v_nom_f),
                         t_end=STEP_T, noise=False, seed=seed, noise_dir=noise_dir)
    vp, tau_p = _fit_step(*res["off+"])
    vm, tau_m_ = _fit_step(*res["off-"])
    tau = 0.5 * (tau_p + tau_m_)
    g = (vp - vm) / (2.0 * tau * V_TEST)
    o = (vp + vm) / (2.0 * tau)
    a_off = g * v_nom_f + o
    v_plus = float(np.mean(res["on+"][1][-50:]))
    v_minus = float(np.mean(res["on-"][1][-50:]))
    d_bot = g * V_TEST + o - v_plus / tau
    d_top = v_minus / tau + g * V_TEST - o
    delta = 0.5 * (d_top + d_bot)
    a = a_off + 0.5 * (d_top - d_bot)

    # bridge width (issue 21 item 6: the vendor model's width at 16 uA per diode moves with
    # temperature): friction on, noise off, force at +-Delta/2; the stuck velocity solves
    # 0 = -v/tau + F - Delta tanh(v/epsilon), F = g V + o + (Delta_top - Delta_bot)/2
    eps = []
    for sign in (1.0, -1.0):
        f_target = 0.5 * sign * delta
        volts = (f_target - o - 0.5 * (d_top - d_bot)) / g
        tw, vw = _run(design, board.replace(v_force=volts * v_f / v_nom_f), t_end=STEP_T,
                      noise=False, seed=seed, noise_dir=noise_dir)
        v_stuck = float(np.mean(vw[-50:]))
        f_eff = g * volts + o + 0.5 * (d_top - d_bot)
        eps.append(v_stuck / math.atanh((f_eff - v_stuck / tau) / delta))
    epsilon = float(np.mean(eps))

    # OU run: friction off, force off, noise on, from v = 0
    ou = off.replace(v_force=0.0)
    t, v = _run(design, ou, t_end=ou_t, noise=True, seed=seed, noise_dir=noise_dir)
    n = math.ceil(ou_t * design.theta / design.noise_ts) + 2
    volts = noise_chain.dac_sequence(design, seed, 0, n)
    per = 8
    tf, cur = noise_chain.chain_current(design.values, np.concatenate([[0.0], volts]),
                                        design.noise_ts, per_hold=per)
    eta = cur * design.theta / (design.values["C"] * design.kappa)   # model units, nominal C
    dt = design.noise_ts / per / design.theta
    lam = math.exp(-dt / tau)
    pred = np.empty_like(eta)
    acc = 0.0
    for i, e in enumerate(eta):            # exact OU response to piecewise-constant input
        acc = acc * lam + e * tau * (1.0 - lam)
        pred[i] = acc
    pred_t = np.interp(t, np.concatenate([[0.0], tf / design.theta]), np.concatenate([[0.0], pred]))
    keep = t > 3.0 * tau
    A = np.column_stack([pred_t[keep], np.ones(keep.sum())])
    (k, _c0), *_ = np.linalg.lstsq(A, v[keep], rcond=None)
    _check_noise_gain(float(k), board)
    gamma_nom = design.realised.gamma
    gamma = gamma_nom / k ** 2
    # variance route, with the chain's coloured-noise factor at lambda = 1/tau
    factor = noise_chain.ou_variance_factor(design.values, design.noise_ts,
                                            1.0 / (tau * design.theta))
    x = v[keep] - v[keep].mean()
    var = float(np.mean(x * x))
    n_eff = keep.sum() * 0.01 / (tau)          # OU: integrated autocorrelation time tau
    var_se = var * math.sqrt(2.0 / max(n_eff, 1.0))
    g_var = tau * factor / var
    return Calibration(tau_m=tau, delta=delta, delta_top=d_top, delta_bot=d_bot, a=a,
                       gamma=gamma, gamma_variance=g_var, gamma_variance_se=g_var * var_se / var,
                       force_gain=g, force_offset=o, noise_gain=float(k), epsilon=epsilon)
