"""Scaling the model onto a buildable board: rails, machine unit, E-series parts.

The board is an inverting integrator (op-amp U1, virtual ground ``sj``) whose feedback holds
the mass capacitor ``C``, the viscous resistor ``R`` and the Coulomb element (a diode bridge fed
by two rail-referenced current sources, :mod:`analogue.board.friction`).  With
``u = V(sj) - V(out)`` (the capacitor voltage; the output is ``-u``) Kirchhoff at ``sj`` is

    C du/dt_c = -u/R - I_0 tanh(u/w) + V_F/R_F + V_n(t_c)/R_N,

the paper's eq. (4) with ``u = kappa v`` and ``t_c = theta t`` (compare
:mod:`analogue.circuit.mapping`):

    tau_m = R C/theta,   Delta = theta I_0/(C kappa),   a = theta V_F/(R_F C kappa),
    1/gamma = theta D_I/(C kappa)^2,   D_I = (s_dac/R_N)^2 TS/2,   epsilon = w/kappa.

Scaling (issue 13): +-15 V rails, machine unit 10 V, ``kappa`` chosen so that the stationary
standard deviation is about 1 V and the largest velocity the experiment needs (initial
velocities, the stationary range where p_s ~ exp(-gamma U) has fallen by e^-32) stays inside
the machine unit.  Every resistor is rounded to E96 (1 %) or E24, capacitors to E12/E6; the
*rounded* values define the model the board really implements (:attr:`BoardDesign.realised`),
and the difference from the requested model enters the error budget term by term.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import eseries

from .. import checks
from ..circuit.mapping import stationary_range, stationary_std
from ..circuit.parts import get_part, thermal_voltage
from ..model import Model
from .opamp import get_opamp

__all__ = [
    "DIELECTRIC_ADVICE",
    "SERIES",
    "BoardDesign",
    "BoardSpec",
    "design_board",
    "round_to_series",
]

SERIES = {"E6": eseries.E6, "E12": eseries.E12, "E24": eseries.E24, "E96": eseries.E96,
          "E192": eseries.E192}
DIELECTRIC_ADVICE = (
    "C0G/NP0 ceramic (0 +- 30 ppm/K, no voltage coefficient, dielectric absorption < 0.1 %) or "
    "polypropylene film (-200 ppm/K, absorption ~0.01 %) for the mass and integrator capacitors. "
    "Not X7R/Y5V: their capacitance moves by 10-50 % with DC bias and 15 % over temperature and "
    "their dielectric absorption (~2.5 %) acts as a memory term in the velocity equation.")


def round_to_series(value: float, series: str) -> float:
    """Nearest value of the E-series ``series`` (``E6``...``E192``)."""
    if series not in SERIES:
        raise ValueError(f"series must be one of {sorted(SERIES)}, got {series!r}")
    value = checks.positive("value", value)
    return float(eseries.find_nearest(SERIES[series], value))


@dataclass(frozen=True)
class BoardSpec:
    """The experimentalist's choices (validated).

    rails: supply voltage (V, symmetric); machine_unit: full-scale signal (V); sigma_volts:
    target stationary standard deviation of the velocity node (V); kappa: volts per unit
    velocity (None: from sigma_volts and machine_unit); time_scale: seconds per model time unit;
    capacitance: mass capacitor (F, an E12 value); opamp: macromodel name of the integrator and
    the Bessel buffer (``OPA2140``, the default: its guaranteed 120 uV offset is inside the
    limit the observables set, 466 uV on the stick design,
    :func:`analogue.board.tolerance.offset_limit`; ``OPA2197``; ``TL072``, whose 10 mV is
    not; or their ``_worst`` sets);
    servo_opamp: the current sources' servos, whose inputs sit ``v_set`` from a rail (a
    rail-to-rail-input part: ``OPA2197``; a TL072's guaranteed range ends 4 V from the rails);
    diode: bridge diode (``1N4148``, ``BAT54``);
    v_set: the current sources' sense voltage (V, from a 2.5 V-class reference);
    v_force: magnitude of the force voltage (V); resistor_series / capacitor_series: E-series
    for rounding; dac_bits, dac_rms (V rms of the noise DAC, clip at dac_range), dac_range (V),
    noise_dt (hold time in model units; None: tau_m/800), bessel_fc (Bessel -3 dB frequency in
    units of the DAC sample rate), ac_corner (None, the default: no AC-coupling capacitor,
    R_N driven DC-coupled by the Bessel buffer; else the AC-coupling corner in units of
    1/tau_m: f_AC = ac_corner/(tau_m theta) Hz, time constant R_N C_AC = tau_m/(2 pi
    ac_corner) = 159 tau_m at 0.001); temperature: board temperature (C).

    No AC coupling by default (issue 21 item 6), measured on the stick design: a capacitor
    small enough to settle within the burn-in (R_N C_AC = burn-in/5 = 0.4 tau_m) leaves only
    0.29 of the OU velocity variance (ou_variance_factor; 0.17 at 0.2 tau_m); at 0.001 (R_N
    C_AC = 156 tau_m, the former default) its DC state never settles in a run (the bench
    needs 0.8 s after power-up) and it still removes 0.6 % of the variance (factor 0.9931
    against 0.9995 for the DAC hold and Bessel alone).  What it blocked, the DC offsets of the
    Bessel buffer and the integrator across R_N, is a constant force (vos_int - vos_bf)/R_N:
    0.019 in a per 3 mV (TL072 typical; 2e-4 per 30 uV, OPA2140 typical); calibration step 1
    measures it with
    the noise DAC at mid-scale (:mod:`analogue.board.calibration`), and the tolerance
    analysis carries it (:func:`analogue.board.tolerance.effective_model`).

    Noise defaults (issue 21): inside the bridge the velocity relaxes in epsilon/Delta = 0.03
    tau_m, so the noise must be white on that scale.  SDE pairs (coloured minus white on common
    increments, stick experiment, 256 replicas x 20 tau_m) measured the stick-fraction bias
    +0.023 at 100 DAC samples per tau_m with the Bessel corner at 0.25 of the DAC rate (the
    previous default), +0.0044 +- 0.0005 at 400 samples with the corner at 0.5 (1.3 standard
    errors of the full job's nominal run, 0.0034) and +0.0005 +- 0.0003 at 800 (0.15 se); the
    other observables' biases are below 0.5 se at 400 already.  At theta = 1 ms the DAC runs at
    800 kS/s (TS = 1.25 us, within a USB-6363's analogue outputs); a slower time scale (theta =
    4 ms) would cut I_0 to 8.5 uA, where the bridge's own leakage with the friction disabled
    (12 nA, measured) exceeds 1e-3 I_0.
    """

    rails: float = 15.0
    machine_unit: float = 10.0
    sigma_volts: float = 1.0
    kappa: float | None = None
    time_scale: float = 1e-3
    capacitance: float = 10e-9
    opamp: str = "OPA2140"
    servo_opamp: str = "OPA2197"
    diode: str = "1N4148"
    v_set: float = 2.5
    v_force: float = 2.5
    resistor_series: str = "E96"
    capacitor_series: str = "E12"
    dac_bits: int = 16
    dac_rms: float = 2.0
    dac_range: float = 10.0
    noise_dt: float | None = None
    bessel_fc: float = 0.5
    ac_corner: float | None = None
    temperature: float = 27.0

    def __post_init__(self):
        for name in ("rails", "machine_unit", "sigma_volts", "time_scale", "capacitance", "v_set",
                     "v_force", "dac_rms", "dac_range", "bessel_fc"):
            object.__setattr__(self, name, checks.positive(name, getattr(self, name)))
        for name in ("kappa", "noise_dt", "ac_corner"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, checks.positive(name, getattr(self, name)))
        object.__setattr__(self, "temperature", checks.finite("temperature", self.temperature))
        if not -40.0 <= self.temperature <= 125.0:
            raise ValueError(f"temperature must be in [-40, 125] C, got {self.temperature}")
        if not self.machine_unit < self.rails:
            raise ValueError(f"machine_unit must be below rails={self.rails} V, got {self.machine_unit}")
        if not self.dac_range <= self.rails:
            raise ValueError(f"dac_range must be <= rails={self.rails} V, got {self.dac_range}")
        if not self.dac_rms * 4.0 <= self.dac_range:
            raise ValueError(f"dac_rms must be <= dac_range/4 = {self.dac_range / 4} V (clipping), "
                             f"got {self.dac_rms}")
        if not self.bessel_fc <= 0.5:
            raise ValueError(f"bessel_fc must be in (0, 0.5] (fraction of the DAC rate), got {self.bessel_fc}")
        if self.ac_corner is not None and not self.ac_corner < 0.2:
            raise ValueError(f"ac_corner must be in (0, 0.2), got {self.ac_corner}")
        object.__setattr__(self, "dac_bits", checks.integer("dac_bits", self.dac_bits, minimum=8, maximum=24))
        for name, allowed in (("resistor_series", ("E24", "E96", "E192")),
                              ("capacitor_series", ("E6", "E12", "E24"))):
            if getattr(self, name) not in allowed:
                raise ValueError(f"{name} must be one of {allowed}, got {getattr(self, name)!r}")
        get_opamp(self.opamp)
        servo = get_opamp(self.servo_opamp)
        lo, hi = servo.guaranteed.common_mode_range(self.rails)
        if not (-self.rails + self.v_set > lo and self.rails - self.v_set < hi):
            raise ValueError(f"servo_opamp {self.servo_opamp!r}: its guaranteed input common-mode "
                             f"range [{lo:g}, {hi:g}] V does not hold the servo inputs at "
                             f"+-{self.rails - self.v_set:g} V (rails - v_set); choose a "
                             f"rail-to-rail-input part (OPA2197) or v_set > {self.rails - hi:g} V")
        get_part(self.diode)

    def replace(self, **changes) -> BoardSpec:
        return replace(self, **changes)

    def as_dict(self) -> dict:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


@dataclass(frozen=True)
class BoardDesign:
    """Component values (SI) of the board, ideal and rounded, and what they implement.

    ``ideal`` are the exact values the mapping asks for; ``values`` the E-series ones used on
    the board; ``realised`` the model the rounded board implements (with the bridge's tanh
    width ``epsilon``); ``rounding`` the relative error of every rounded value.
    """

    model: Model
    spec: BoardSpec
    kappa: float
    theta: float
    eps_volts: float
    noise_ts: float
    ideal: dict
    values: dict
    rounding: dict
    realised: Model
    v_max: float
    notes: tuple = field(default_factory=tuple)

    @property
    def to_model_v(self) -> float:
        """Model velocity per volt of the integrator output (the output is -kappa v)."""
        return -1.0 / self.kappa

    @property
    def noise_dt(self) -> float:
        return self.noise_ts / self.theta

    @property
    def x_volts(self) -> float:
        """Volts per unit position at the position integrator (spring boards)."""
        return self.kappa * self.theta / (self.values["R_X"] * self.values["C_X"])

    @property
    def i_delta(self) -> float:
        """Current of each bridge source, v_set / R_S."""
        return self.spec.v_set / self.values["R_S"]

    @property
    def force_sign(self) -> float:
        return 1.0 if self.model.a >= 0 else -1.0

    def table(self) -> list[tuple[str, float, float, float, str]]:
        """Rows (name, ideal, rounded, relative error, meaning)."""
        meaning = {"C": "mass capacitor (integrator feedback)",
                   "R": "viscous resistor (integrator feedback)",
                   "R_S": "current-source sense resistor, I_0 = v_set/R_S (two, matched)",
                   "R_F": "force resistor, I_F = V_F/R_F into the virtual ground",
                   "R_N": "noise resistor, I_n = V_n/R_N into the virtual ground",
                   "C_AC": "AC-coupling capacitor of the noise chain",
                   "R_B1": "Bessel low-pass resistor", "R_B2": "Bessel low-pass resistor",
                   "C_B1": "Bessel low-pass feedback capacitor",
                   "C_B2": "Bessel low-pass capacitor to ground",
                   "C_X": "position integrator capacitor (reset switch across it)",
                   "R_X": "position integrator input resistor",
                   "R_K": "spring resistor, -V(x)/R_K into the virtual ground",
                   "R_I": "inverter resistors (two)"}
        return [(k, self.ideal[k], self.values[k], self.rounding[k], meaning.get(k, ""))
                for k in self.values]


def choose_kappa(model: Model, spec: BoardSpec, v0=()) -> tuple[float, float]:
    """(kappa, v_max): volts per unit velocity and the largest |v| the board must carry.

    kappa = min(sigma_volts/std, machine_unit/v_max): about 1 V of stationary spread unless
    the initial velocities or the stationary tails (to e^-32 of the peak) would leave the
    machine unit.  With a spring the spread is that of the spring-free model and the largest
    |v| also covers the release from x0 (energy: |v| <= sqrt(spring) |x0| + the spring-free
    tails)."""
    base = _velocity_only(model)
    lo, hi = stationary_range(base)
    v_max = max([abs(lo), abs(hi)] + [abs(float(x)) for x in v0])
    if model.spring > 0:
        v_max = max(v_max, math.sqrt(model.spring) * abs(model.x0) + max(abs(lo), abs(hi)))
    if spec.kappa is not None:
        return spec.kappa, v_max
    std = stationary_std(base)
    return min(spec.sigma_volts / std, spec.machine_unit / v_max), v_max


def _velocity_only(model: Model) -> Model:
    return model.replace(spring=0.0, x0=0.0) if model.spring > 0 else model


def bessel2_sallen_key(fc: float, r: float) -> tuple[float, float]:
    """(C1, C2) of a unity-gain equal-resistor Sallen-Key 2nd-order Bessel low-pass with -3 dB
    frequency ``fc``: Q = 1/sqrt(3) needs C1/C2 = 4 Q^2 = 4/3 (C1 the feedback capacitor);
    the Bessel -3 dB point sits at omega_0/1.2720 (omega_0 = 1/(R sqrt(C1 C2)))."""
    w0 = 2.0 * math.pi * fc * 1.27201964951
    prod = 1.0 / (w0 * r) ** 2
    c2 = math.sqrt(prod * 3.0 / 4.0)
    return 4.0 / 3.0 * c2, c2


def design_board(model: Model, spec: BoardSpec | None = None, v0=()) -> BoardDesign:
    """Component values for ``model`` on the board ``spec`` (see module docstring).

    ``v0``: initial velocities the experiment starts from (they must fit the machine unit).
    Raises ValueError naming the parameter when the model cannot be scaled inside the rails.
    """
    checks.instance("model", model, Model, description="an analogue.Model")
    spec = checks.instance("spec", BoardSpec() if spec is None else spec, BoardSpec,
                           description="a BoardSpec")
    if model.delta <= 0:
        raise ValueError("model.delta must be > 0 for the board (its friction element is the bridge)")
    for name, off in (("cubic", model.cubic == 0), ("stribeck", model.stribeck is None),
                      ("shot", getattr(model, "shot", None) is None)):
        if not off:
            raise ValueError(f"model.{name} is not built on the board yet (it realises tau_m, Delta, "
                             f"a, gamma and the spring); set {name} to its default")
    kappa, v_max = choose_kappa(model, spec, v0)
    if kappa * v_max > spec.machine_unit * (1 + 1e-9):
        raise ValueError(f"kappa={kappa:.4g} V puts |v| = {v_max:.4g} at {kappa * v_max:.3g} V, beyond "
                         f"the machine unit {spec.machine_unit} V; lower kappa")
    theta, rs, cs = spec.time_scale, spec.resistor_series, spec.capacitor_series
    cap = round_to_series(spec.capacitance, cs)
    ck = cap * kappa
    part = get_part(spec.diode)
    temp_k = spec.temperature + 273.15
    eps_volts = part.smoothing_volts(model.delta * ck / theta, temp_k)
    noise_dt = spec.noise_dt if spec.noise_dt is not None else model.tau_m / 800.0
    noise_ts = noise_dt * theta

    i_total = model.delta * ck / theta
    i0 = i_total - 2.0 * part.IS            # the bridge amplitude is I_0 + 2 IS
    r_visc = 1.0 / (cap / (model.tau_m * theta) - (2.0 / part.rp if part.rp else 0.0))  # diode leakage rp/2 in parallel
    i_force = abs(model.a) * ck / theta
    d_i = ck ** 2 / (theta * model.gamma)
    r_noise = spec.dac_rms * math.sqrt(noise_ts / (2.0 * d_i))
    f_dac = 1.0 / noise_ts
    r_b = 10e3
    c_b1, c_b2 = bessel2_sallen_key(spec.bessel_fc * f_dac, r_b)
    ideal = {"C": spec.capacitance, "R": r_visc, "R_S": spec.v_set / i0,
             "R_F": spec.v_force / i_force if i_force > 0 else math.inf,
             "R_N": r_noise, "R_B1": r_b, "R_B2": r_b, "C_B1": c_b1, "C_B2": c_b2}
    if spec.ac_corner is not None:
        # AC coupling: C_AC in series with R_N; corner f = ac_corner/(tau_m theta) Hz
        ideal["C_AC"] = 1.0 / (2.0 * math.pi * spec.ac_corner / (model.tau_m * theta) * r_noise)
    values = {}
    for k, x in ideal.items():
        if not math.isfinite(x):
            values[k] = x
        elif k.startswith("C"):
            values[k] = round_to_series(x, cs if k == "C" else "E12")
        else:
            values[k] = round_to_series(x, rs)
    rounding = {k: (values[k] / ideal[k] - 1.0) if math.isfinite(ideal[k]) else 0.0 for k in ideal}

    # what the rounded board implements (ideal op-amps; offsets are tolerances, not design)
    r_tot = 1.0 / (1.0 / values["R"] + (2.0 / part.rp if part.rp else 0.0))
    i_amp = spec.v_set / values["R_S"] + 2.0 * part.IS
    a_real = (spec.v_force / values["R_F"]) * theta / ck if i_force > 0 else 0.0
    if model.a < 0:
        a_real = -a_real
    d_real = (spec.dac_rms / values["R_N"]) ** 2 * noise_ts / 2.0
    spring_real = 0.0
    if model.spring > 0:
        # position integrator U5 (R_X from the output, C_X feedback): V(x) = kappa theta/(R_X C_X) x;
        # inverter U6 (two R_I); spring current -V(x)/R_K into the virtual ground:
        # spring = theta^2/(R_X C_X R_K C) (with R_X C_X = theta: V(x) = kappa x)
        ideal.update({"C_X": cap, "R_X": theta / cap, "R_K": theta / (model.spring * cap), "R_I": 100e3})
        for k in ("C_X", "R_X", "R_K", "R_I"):
            values[k] = round_to_series(ideal[k], cs if k == "C_X" else rs)
            rounding[k] = values[k] / ideal[k] - 1.0
        spring_real = theta ** 2 / (values["R_X"] * values["C_X"] * values["R_K"] * cap)
    realised = model.replace(tau_m=r_tot * cap / theta, delta=theta * i_amp / ck, a=a_real,
                             gamma=ck ** 2 / (theta * d_real), epsilon=eps_volts / kappa,
                             spring=spring_real)
    std = stationary_std(_velocity_only(model))
    notes = ((f"kappa = {kappa:.4g} V per unit velocity: stationary std {std:.4g} "
             f"-> {kappa * std:.3g} V; largest |v| {v_max:.3g} -> "
             f"{kappa * v_max:.3g} V (machine unit {spec.machine_unit} V, rails +-{spec.rails} V)"),
             (f"bridge tanh width w = 2 N V_T + RS I = {eps_volts * 1e3:.4g} mV "
             f"({spec.diode}, N = {part.N}, V_T = {thermal_voltage(temp_k) * 1e3:.4g} mV) -> epsilon = "
             f"{eps_volts / kappa:.4g} = {eps_volts / kappa / std:.3g} std"),
             DIELECTRIC_ADVICE)
    return BoardDesign(model=model, spec=spec, kappa=kappa, theta=theta, eps_volts=eps_volts,
                       noise_ts=noise_ts, ideal=ideal, values=values, rounding=rounding,
                       realised=realised, v_max=v_max, notes=notes)

