"""The board's ngspice deck: replicas of one board (same parts, independent noise sequences).

Per replica ``i`` (see :mod:`analogue.board.design` for the equation):

- ``XU{i}``: the integrator op-amp, non-inverting input grounded, inverting input the virtual
  ground ``sj{i}``, output ``o{i}`` = ``-kappa v``;
- feedback ``sj{i}``-``o{i}``: the mass capacitor ``C``, the viscous resistor ``R`` and the
  diode bridge with its two active current sources (:func:`analogue.board.friction.bridge_lines`);
- the force: the reference voltage ``V_F`` (node ``f``, shared) through ``R_F`` into ``sj{i}``;
- the noise: DAC ``d{i}`` (filesource of the replica's seeded sequence) -> Bessel -> ``C_AC``
  -> ``R_N`` into ``sj{i}``;
- position: digitally, from the sampled output (trapezoid in :func:`analogue.circuit.simulate.
  run_batch`), as an ADC-fed microcontroller would do it.

The initial velocity is set with ``.ic`` on the output and the integrator's gain node (no
``uic``: ngspice then solves the operating point of the current sources, the Bessel filter and
the bridge with the integrator held, which is what a reset switch across ``C`` followed by an
initial-condition drive does on the bench).  No ``.control`` block; every number is formatted
by :func:`analogue.checks.spice_number`.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass, field, replace

import numpy as np

from .. import checks
from ..circuit.parts import get_part
from . import friction, noise_chain, opamp
from .design import BoardDesign

__all__ = ["RESET_TIME", "R_IC", "BoardDeck", "BoardInstance", "build_board_deck", "ic_voltage",
           "nominal_instance", "role_part"]

ROLES = ("int", "st", "sb", "bf")  # integrator, source top, source bottom, Bessel buffer


@dataclass(frozen=True)
class BoardInstance:
    """One physical board: actual component values and part parameters.

    ``values``: component values (keys of :attr:`BoardDesign.values`, with ``R_S_top`` and
    ``R_S_bot`` separate); ``v_set_top``/``v_set_bot``: the two reference voltages;
    ``v_force``: force voltage (signed); ``opamps``: role -> :class:`~analogue.board.opamp.OpAmp`;
    ``diode_is``: four IS scale factors (bridge diode mismatch); ``temperature`` (C);
    ``label``: for reports; ``mosfet_vto``: the current-source MOSFETs' threshold magnitude
    (V; datasheet range 0.8-2.5 V); ``enable``: the friction enable (False: both sources'
    drains steered to ground, friction off, as the calibration's first step runs).
    """

    values: dict
    v_set_top: float
    v_set_bot: float
    v_force: float
    opamps: dict
    diode_is: tuple = (1.0, 1.0, 1.0, 1.0)
    temperature: float = 27.0
    rails: float = 15.0
    label: str = "nominal"
    draws: dict = field(default_factory=dict)
    mosfet_vto: float = friction.MOSFET_VTO
    enable: bool = True

    def replace(self, **changes) -> BoardInstance:
        return replace(self, **changes)


def nominal_instance(design: BoardDesign, offsets: bool = False) -> BoardInstance:
    """The board with the rounded nominal values; op-amp offsets and bias currents zero
    unless ``offsets`` (then the typical values of the part, as drawn on a datasheet)."""
    v = dict(design.values)
    v["R_S_top"] = v["R_S_bot"] = v.pop("R_S")
    amps = {}
    for role in ROLES:
        amp = opamp.get_opamp(role_part(design, role)).at_temperature(design.spec.temperature)
        amps[role] = amp if offsets else amp.replace(vos=0.0, ib=0.0, ios=0.0)
    return BoardInstance(values=v, v_set_top=design.spec.v_set, v_set_bot=design.spec.v_set,
                         v_force=design.force_sign * design.spec.v_force,
                         opamps=amps, temperature=design.spec.temperature,
                         rails=design.spec.rails)


def role_part(design: BoardDesign, role: str) -> str:
    """The op-amp part of ``role``: the servos (``st``, ``sb``) use ``spec.servo_opamp``,
    the integrator and the Bessel buffer ``spec.opamp``."""
    return design.spec.servo_opamp if role in ("st", "sb") else design.spec.opamp


@dataclass(frozen=True)
class BoardDeck:
    """A deck with the interface :func:`analogue.circuit.simulate.run_decks` expects."""

    text: str
    vectors: dict
    to_model_v: float
    to_model_x: float
    time_scale: float
    seed: int
    replicas: int
    sha256: str
    noise_files: tuple
    noise_dt: float = 0.0
    to_model_noise: float = 1.0
    t_offset: float = 0.0


_n = checks.spice_number  # a deck number: _n(name, value)

# The bench start (issue 21): R_IC across C through the reset switch and from the IC voltage
# into the virtual ground through the IC switch.  R_IC C = 100 us; the switches stay closed
# for RESET_TIME = 20 R_IC C (settled to e^-20) with the friction disabled.  10 kOhm keeps the
# integrator's output current at 1 mA for a 10 V start (OPA2140: 20 mA guaranteed limit in
# the macromodel's worst set).
R_IC = 10e3
RESET_TIME = 2e-3


def ic_voltage(design: BoardDesign, v0: float, v_force: float, values: dict | None = None) -> float:
    """The IC voltage that puts the integrator output at ``-kappa v0`` during reset: with
    both switches closed (on-resistance ``r_on``) the output settles at
    ``-(V_IC/(R_IC + r_on) + V_F/R_F) (R_IC + r_on || R)``, the viscous resistor ``R`` in
    parallel with the reset branch and the force current still flowing."""
    v = values or design.values
    r_branch = R_IC + friction.SWITCH_RON
    r_fb = 1.0 / (1.0 / r_branch + 1.0 / v["R"])
    i_f = v_force / v["R_F"] if np.isfinite(v["R_F"]) else 0.0
    return r_branch * (design.kappa * float(v0) / r_fb - i_f)


def build_board_deck(design: BoardDesign, board: BoardInstance, *, v0, t_end: float,
                     sample_dt: float, seed: int, noise_dir, first_replica: int = 0,
                     reltol: float = 1e-4, save_all: bool = False,
                     friction_kind: str = "bridge", ota: dict | None = None,
                     noise_off: bool = False, vendor: tuple | None = None,
                     start: str = "ic") -> BoardDeck:
    """Deck for ``len(v0)`` replicas of ``board`` started at ``v0`` (model units).

    Replica ``j`` is driven by the DAC sequence ``(seed, first_replica + j)``
    (:func:`analogue.board.noise_chain.dac_sequence`), written to ``noise_dir`` (created).
    ``save_all``: save every node (for the rails check).  ``friction_kind``: ``"bridge"`` or
    ``"ota"`` (then ``ota`` = dict(i_abc, k, vos, asymmetry)).  ``noise_off``: the DAC stays
    at mid-scale (0 V; calibration runs).  ``vendor``: ``(path, subckt)`` of an op-amp model the
    user downloaded (validated by :func:`analogue.board.opamp.vendor_model_path`, pins in+ in-
    V+ V- out); every op-amp of the board then uses it, so it must be a part whose input
    common-mode range reaches ``v_set`` from both rails (the servos; an OPA2140 model makes the
    sourcing servo's gain collapse at V+ - 3.5 V, as the real part would).  ngspice runs here refuse ``.include``
    (:func:`analogue.circuit.ngspice.run_deck`), so the validated file's text is inlined into the
    deck built on the user's machine (it is never part of this repository).

    ``start``: ``"ic"`` sets the initial velocities with ``.ic`` (the integrator held through the
    operating point; what the Monte Carlo runs); ``"reset"`` starts them as the bench does
    (issue 21): for ``RESET_TIME`` the reset switch closes ``R_IC`` across ``C``, the IC switch
    feeds the IC voltage (:func:`ic_voltage`, a DAQ output) through ``R_IC`` into the virtual
    ground, the friction enable is low and the noise DAC at mid-scale; at ``RESET_TIME`` both
    switches open, the enable goes high and the DAC sequence starts.  The deck's time axis then
    runs to ``RESET_TIME + t_end`` (:attr:`BoardDeck.t_offset`).
    """
    from pathlib import Path
    if not isinstance(design, BoardDesign):
        raise TypeError(f"design must be a BoardDesign, got {type(design).__name__}")
    if not isinstance(board, BoardInstance):
        raise TypeError(f"board must be a BoardInstance, got {type(board).__name__}")
    if start not in ("ic", "reset"):
        raise ValueError(f"start must be 'ic' or 'reset', got {start!r}")
    if friction_kind not in ("bridge", "ota"):
        raise ValueError(f"friction_kind must be 'bridge' or 'ota', got {friction_kind!r}")
    v0 = np.atleast_1d(np.asarray(v0, dtype=float))
    if v0.ndim != 1 or v0.size < 1 or not np.all(np.isfinite(v0)):
        raise ValueError("v0 must be a non-empty 1-D array of finite velocities")
    if np.max(np.abs(v0)) * design.kappa > design.spec.machine_unit * (1 + 1e-9):
        raise ValueError(f"v0: |v0| up to {np.max(np.abs(v0)):.3g} exceeds the machine unit "
                         f"({design.spec.machine_unit / design.kappa:.3g} at kappa={design.kappa:.3g} V)")
    t_end = checks.positive("t_end", t_end)
    sample_dt = checks.positive("sample_dt", sample_dt)
    theta, ts = design.theta, design.noise_ts
    n_samples = int(np.ceil(t_end * theta / ts)) + 2
    noise_dir = Path(noise_dir)
    noise_dir.mkdir(parents=True, exist_ok=True)
    part = get_part(design.spec.diode)
    b = board
    temp_k = b.temperature + 273.15

    lines = [f"board {checks.identifier('opamp', design.spec.opamp)} {part.name}",
             (f"* analogue board deck: kappa={_n('kappa', design.kappa)} V/unit theta={_n('theta', theta)} s "
             f"TS={_n('ts', ts)} s seed={int(seed)}")]
    include = None
    if vendor is not None:
        if not (isinstance(vendor, tuple) and len(vendor) == 2):
            raise TypeError("vendor must be a tuple (path, subckt)")
        vpath = opamp.vendor_model_path(vendor[0], vendor[1])
        include = f"* vendor op-amp model inlined from {vpath}\n" + vpath.read_text(errors="replace").strip()
        for role in ROLES:
            lines += [f".subckt opa_{role} inp inn vcc vee out",
                      f"X1 inp inn vcc vee out {vendor[1]}", f".ends opa_{role}"]
    else:
        for role in ROLES:
            lines.append(opamp.subcircuit(b.opamps[role], f"opa_{role}", rails=b.rails))
    dmodels = [f"dbr{k}" for k in range(4)]
    for name, scale in zip(dmodels, b.diode_is):
        lines.append(friction.diode_model_line(name, part, is_scale=scale))
    lines += list(friction.mosfet_models(b.mosfet_vto)) + list(friction.SWITCH_MODELS)
    lines += [f"Vcc vcc 0 dc {_n('rails', b.rails)}", f"Vee vee 0 dc {_n('rails', -b.rails)}",
              f"Vf f 0 dc {_n('v_force', b.v_force)}"]
    t0 = RESET_TIME if start == "reset" else 0.0
    logic = 5.0 if b.enable else 0.0
    if start == "reset":
        # reset/IC switches closed and enable low until t0, then released within 100 ns
        edge = t0 + 100e-9
        lines += [f"Vsr sr 0 pwl(0 5 {_n('t0', t0)} 5 {_n('edge', edge)} 0)",
                  f"Ven en 0 pwl(0 0 {_n('t0', t0)} 0 {_n('edge', edge)} {_n('logic', logic)})"]

    files, ic = [], []
    val_ = b.values
    for j in range(v0.size):
        r = first_replica + j
        sj, o = f"sj{j}", f"o{j}"
        lines += [f"XU{j} 0 {sj} vcc vee {o} opa_int",
                  f"C{j}m {sj} {o} {_n('C', val_['C'])}",
                  f"R{j}v {sj} {o} {_n('R', val_['R'])}"]
        if friction_kind == "bridge":
            lines += friction.bridge_lines(
                f"b{j}", sj, o, part=part, diode_models=dmodels, r_s_top=val_["R_S_top"],
                r_s_bot=val_["R_S_bot"], v_set_top=b.v_set_top, v_set_bot=b.v_set_bot,
                opamp_top="opa_st", opamp_bot="opa_sb",
                enable="en" if start == "reset" else bool(b.enable))
        else:
            lines += friction.ota_lines(f"b{j}", sj, o, temperature_k=temp_k, **(ota or {}))
        if np.isfinite(val_["R_F"]):
            lines.append(f"R{j}f f {sj} {_n('R_F', val_['R_F'])}")
        volts = (np.zeros(n_samples) if noise_off
                 else noise_chain.dac_sequence(design, seed, r, n_samples))
        path, sha = noise_chain.write_dac_file(noise_dir, volts, ts)
        files.append(str(path))
        lines += noise_chain.dac_lines(f"n{j}", f"d{j}", path, sha, time_offset=t0)
        lines += noise_chain.bessel_lines(f"n{j}", f"d{j}", f"bo{j}", design, "opa_bf", val_)
        if "C_AC" in val_:
            lines += [f"C{j}ac bo{j} ac{j} {_n('C_AC', val_['C_AC'])}",
                      f"R{j}n ac{j} {sj} {_n('R_N', val_['R_N'])}"]
        else:
            lines.append(f"R{j}n bo{j} {sj} {_n('R_N', val_['R_N'])}")
        spring = "R_K" in val_
        if spring:
            # position integrator (reset = the .ic below) and inverter; spring current
            # -V(x)/R_K into the virtual ground
            lines += [f"XU{j}x 0 sx{j} vcc vee ox{j} opa_int",
                      f"R{j}x {o} sx{j} {_n('R_X', val_['R_X'])}",
                      f"C{j}x sx{j} ox{j} {_n('C_X', val_['C_X'])}",
                      f"XU{j}i 0 si{j} vcc vee oi{j} opa_int",
                      f"R{j}i1 ox{j} si{j} {_n('R_I', val_['R_I'])}",
                      f"R{j}i2 si{j} oi{j} {_n('R_I', val_['R_I'])}",
                      f"R{j}k oi{j} {sj} {_n('R_K', val_['R_K'])}"]
            vx = design.x_volts * design.model.x0
            ic.append(f"v(ox{j})={_n('vx', vx)} v(xu{j}x.g)={_n('vx', vx)} v(sx{j})=0 "
                      f"v(oi{j})={_n('vx', -vx)} v(xu{j}i.g)={_n('vx', -vx)} v(si{j})=0")
        vo = -design.kappa * v0[j]
        if start == "reset":
            v_ic = ic_voltage(design, v0[j], b.v_force, values=val_)
            lines += [f"Vic{j} ic{j} 0 dc {_n('v_ic', v_ic)}",
                      f"S{j}r {o} {j}rr sr 0 swno", f"R{j}r {j}rr {sj} {_n('R_IC', R_IC)}",
                      f"R{j}i ic{j} {j}ri {_n('R_IC', R_IC)}", f"S{j}i {j}ri {sj} sr 0 swno"]
            continue
        # the virtual ground's own equilibrium, -vos - V(out)/a0: holding it at 0 through the
        # operating point would, on a board with the optional AC-coupling capacitor, charge it
        # to the offset, which then bleeds a current vos/R_N into sj for ~R_N C_AC = 170
        # tau_m (measured: 0.5 uA, a force error of 0.01 for vos = 4 mV)
        amp = b.opamps["int"]
        v_sj = -amp.vos - vo / amp.a0
        ic.append(f"v({o})={_n('vo', vo)} v(xu{j}.g)={_n('vo', vo)} v({sj})={_n('v_sj', v_sj)}")
    if ic:
        lines.append(".ic " + " ".join(ic))
    lines.append(f".options reltol={_n('reltol', reltol)} abstol=1e-12 vntol=1e-7 method=gear "
                 f"temp={_n('temperature', b.temperature)} tnom=27")
    spring = "R_K" in val_
    v_names = [f"v(o{j})" for j in range(v0.size)]
    x_names = [f"v(ox{j})" for j in range(v0.size)] if spring else None
    vectors = {"v": v_names, "x": x_names}
    if not save_all:
        lines.append(".save " + " ".join(v_names + (x_names or [])))
    # two steps per DAC hold where the noise runs; noise-off decks (calibration steps) only
    # need the sampling grid
    max_step = ts / 2.0 if not noise_off else max(ts / 2.0, sample_dt * theta / 2.0)
    lines.append(f".tran {_n('tstep', sample_dt * theta)} {_n('tstop', t_end * theta + t0)} 0 "
                 f"{_n('max_step', max_step)}")
    lines.append(".end")
    text = "\n".join(lines) + "\n"
    if include is not None:   # the validated vendor text (no .control/.include/shell lines)
        head, rest = text.split("\n", 1)
        text = f"{head}\n{include}\n{rest}"
    if opamp.forbidden_deck_lines(text):
        raise ValueError("the board deck contains a forbidden line (.control/.exec/shell/.include/.lib)")
    return BoardDeck(text=text, vectors=vectors, to_model_v=design.to_model_v,
                     to_model_x=1.0 / design.x_volts if spring else 1.0,
                     time_scale=theta, seed=int(seed), replicas=int(v0.size),
                     sha256=hashlib.sha256(text.encode()).hexdigest(), noise_files=tuple(files),
                     noise_dt=0.0, t_offset=t0)
