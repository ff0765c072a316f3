"""The noise chain: seeded digital Gaussian -> DAC -> Bessel low-pass -> R_N.

What a microcontroller or FPGA runs: ``z_k`` standard normal from numpy's PCG64 seeded with
``SeedSequence(seed, spawn_key=(replica,))`` (so a built board can be driven by the very
sequence the simulation used), scaled to ``dac_rms`` volts, rounded to the DAC's LSB
(``2 dac_range / 2^bits``), clipped to the range, held for ``TS`` (the DAC's zero-order hold),
then a unity-gain 2nd-order Sallen-Key Bessel low-pass and the noise resistor into the
integrator's virtual ground (a series AC-coupling capacitor only where ``BoardSpec.ac_corner``
asks for one; none by default, issue 21 item 6).

In ngspice the DAC is an XSPICE ``filesource`` with ``amplstep=true`` (measured here: 40 000
samples in 0.4 s, where an inline ``pwl`` source costs 220 s because every evaluation scans
its point list).  The same chain is computed exactly in numpy (:func:`chain_current`), which
lets a test check the ngspice chain trajectory by trajectory and lets the budget use the
exact coloured noise (:func:`filtered_noise`).

Finite bandwidth (budget): the velocity sees ``S(w) = S_0 sinc^2(w TS/2) |H_B(w)|^2
|H_AC(w)|^2`` instead of ``S_0``.  For an OU process with relaxation rate ``lam`` the
stationary variance changes by the factor :func:`ou_variance_factor`; the full nonlinear
effect on every observable is measured by an SDE pair driven by the same increments, white and
coloured (:mod:`analogue.board.budget`).
"""
from __future__ import annotations

import hashlib
import math
import os
import re
from pathlib import Path

import numpy as np
from scipy import integrate, signal

from .. import checks
from .design import BoardDesign

__all__ = [
    "SAFE_PATH",
    "bessel_lines",
    "chain_current",
    "chain_transfer",
    "dac_lines",
    "dac_sequence",
    "filtered_noise",
    "ou_variance_factor",
    "write_dac_file",
]

SAFE_PATH = re.compile(r"/[A-Za-z0-9_./+-]+")


_n = checks.spice_number  # a deck number: _n(name, value)


def standard_normals(seed: int, replica: int, n: int) -> np.ndarray:
    seed = checks.integer("seed", seed, minimum=0)
    replica = checks.integer("replica", replica, minimum=0)
    rng = np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(int(replica),)))
    return rng.standard_normal(int(n))


def dac_sequence(design: BoardDesign, seed: int, replica: int, n: int) -> np.ndarray:
    """DAC output volts for ``n`` samples: quantised to the LSB and clipped to the range."""
    spec = design.spec
    lsb = 2.0 * spec.dac_range / 2 ** spec.dac_bits
    z = standard_normals(seed, replica, n)
    volts = np.round(z * spec.dac_rms / lsb) * lsb
    return np.clip(volts, -spec.dac_range, spec.dac_range - lsb)


def write_dac_file(directory: Path, volts: np.ndarray, ts: float) -> tuple[Path, str]:
    """Write the filesource table (time, value) as ``directory/dac_<sha256>.txt`` (named by its
    content, so concurrent jobs never overwrite each other's sequences; written atomically);
    returns (path, sha256)."""
    directory = Path(directory)
    # mid-scale (0 V) while the integrator is held in reset, sample k from (k + 1) TS on:
    # an optional AC-coupling capacitor then starts uncharged (a first sample held through the
    # operating point would charge it and leave a decaying force offset).
    t = np.concatenate([[0.0], (np.arange(volts.size) + 1) * ts])
    volts = np.concatenate([[0.0], volts])
    text = "".join(f"{a:.12e} {b:.9e}\n" for a, b in zip(t, volts))
    data = text.encode()
    sha = hashlib.sha256(data).hexdigest()
    path = directory / f"dac_{sha}.txt"
    if not path.exists():
        tmp = path.with_suffix(f".tmp{os.getpid()}")
        tmp.write_bytes(data)
        os.replace(tmp, path)
    return path, sha


def dac_lines(prefix: str, node: str, path, sha256: str, time_offset: float = 0.0) -> list[str]:
    """XSPICE filesource (zero-order hold) reading ``path``, driving ``node``, its table
    delayed by ``time_offset`` seconds (a bench start by the reset switch).  The deck names
    the file without its directory; whoever runs the deck passes ``path`` along
    (:attr:`analogue.board.netlist.BoardDeck.noise_files`)."""
    p = checks.identifier("prefix", prefix)
    node = checks.identifier("node", node)
    if re.fullmatch(r"[0-9a-f]{64}", sha256 or "") is None:
        raise ValueError("sha256 must be 64 hex digits")
    # by its name only: ngspice lower-cases the path it opens, so the runner links the file
    # into the deck's working directory (analogue.circuit.ngspice.run_deck(files=...))
    f = Path(path).name
    if re.fullmatch(r"dac_[0-9a-f]{64}\.txt", f) is None:
        raise ValueError(f"noise file must be named dac_<sha256>.txt, got {f!r}")
    return [f"* {p} noise file sha256 {sha256}",
            f"A{p}dac %v([{node}]) fs{p}",
            (f".model fs{p} filesource (file=\"{f}\" amploffset=[0] amplscale=[1] "
             f"timeoffset={_n('time_offset', float(time_offset))} "
            f"timescale=1 timerelative=false amplstep=true)")]


def bessel_lines(prefix: str, inp: str, out: str, design: BoardDesign, opamp: str,
                 values: dict | None = None) -> list[str]:
    """Unity-gain Sallen-Key Bessel low-pass from ``inp`` to ``out`` (op-amp ``opamp``)."""
    p = checks.identifier("prefix", prefix)
    v = values or design.values
    return [f"R{p}b1 {inp} {p}b1 {_n('R_B1', v['R_B1'])}", f"R{p}b2 {p}b1 {p}b2 {_n('R_B2', v['R_B2'])}",
            f"C{p}b1 {p}b1 {out} {_n('C_B1', v['C_B1'])}", f"C{p}b2 {p}b2 0 {_n('C_B2', v['C_B2'])}",
            f"X{p}ubf {p}b2 {out} vcc vee {out} {opamp}"]


def chain_transfer(values: dict) -> signal.lti:
    """H(s) from the DAC voltage to the current into the virtual ground, times R_N (unit DC
    gain of the pass band): Bessel ``1/(1 + s R (C1 + ... ))``, times the AC coupling
    ``s tau_ac/(1 + s tau_ac)``, ``tau_ac = C_AC R_N``, where the design has ``C_AC``."""
    r1, r2, c1, c2 = values["R_B1"], values["R_B2"], values["C_B1"], values["C_B2"]
    # Sallen-Key unity gain: H = 1/(s^2 R1 R2 C1 C2 + s C2 (R1 + R2) + 1)
    den_b = [r1 * r2 * c1 * c2, c2 * (r1 + r2), 1.0]
    if "C_AC" not in values:
        return signal.lti([1.0], den_b)
    tau = values["C_AC"] * values["R_N"]
    num = np.polymul([tau, 0.0], [1.0])
    den = np.polymul(den_b, [tau, 1.0])
    return signal.lti(num, den)


def chain_current(values: dict, volts: np.ndarray, ts: float, per_hold: int = 8) -> tuple:
    """Exact response (ZOH discretisation) of the chain to the held DAC volts: returns
    (times, current) on a grid of ``per_hold`` points per sample; current in amperes into the
    virtual ground."""
    dt = ts / per_hold
    sys_d = chain_transfer(values).to_ss()
    ad, bd, cd, dd, _ = signal.cont2discrete((sys_d.A, sys_d.B, sys_d.C, sys_d.D), dt, "zoh")
    u = np.repeat(np.asarray(volts, float), per_hold)
    _, y, _ = signal.dlsim((ad, bd, cd, dd, dt), u)
    t = (np.arange(u.size) + 1) * dt
    return t, y[:, 0] / values["R_N"]


def filtered_noise(values: dict, z_fine: np.ndarray, per_hold: int, ts: float, *, rms: float,
                   lsb: float, clip: float) -> np.ndarray:
    """The SDE noise array (``simulate_sde(noise=...)`` convention: increments
    ``sqrt(2 dt/gamma) noise``) of the coloured chain driven by the same fine increments
    ``z_fine`` (replicas, n_hold*per_hold) as a white reference: each hold gets the mean of
    its fine increments (the same integrated noise), scaled to DAC volts, quantised, clipped,
    held, and filtered through :func:`chain_transfer` (exact for piecewise-constant input)."""
    r, n = z_fine.shape
    n_hold = n // per_hold
    held = z_fine.reshape(r, n_hold, per_hold).mean(axis=2) * math.sqrt(per_hold)
    volts = np.clip(np.round(held * rms / lsb) * lsb, -clip, clip - lsb)
    u = np.repeat(volts / rms, per_hold, axis=1) / math.sqrt(per_hold)
    return _filter_fine(values, u, ts / per_hold)


def _filter_fine(values: dict, u: np.ndarray, dt: float) -> np.ndarray:
    """The chain (exact ZOH discretisation at step dt) applied along the last axis."""
    ss = chain_transfer(values).to_ss()
    ad, bd, cd, dd, _ = signal.cont2discrete((ss.A, ss.B, ss.C, ss.D), dt, "zoh")
    num, den = signal.ss2tf(ad, bd, cd, dd)
    return signal.lfilter(num[0], den, u, axis=-1)


def ou_variance_factor(values: dict, ts: float, lam: float) -> float:
    """Var(coloured)/Var(white) of an OU process ``dv = -lam v dt + noise`` (circuit time)
    whose noise has the chain's spectrum ``sinc^2(w TS/2) |H(w)|^2`` (held samples at a random
    phase, then the filter): ``int S |1/(iw + lam)|^2 dw / int S_0 |...|^2 dw``."""
    h = chain_transfer(values)

    def f(w):
        _, resp = signal.freqresp(h, [w])
        x = w * ts / 2.0
        sinc2 = (math.sin(x) / x) ** 2 if x > 0 else 1.0
        return sinc2 * abs(resp[0]) ** 2 / (w * w + lam * lam)

    top = 200.0 / ts
    pts = [lam, 1.0 / ts, 10.0 / ts]
    num = integrate.quad(f, 0.0, top, points=pts, limit=400)[0]
    den = math.pi / (2.0 * lam)
    return num / den
