"""SPICE decks for an ensemble of independent stick-slip replicas.

One replica ``i`` (subcircuit ``replica``, pins ``v<i> x<i> nz<i>``):

- node ``v<i>`` (voltage = kappa * velocity): ``C`` and ``R`` to ground, the force current
  ``I_F`` into the node, the noise current ``noise_gain * V(nz<i>)`` into the node, and the
  Coulomb element from ``v<i>`` to ground (subcircuit ``bridge``: four diodes around the
  current source ``I_Delta``, or a B-source ``I_Delta tanh(V/eps_V)`` / ``I_Delta sgn(V)``;
  none at all for Delta = 0, see :mod:`analogue.circuit.mapping`);
- node ``nz<i>``: a ``trrandom`` Gaussian voltage, held for ``TS``, equal to the velocity noise
  in model units (saved: the raw file then holds the very noise that drove the replica, so an
  SDE integrator can be fed the same sequence; it costs one node and no extra breakpoints);
- node ``x<i>``: the integrator ``g_x V(v<i>)`` into ``C_x`` (V(x) = 1 V per unit position).

Model family (issue 9; see :mod:`analogue.circuit.nonlinear` and :mod:`analogue.circuit.shot`):

- cubic viscous law: a B-source ``g3 V^3`` or the subcircuit ``cubicnet`` (diode-resistor
  breakpoint branches, diode model ``dcubic``) from ``v<i>`` to ground;
- Stribeck law: the friction element's amplitude becomes ``Delta(V)`` (B-source expression;
  inside the diode bridge, its current source becomes a B-source of the terminal voltage);
- spring: the inductor ``Lspring`` (initial current = spring force at x0) in series with its
  resistance ``R_L`` and a 0 V sense source from ``v<i>`` to ground; a CCVS turns the sensed
  current into node ``xs<i>`` = the spring's position in model units (1 V per unit), saved as
  ``vectors["x_spring"]``; the integrator node ``x<i>`` stays (it carries the work);
- shot noise: a top-level ``pwl`` current source ``Ishot<i>`` into ``v<i>`` (seeded kicks drawn
  in numpy; ``Deck.kicks`` holds them);
- gamma = inf: no ``trrandom`` source, no ``nz<i>`` node;
- coloured noise (:class:`analogue.variants.OrnsteinUhlenbeck`): the ``trrandom`` source
  low-pass filtered by ``R_ou``/``C_ou`` into node ``ou`` inside the replica, which drives the
  noise current.  Each noise kind adds its own elements (``Noise.replica_elements``).

Initial conditions by ``.ic`` with ``.tran ... uic`` (no operating point is needed, so the
integrator node needs no leak resistor and has no bias); the bridge's inner nodes get
consistent DC values in the ``.ic`` line as well.  ``trrandom`` with
``.options seed=N`` is reproducible in ngspice 39 (``trnoise`` is not).
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np
from PySpice.Spice.Netlist import Circuit, SubCircuit

from .. import checks
from .mapping import CircuitMapping
from .nonlinear import DiodeNetwork, branch_current
from .parts import DiodePart, bridge_node_voltages
from .shot import deck_kicks, pulse_pwl

__all__ = ["Deck", "build_deck", "replica_subcircuit", "bridge_subcircuit"]

_MODEL_NAME = "dcoulomb"
_CUBIC_MODEL = "dcubic"
_SEED_MAX = 2**31 - 1


@dataclass(frozen=True)
class Deck:
    """A complete ngspice deck and how to read its raw file back into model units.

    ``vectors``: {"v": [...], "x": [...], "noise": [...]} raw-file vector names per replica
    (lower case).  Model value = raw value * ``to_model_v`` / ``to_model_x`` /
    ``to_model_noise``; model time = raw time / ``time_scale``.
    """

    text: str
    vectors: dict
    to_model_v: float
    to_model_x: float
    time_scale: float
    seed: int
    replicas: int
    sha256: str
    to_model_noise: float = 1.0
    noise_dt: float = 0.0
    t_end: float = 0.0
    sample_dt: float = 0.0
    # shot noise: per replica (effective kick times = pulse centres, signed jumps), model units
    kicks: tuple = ()
    x_spring_initial: float = 0.0  # value of vectors["x_spring"] at t = 0 (x0)


def _bridge_part(mapping: CircuitMapping) -> DiodePart:
    """The bridge's diode (every diode-bridge mapping has one: an ideal or a vendor part)."""
    if mapping.part is None:
        raise ValueError("the mapping has no diode part (no diode-bridge Coulomb element)")
    return mapping.part


def _cubic_network(mapping: CircuitMapping) -> DiodeNetwork:
    """The cubic breakpoint network (every diode-network cubic element has one)."""
    if mapping.cubic_network is None:
        raise ValueError("the mapping has no cubic diode network (cubic element is not "
                         "'diode-network')")
    return mapping.cubic_network


_spice_value = checks.spice_number  # a deck number: _spice_value(name, value)


def bridge_subcircuit(mapping: CircuitMapping) -> SubCircuit:
    """Four diodes around ``I_Delta`` (current circulates v -> D1 -> p -> I -> n -> D4 -> 0 and
    0 -> D2 -> p -> I -> n -> D3 -> v): terminal current ``I_Delta tanh(V/(2 N V_T))``."""
    sub = SubCircuit("bridge", "t")
    sub.D("1", "t", "p", model=_MODEL_NAME)
    sub.D("2", sub.gnd, "p", model=_MODEL_NAME)
    sub.D("3", "n", "t", model=_MODEL_NAME)
    sub.D("4", "n", sub.gnd, model=_MODEL_NAME)
    # the friction law's amplitude source (Stribeck: a B-source following Delta(V_t))
    mapping.model.friction.bridge_source(sub, mapping, _spice_value)
    part = _bridge_part(mapping)
    if part.rp:
        # The vendor models' parallel resistor across each diode.
        sub.R("p1", "t", "p", _spice_value("rp", part.rp))
        sub.R("p2", sub.gnd, "p", _spice_value("rp", part.rp))
        sub.R("p3", "n", "t", _spice_value("rp", part.rp))
        sub.R("p4", "n", sub.gnd, _spice_value("rp", part.rp))
    return sub


def _friction_expr(m: CircuitMapping, law: str, node: str = "v") -> str:
    """The Coulomb element's B-source current: the friction law's amplitude factor
    (``I_Delta``, or Stribeck's ``(I_Delta + I_s exp(-|V|/V_s))``) times tanh or sgn."""
    amp = m.model.friction.amplitude_factor(m, node, _spice_value)
    if law == "tanh":
        return f"{amp}*tanh(V({node})/{_spice_value('eps_V', m.eps_volts)})"
    return f"{amp}*sgn(V({node}))"


def cubic_subcircuit(mapping: CircuitMapping) -> SubCircuit:
    """The breakpoint network (pin t): per branch j, ``t -- R -- D -- +E_j`` (conducts for
    V > E_j + drop) and its mirror ``t -- R -- D(reversed) -- -E_j``."""
    net = _cubic_network(mapping)
    sub = SubCircuit("cubicnet", "t")
    for j, (r, e) in enumerate(zip(net.resistors, net.biases)):
        sub.R(f"{j}p", "t", f"a{j}", _spice_value(f"R_cubic{j}", r))
        sub.D(f"{j}p", f"a{j}", f"b{j}", model=_CUBIC_MODEL)
        sub.V(f"{j}p", f"b{j}", sub.gnd, _spice_value(f"E_cubic{j}", e))
        sub.R(f"{j}n", "t", f"c{j}", _spice_value(f"R_cubic{j}", r))
        sub.D(f"{j}n", f"d{j}", f"c{j}", model=_CUBIC_MODEL)
        sub.V(f"{j}n", f"d{j}", sub.gnd, _spice_value(f"E_cubic{j}", -e))
    return sub


def replica_pins(mapping: CircuitMapping) -> tuple:
    """Pins of the replica subcircuit: v, x, then nz (Gaussian noise) and xs (spring) when
    present."""
    pins = ["v", "x"]
    if mapping.gaussian_noise:
        pins.append("nz")
    if mapping.inductance > 0:
        pins.append("xs")
    return tuple(pins)


def replica_subcircuit(mapping: CircuitMapping) -> SubCircuit:
    """One replica: pins :func:`replica_pins` (v, x, nz for the paper's model)."""
    m = mapping
    sub = SubCircuit("replica", *replica_pins(m))
    sub.C("m", "v", sub.gnd, _spice_value("C", m.capacitance))
    sub.R("visc", "v", sub.gnd, _spice_value("R", m.resistance))
    sub.I("force", sub.gnd, "v", _spice_value("I_F", m.i_force))  # current flows 0 -> source -> v
    # the noise's own element (analogue.variants: white trrandom source, none, or filtered)
    m.model.noise_kind.replica_elements(sub, m, _spice_value)
    element = m.coulomb_element
    if element == "diode-bridge":
        sub.X("coulomb", "bridge", "v")
    elif element == "behavioural":
        sub.BehavioralSource("coulomb", "v", sub.gnd, current_expression=_friction_expr(m, "tanh"))
    elif element == "behavioural-sgn":
        sub.BehavioralSource("coulomb", "v", sub.gnd, current_expression=_friction_expr(m, "sgn"))
    # the friction law's own elements beyond the Coulomb element (the cubic conductance) and
    # the restoring force's (the spring's inductor): analogue.variants
    m.model.friction.replica_elements(sub, m, _spice_value)
    m.model.restoring.replica_elements(sub, m, _spice_value)
    sub.VCCS("x", sub.gnd, "x", "v", sub.gnd, _spice_value("g_x", m.g_x))
    sub.C("x", "x", sub.gnd, _spice_value("C_x", m.cap_x))
    return sub


def _pwl_lines(name: str, node: str, times, currents) -> list[str]:
    """A pwl current source into ``node``, 6 pairs per continuation line."""
    pairs = [f"{_spice_value('pwl time', t)} {_spice_value('pwl current', i)}" for t, i in zip(times, currents)]
    out = [f"I{name} 0 {node} pwl("]
    for k in range(0, len(pairs), 6):
        out.append("+ " + " ".join(pairs[k:k + 6]))
    out.append("+ )")
    return out


def build_deck(mapping: CircuitMapping, *, replicas: int, v0, t_end: float, seed: int,
               sample_dt: float, title: str = "analogue") -> Deck:
    """The ngspice deck for ``replicas`` independent replicas started at ``v0`` (model units).

    ``t_end`` and ``sample_dt`` are in model time units; the deck asks for
    ``.tran sample_dt*theta t_end*theta 0 max_step*theta uic`` and saves only
    ``v(v<i>)``, ``v(x<i>)`` and ``v(nz<i>)``.  No ``.control`` block: run it as
    ``ngspice -b -r out.raw deck.cir``.
    """
    if not isinstance(mapping, CircuitMapping):
        raise ValueError(f"mapping must be a CircuitMapping, got {type(mapping).__name__}")
    title = checks.identifier("title", title)
    replicas = checks.integer("replicas", replicas, minimum=1, maximum=100_000)
    seed = checks.integer("seed", seed, minimum=0, maximum=_SEED_MAX)
    t_end = checks.positive("t_end", t_end)
    sample_dt = checks.positive("sample_dt", sample_dt)
    if not sample_dt <= t_end:
        raise ValueError(f"sample_dt must be in (0, t_end={t_end}], got {sample_dt!r}")
    try:
        v0 = np.asarray(v0, dtype=float)
    except (TypeError, ValueError):
        raise ValueError("v0 must be an array of finite floats of shape (replicas,)") from None
    if v0.shape != (replicas,):
        raise ValueError(f"v0 must have shape (replicas,) = ({replicas},), got {v0.shape}")
    if not np.all(np.isfinite(v0)):
        raise ValueError("v0 must be finite")
    part = mapping.part
    if part is not None and not part.ideal:
        vmax = mapping.kappa * float(np.max(np.abs(v0)))
        if vmax >= part.max_reverse_voltage:
            raise ValueError(f"v0: |v0| up to {np.max(np.abs(v0)):.3g} means {vmax:.3g} V (volts_per_velocity="
                             f"{mapping.kappa:.3g} V), at or above the {part.name} reverse-voltage rating "
                             f"{part.max_reverse_voltage:.3g} V; keep |v0| below "
                             f"{part.max_reverse_voltage / mapping.kappa:.3g}, raise smoothing (a real "
                             f"diode's kappa is 2 N V_T/(smoothing sqrt(tau_m/gamma))) or use diode='ideal'")

    spec, theta = mapping.spec, mapping.theta
    max_step = spec.max_step if spec.max_step is not None else mapping.noise_dt
    if spec.max_step is None and mapping.inductance > 0:
        # gear (BDF2) damps an oscillator numerically when its steps are long against the
        # period: a Coulomb ring-down (tau_m = 1000, period 2 pi) with steps up to noise_dt =
        # 10 lost 0.005 more swing per half period than with steps <= 0.01; cap at period/200.
        max_step = min(max_step, 2.0 * np.pi / np.sqrt(mapping.model.spring) / 200.0)
    max_step = min(max_step, t_end)

    circuit = Circuit(title)
    bridge = mapping.coulomb_element == "diode-bridge"
    if bridge:
        circuit.model(_MODEL_NAME, "D", **{k: _spice_value(k, v)
                                           for k, v in _bridge_part(mapping).model})
        circuit.subcircuit(bridge_subcircuit(mapping))
    net = mapping.cubic_network
    if net is not None:
        circuit.model(_CUBIC_MODEL, "D", **{k: _spice_value(k, v) for k, v in net.part.model})
        circuit.subcircuit(cubic_subcircuit(mapping))
    circuit.subcircuit(replica_subcircuit(mapping))
    pins = replica_pins(mapping)
    for i in range(replicas):
        circuit.X(f"r{i}", "replica", *[f"{p}{i}" for p in pins])

    lines = [str(circuit).rstrip("\n")]
    kicks: tuple = ()
    if mapping.shot_charge > 0:
        # seeded kicks (analogue.circuit.shot): flat-topped pulses of area C kappa z, width w
        w = mapping.shot_width
        starts = deck_kicks(mapping.model, t_end, seed, replicas)
        for i, (t_k, z_k) in enumerate(starts):
            times, amps = pulse_pwl(t_k * theta, mapping.shot_charge * z_k, w * theta)
            lines += _pwl_lines(f"shot{i}", f"v{i}", times, amps)
        kicks = tuple((t_k + 0.5 * w, z_k) for t_k, z_k in starts)
    volts = mapping.kappa * v0
    ic = [f"v(v{i})={_spice_value('v0', volts[i])} v(x{i})=0" for i in range(replicas)]
    if bridge:
        # uic skips the operating point, so the bridge's inner nodes need consistent starting
        # values too (else D1 starts forward biased by the whole of V and the first step fails).
        vp, vn = mapping.model.friction.bridge_node_voltages(
            mapping, volts, lambda i, v: bridge_node_voltages(_bridge_part(mapping), i, v))
        ic += [f"v(xr{i}.xcoulomb.p)={_spice_value('ic', vp[i])} "
               f"v(xr{i}.xcoulomb.n)={_spice_value('ic', vn[i])}"
               for i in range(replicas)]
    if net is not None:
        # consistent inner nodes of the breakpoint branches: V - R i (and V + R i mirrored)
        for i in range(replicas):
            for j, (r, e) in enumerate(zip(net.resistors, net.biases)):
                ip = float(branch_current(net.part, r, e, volts[i]))
                im = float(branch_current(net.part, r, e, -volts[i]))
                ic.append(f"v(xr{i}.xcubic.a{j})={_spice_value('ic', volts[i] - r * ip)} "
                          f"v(xr{i}.xcubic.c{j})={_spice_value('ic', volts[i] + r * im)}")
    lines.append(".ic " + " ".join(ic))
    lines.append(f".options seed={seed} reltol={_spice_value('reltol', mapping.reltol)} "
                 f"abstol={_spice_value('abstol', spec.abstol)} vntol={_spice_value('vntol', mapping.vntol)} "
                 f"trtol={_spice_value('trtol', mapping.trtol)} method={mapping.method} "
                 f"temp=27 tnom=27")
    vectors = {"v": [f"v(v{i})" for i in range(replicas)],
               "x": [f"v(x{i})" for i in range(replicas)],
               "noise": [f"v(nz{i})" for i in range(replicas)] if mapping.gaussian_noise else []}
    saved = vectors["v"] + vectors["x"] + vectors["noise"]
    if mapping.inductance > 0:
        vectors["x_spring"] = [f"v(xs{i})" for i in range(replicas)]
        saved += vectors["x_spring"]
    lines.append(".save " + " ".join(saved))
    lines.append(f".tran {_spice_value('tstep', sample_dt * theta)} {_spice_value('tstop', t_end * theta)} 0 "
                 f"{_spice_value('tmax', max_step * theta)} uic")
    lines.append(".end")
    text = "\n".join(lines) + "\n"
    return Deck(text=text, vectors=vectors, to_model_v=mapping.to_model_v,
                to_model_x=mapping.to_model_x, time_scale=theta, seed=seed, replicas=replicas,
                sha256=hashlib.sha256(text.encode()).hexdigest(), to_model_noise=1.0,
                noise_dt=mapping.noise_dt if mapping.gaussian_noise else 0.0, t_end=t_end,
                sample_dt=sample_dt, kicks=kicks, x_spring_initial=float(mapping.model.x0))


def bridge_dc_deck(mapping: CircuitMapping, v_max: float, points: int = 201) -> str:
    """A ``.dc`` deck sweeping the voltage across one Coulomb element from ``-v_max`` to
    ``v_max`` volts (source ``vs``; the element's current is ``-i(vs)``): checks the friction
    law of the bridge (or B-source) directly."""
    if not isinstance(mapping, CircuitMapping):
        raise ValueError(f"mapping must be a CircuitMapping, got {type(mapping).__name__}")
    v_max = checks.positive("v_max", v_max)
    points = checks.integer("points", points, minimum=3, maximum=100_001)
    element = mapping.coulomb_element
    if element is None:
        raise ValueError("mapping has no Coulomb element to sweep (Delta = 0: the circuit is built "
                         "without one); map a model with Delta > 0")
    circuit = Circuit("bridgedc")
    if element == "diode-bridge":
        circuit.model(_MODEL_NAME, "D", **{k: _spice_value(k, v) for k, v in _bridge_part(mapping).model})
        circuit.subcircuit(bridge_subcircuit(mapping))
        circuit.X("coulomb", "bridge", "t")
    elif element == "behavioural":
        circuit.BehavioralSource("coulomb", "t", circuit.gnd,
                                 current_expression=_friction_expr(mapping, "tanh", "t"))
    else:
        circuit.BehavioralSource("coulomb", "t", circuit.gnd,
                                 current_expression=_friction_expr(mapping, "sgn", "t"))
    circuit.V("s", "t", circuit.gnd, "dc 0")
    step = 2.0 * v_max / (points - 1)
    lines = [str(circuit).rstrip("\n"),
             # tight tolerances: the test compares with the closed form to 1e-5 of I_Delta
             ".options reltol=1e-9 abstol=1e-18 vntol=1e-12 temp=27 tnom=27",
             f".dc vs {_spice_value('v_max', -v_max)} {_spice_value('dc stop', v_max + 0.5 * step)} "
             f"{_spice_value('dc step', step)}", ".end"]
    return "\n".join(lines) + "\n"


def cubic_dc_deck(mapping: CircuitMapping, v_max: float, points: int = 201) -> str:
    """A ``.dc`` deck sweeping the voltage across the cubic conductance (B-source or diode
    network) from ``-v_max`` to ``v_max`` volts; the element's current is ``-i(vs)``."""
    if not isinstance(mapping, CircuitMapping):
        raise ValueError(f"mapping must be a CircuitMapping, got {type(mapping).__name__}")
    v_max = checks.positive("v_max", v_max)
    points = checks.integer("points", points, minimum=3, maximum=100_001)
    if mapping.cubic_element is None:
        raise ValueError("mapping has no cubic element to sweep (cubic = 0); map a model with cubic > 0")
    circuit = Circuit("cubicdc")
    if mapping.cubic_element == "diode-network":
        circuit.model(_CUBIC_MODEL, "D", **{k: _spice_value(k, v)
                                              for k, v in _cubic_network(mapping).part.model})
        circuit.subcircuit(cubic_subcircuit(mapping))
        circuit.X("cubic", "cubicnet", "t")
    else:
        circuit.BehavioralSource("cubic", "t", circuit.gnd,
                                 current_expression=f"{_spice_value('g3', mapping.g3)}*V(t)*V(t)*V(t)")
    circuit.V("s", "t", circuit.gnd, "dc 0")
    step = 2.0 * v_max / (points - 1)
    lines = [str(circuit).rstrip("\n"),
             ".options reltol=1e-9 abstol=1e-18 vntol=1e-12 temp=27 tnom=27",
             f".dc vs {_spice_value('v_max', -v_max)} {_spice_value('dc stop', v_max + 0.5 * step)} "
             f"{_spice_value('dc step', step)}", ".end"]
    return "\n".join(lines) + "\n"
