"""Monte Carlo reference: the reduced Langevin equation (paper, eq. (4)) integrated in numpy.

``dv = (a - v/tau_m - Delta sgn(v)) dt + sqrt(2/gamma) dW`` (or ``tanh(v/epsilon)``), vectorised
over replicas, looping over time steps only, streaming (only the output grid is stored).

Schemes (step ``dt``, standard normal ``xi_k = noise[:, k]`` for step k):

* ``"exponential"`` (default): the linear part is integrated exactly, the friction is held at its
  value at the start of the step,
  ``v' = v r + tau_m (a - Delta sgn v)(1 - r) + sqrt((tau_m/gamma)(1 - r^2)) xi_k``,
  ``r = e^{-dt/tau_m}``.  Exact (no time-step error at all) for Delta = 0 and for steps that
  stay on one half line; its noise term is the exact OU-weighted integral of the Wiener
  increment ``sqrt(2/gamma)(W_{k+1} - W_k) = sqrt(2 dt/gamma) xi_k``.
* ``"euler"``: Euler-Maruyama, ``v' = v + (a - v/tau_m - Delta sgn v) dt + sqrt(2 dt/gamma) xi_k``.

Both share the weak error of any explicit scheme at the discontinuity of ``sgn``: steps that
straddle ``v = 0`` use the wrong friction for part of the step (theory for discontinuous
drifts guarantees only weak order 1/2).  Measured with common random numbers
(``benchmarks/bench_exact.py``; tau_m = 1, Delta = 0.7, a = 0.2, gamma = 10, stationary
variance 0.0240): going from dt = 5e-4 to 1e-3 and 2e-3 changes the stationary variance by
3e-5 and 1e-4 and the mean by 3e-5 and 7e-5 (exponential scheme; Euler about 30% more), i.e.
close to linear in dt.  The tests measure the bias the same way and require it to be below
one standard error of each comparison.  Scheme aliases: "em", "euler-maruyama" -> "euler";
"ou", "exact-ou" -> "exponential".

Positions ``x(t) = int_0^t v ds`` use the trapezoid rule on the fine step.
"""
from __future__ import annotations

import math
import numbers

import numpy as np

from . import checks
from .ensemble import Ensemble
from .model import Model
from .theory.flow_table import flow_table
from .theory.kolmogorov_feller import _grid_range
from .theory.stationary import sample_stationary

__all__ = ["simulate_sde", "simulate_sde_held_pair", "standard_noise", "default_dt", "SCHEMES"]

SCHEMES = ("exponential", "euler")
_ALIASES = {"em": "euler", "euler-maruyama": "euler", "euler_maruyama": "euler",
            "ou": "exponential", "exact-ou": "exponential", "exact_ou": "exponential"}
_MAX_OUTPUT_POINTS = 1000
# numbers (steps x rows) per block of the time-stepped loop: its three block buffers of 1 MB
# stay in cache (measured, work's held pair, 64000 steps x 512 rows / 19200 x 2048: 1 << 20
# numbers 0.43 / 0.30 CPU s, 1 << 17 0.33 / 0.26)
_BLOCK_NUMBERS = 1 << 17


def default_dt(model: Model) -> float:
    """``min(tau_m/500, t_kink/50, 0.1 epsilon/Delta)``.

    ``t_kink = 2/(gamma (Delta + |a|)^2)`` is the time in which the friction drift carries a
    particle as far as the noise spreads it near ``v = 0`` (the stick time of a thermal
    excursion), which for large gamma is much shorter than tau_m; ``epsilon/Delta`` is the
    relaxation time of the smooth law at ``v = 0``.
    """
    dt = model.tau_m / 500.0
    d0 = model.static_friction
    if d0 > 0 and math.isfinite(model.gamma):
        t_kink = 2.0 / (model.gamma * (d0 + abs(model.a)) ** 2)
        dt = min(dt, t_kink / 50.0)
    if d0 > 0 and model.epsilon > 0:
        dt = min(dt, 0.1 * model.epsilon / d0)
    # Family members (each variant's own limit, analogue.variants): the spring period, the
    # Stribeck length crossed at the typical speed, the explicit cubic term's stability
    # (dt * 3 cubic v^2 <= 1/50 at 6 speeds), 1/20 of the mean time between kicks.
    v_typ = max(model.velocity_scale, abs(model.attractor), 1e-300)
    v_typ = model.noise_kind.typical_speed(v_typ)
    dt = model.restoring.dt_limit(dt)
    dt = model.friction.dt_limit(dt, v_typ)
    return model.noise_kind.dt_limit(dt)


def _streams(seed):
    """(initial-state generator, noise generator) derived from ``seed``."""
    if isinstance(seed, (bool, np.bool_)):
        raise ValueError("seed must be None, an int >= 0, a SeedSequence or a Generator")
    if seed is not None and not isinstance(seed, (numbers.Integral, np.random.SeedSequence,
                                                  np.random.Generator)):
        raise ValueError(f"seed must be None, an int >= 0, a SeedSequence or a Generator, got {seed!r}")
    if isinstance(seed, numbers.Integral) and seed < 0:
        raise ValueError(f"seed must be >= 0, got {seed}")
    root = np.random.default_rng(seed)
    init, noise, kicks = root.spawn(3)  # spawn keys 0, 1 as before: old seeds reproduce
    return init, noise, kicks


def standard_noise(seed, replicas: int, n_steps: int) -> np.ndarray:
    """The standard normals (shape (replicas, n_steps)) that :func:`simulate_sde` draws for
    ``seed`` (an int or SeedSequence): passing them as ``noise=`` reproduces the seeded run."""
    _, rng, _ = _streams(seed)
    return rng.standard_normal((int(n_steps), int(replicas))).T


def _ratio(name_num, num, name_den, den) -> int:
    """``num/den`` as an integer, or a ValueError naming both parameters."""
    k = round(num / den)
    if k < 1 or abs(k * den - num) > 1e-9 * num:
        raise ValueError(f"{name_num}={num!r} must be a whole multiple of {name_den}={den!r}")
    return int(k)


def _time_grid(model, t_end, dt, sample_dt):
    """(dt, steps per output sample, number of fine steps)."""
    if dt is not None and sample_dt is not None:
        n_steps = _ratio("t_end", t_end, "dt", dt)
        per = _ratio("sample_dt", sample_dt, "dt", dt)
        if n_steps % per:
            raise ValueError(f"t_end={t_end!r} must be a whole multiple of sample_dt={sample_dt!r}")
        return dt, per, n_steps
    if sample_dt is not None:
        n_out = _ratio("t_end", t_end, "sample_dt", sample_dt)
        per = max(1, math.ceil(sample_dt / default_dt(model) - 1e-9))
        return sample_dt / per, per, n_out * per
    # Output every `per` steps, at most ~_MAX_OUTPUT_POINTS samples; `per` must divide n_steps.
    if dt is not None:
        n_steps = _ratio("t_end", t_end, "dt", dt)
        per = max(1, math.ceil(n_steps / _MAX_OUTPUT_POINTS))
        per = next(k for k in range(per, n_steps + 1) if n_steps % k == 0)
        return dt, per, n_steps
    n_steps = max(1, math.ceil(t_end / default_dt(model) - 1e-9))
    per = max(1, math.ceil(n_steps / _MAX_OUTPUT_POINTS))
    n_steps = per * math.ceil(n_steps / per)
    return t_end / n_steps, per, n_steps


def _given_v0(v0, replicas: int, allowed: str) -> tuple[np.ndarray, float | str]:
    """``(v, v0 for the meta)``: the initial velocities ``v0`` (a number or an array) as a
    finite array of ``replicas`` values (a copy); ``allowed`` says what ``v0`` may be."""
    try:
        v = np.broadcast_to(np.asarray(v0, dtype=float), (replicas,)).copy()
    except (ValueError, TypeError):
        raise ValueError(f"v0 must be {allowed}, got shape {np.shape(v0)}") from None
    if not np.all(np.isfinite(v)):
        raise ValueError("v0 must be finite")
    return v, (float(v0) if np.ndim(v0) == 0 else "array")


def simulate_sde(model: Model, *, v0, t_end: float, replicas: int, seed=None, dt: float | None = None,
                 sample_dt: float | None = None, noise: np.ndarray | None = None,
                 scheme: str = "exponential", noise_hold: int = 1) -> Ensemble:
    """Integrate eq. (4) for ``replicas`` independent trajectories from t = 0 to ``t_end``.

    Parameters
    ----------
    v0 : float, array (replicas,), or "stationary"
        Initial velocities; "stationary" draws them from ``p_s`` (eq. (6)) with
        :func:`analogue.theory.stationary.sample_stationary` using a stream derived from seed
        (independent of the noise stream).
    t_end : float
        Final time (> 0), a whole multiple of ``dt`` / ``sample_dt`` when those are given.
    replicas : int
        Number of independent trajectories (>= 1).
    seed : None, int, SeedSequence or Generator
        Seeds the noise (and the stationary initial state).  Same int seed -> identical result.
    dt : float, optional
        Integration step (default :func:`default_dt`, adjusted to divide sample_dt / t_end).
    sample_dt : float, optional
        Output interval, a whole multiple of dt (default: at most ~1000 output intervals).
    noise : array (replicas, n_steps), optional
        Standard normals driving the integrator instead of the seeded generator:
        ``noise[:, k]`` is the Wiener increment over fine step k in units of its std, i.e. the
        noise term increment is ``sqrt(2 dt/gamma) * noise[:, k]`` (see module docstring for
        the exponential scheme's OU weighting).  ``n_steps = t_end/dt``.
    scheme : "exponential" | "euler"
    noise_hold : int, optional
        With ``noise``: each column drives ``noise_hold`` consecutive fine steps (a held noise,
        like the circuit's ``trrandom``), so ``noise`` has shape (replicas, n_steps /
        noise_hold).  The same as passing every column repeated ``noise_hold`` times, without
        building that array (the report's held-noise Monte Carlo: 256 replicas x 160000 steps
        would be 330 MB).

    Returns
    -------
    The same :class:`~analogue.Ensemble` type as :func:`analogue.simulate`, with the keywords
    both share (``v0``, ``t_end``, ``replicas``, ``seed``, ``sample_dt``) meaning the same:
    t (n_out,), v and x (replicas, n_out), meta: source="sde", seed, dt, sample_dt, t_end,
    scheme, noise ("seeded" or "given"), v0, model parameters; ``noise``: the given ``noise``
    array (with ``meta["noise_dt"] = dt``), None when seeded.
    """
    checks.instance("model", model, Model, description="an analogue.Model")
    scheme = _ALIASES.get(scheme, scheme) if isinstance(scheme, str) else scheme
    if scheme not in SCHEMES:
        raise ValueError(f"scheme must be one of {SCHEMES} (or an alias), got {scheme!r}")
    t_end = checks.positive("t_end", t_end)
    replicas = checks.integer("replicas", replicas, minimum=1)
    dt = None if dt is None else checks.positive("dt", dt)
    sample_dt = None if sample_dt is None else checks.positive("sample_dt", sample_dt)
    if sample_dt is not None and sample_dt > t_end * (1 + 1e-12):
        raise ValueError(f"sample_dt={sample_dt!r} must be <= t_end={t_end!r}")
    dt, per, n_steps = _time_grid(model, t_end, dt, sample_dt)
    init_rng, noise_rng, kick_rng = _streams(seed)
    if not model.is_noisy:
        raise ValueError("the model is noise-free (gamma = inf, shot = None): use "
                         "Model.deterministic, or set a finite gamma or shot noise")
    if noise is not None and not math.isfinite(model.gamma):
        raise ValueError("noise= gives Gaussian increments, but gamma = inf (no Gaussian noise)")

    noise_hold = checks.integer("noise_hold", noise_hold, minimum=1)
    if noise_hold > 1 and noise is None:
        raise ValueError("noise_hold > 1 needs noise= (the held values)")
    if noise is not None:
        noise = np.asarray(noise, dtype=float)
        if n_steps % noise_hold:
            raise ValueError(f"noise_hold={noise_hold} must divide the number of steps {n_steps}")
        if noise.shape != (replicas, n_steps // noise_hold):
            what = "n_steps" if noise_hold == 1 else "n_steps / noise_hold"
            raise ValueError(f"noise must have shape (replicas, {what}) = "
                             f"{(replicas, n_steps // noise_hold)}, got {noise.shape}")
        if not _all_finite(noise):
            raise ValueError("noise must be finite")

    if isinstance(v0, str):
        if v0 != "stationary":
            raise ValueError(f"v0 must be a number, an array (replicas,), or 'stationary', got {v0!r}")
        v = sample_stationary(model, replicas, seed=init_rng)
        v0_meta: float | str = "stationary"
    else:
        v, v0_meta = _given_v0(v0, replicas, f"a number, an array of shape ({replicas},) or "
                                             "'stationary'")

    g = model.gamma
    n_out = n_steps // per + 1
    if not math.isfinite(g):
        v_out, x_out, n_kicks = _event_driven(model, v, n_out, per * dt, dt, kick_rng)
    else:
        parts = None if noise is None else ((noise, noise_hold),)
        v_out, x_out, n_kicks = model.noise_kind.stepped(model, v, n_steps, per, dt, scheme,
                                                         parts, noise_rng, kick_rng, _stepped)

    t = np.arange(n_out) * (per * dt)
    meta = _meta(model, seed, dt, per, scheme, noise is not None, v0_meta, replicas, t,
                 noise_hold, n_kicks)
    return Ensemble(t, v_out, x_out, meta, noise)


def _all_finite(a: np.ndarray, sums: np.ndarray | None = None) -> bool:
    """Whether every element of ``a`` is finite, from ``sums`` (sums or means over parts of
    ``a``; default: its total) when those are finite: an inf or nan in a sum's terms makes it
    inf or nan.  Only a sum that is not finite (a non-finite term, or finite terms that
    overflow) costs the elementwise test, which at the report's full size (256 x 320000) took
    0.22 CPU s, 10 % of the held pair."""
    if sums is None:
        with np.errstate(over="ignore", invalid="ignore"):
            sums = np.add.reduce(a, axis=None)
    return bool(np.all(np.isfinite(sums))) or bool(np.all(np.isfinite(a)))


def _meta(model, seed, dt, per, scheme, given, v0_meta, replicas, t, noise_hold, n_kicks) -> dict:
    g = model.gamma
    meta = {"source": "sde", "seed": int(seed) if isinstance(seed, numbers.Integral) else None,
            "dt": dt, "sample_dt": per * dt, "scheme": scheme,
            "noise": "given" if given else "seeded", "v0": v0_meta,
            "replicas": replicas, "model": model.as_dict(), "t_end": float(t[-1])}
    if given:
        # Ensemble.noise: one standard normal per step (per hold), as for simulate
        meta["noise_dt"] = dt * noise_hold
    meta.update(model.noise_kind.mc_meta(n_kicks, "compound Poisson sum per step"
                                         if math.isfinite(g) else _FLOW_ROUTES[_flow_route(model)]))
    meta.update(model.restoring.mc_meta())
    return meta


def _given_blocks(noise: np.ndarray, hold: int):
    """Blocks (steps, replicas) of a given noise (replicas, steps / hold), each column
    repeated over its ``hold`` steps; blocks start on whole holds.  A contiguous copy: a row
    of the transposed view is strided by the whole record (one cache line per replica), which
    cost about half of the loop's time at 160 000 steps."""
    def block(start: int, stop: int) -> np.ndarray:
        cols = noise[:, start // hold:-(-stop // hold)].T
        return np.ascontiguousarray(cols if hold == 1 else np.repeat(cols, hold, axis=0))
    return block


def simulate_sde_held_pair(model: Model, *, v0, t_end: float, replicas: int, noise: np.ndarray,
                           noise_hold: int, dt: float, sample_dt: float,
                           scheme: str = "exponential") -> tuple[Ensemble, Ensemble]:
    """``(held, white)``: the same, bit for bit, as ``simulate_sde(noise=m, noise_hold=
    noise_hold)`` with ``m`` the mean of ``noise`` over each hold, and ``simulate_sde(noise=
    noise)`` (same ``v0``, ``dt``, ``sample_dt``), integrated in one loop over both sets of
    rows: at a few hundred replicas each step's numpy calls cost more than their arithmetic,
    so one loop over 2 x replicas rows takes about half the time of two (the report's
    bandwidth term: white against held noise on common Wiener increments).

    ``noise``: standard normals (replicas, n_steps), ``n_steps = t_end / dt`` a whole number
    of holds of ``noise_hold`` steps."""
    checks.instance("model", model, Model, description="an analogue.Model")
    if not model.noise_kind.paper:
        raise ValueError("simulate_sde_held_pair needs white Gaussian noise only (finite "
                         "gamma, shot = None, noise = None)")
    scheme = _ALIASES.get(scheme, scheme) if isinstance(scheme, str) else scheme
    if scheme not in SCHEMES:
        raise ValueError(f"scheme must be one of {SCHEMES} (or an alias), got {scheme!r}")
    replicas = checks.integer("replicas", replicas, minimum=1)
    hold = checks.integer("noise_hold", noise_hold, minimum=1)
    t_end = checks.positive("t_end", t_end)
    dt, per, n_steps = _time_grid(model, t_end, checks.positive("dt", dt),
                                  checks.positive("sample_dt", sample_dt))
    noise = np.asarray(noise, dtype=float)
    if n_steps % hold:
        raise ValueError(f"noise_hold={hold} must divide the number of steps {n_steps}")
    if noise.shape != (replicas, n_steps):
        raise ValueError(f"noise must have shape (replicas, n_steps) = {(replicas, n_steps)}, "
                         f"got {noise.shape}")
    with np.errstate(over="ignore", invalid="ignore"):
        means = noise.reshape(replicas, n_steps // hold, hold).mean(axis=2)
    if not _all_finite(noise, means):
        raise ValueError("noise must be finite")
    v, v0_meta = _given_v0(v0, replicas, f"a number or an array of shape ({replicas},)")
    v_out, x_out, _ = _stepped(model, np.concatenate([v, v]), n_steps, per, dt, scheme,
                               ((means, hold), (noise, 1)), None, None)
    t = np.arange(n_steps // per + 1) * (per * dt)
    held = Ensemble(t, v_out[:replicas], x_out[:replicas],
                    _meta(model, None, dt, per, scheme, True, v0_meta, replicas, t, hold, 0), means)
    white = Ensemble(t, v_out[replicas:], x_out[replicas:],
                     _meta(model, None, dt, per, scheme, True, v0_meta, replicas, t, 1, 0), noise)
    return held, white


# ----------------------------------------------------------------- time-stepped (gamma finite)
def _coulomb_fn(model):
    """``model.coulomb`` as a closure: the same floating-point operations (``Delta * sgn(v)``,
    ``Delta * tanh(v/epsilon)``) without its per-call conversions (``asarray``, ``full_like``),
    which cost about as much as the step itself (measured: 400 000 calls, 8 s of 20 s)."""
    return model.friction.fast_dry()


def _coefficients(scheme, dt, tau, g):
    """``(lin, push, amp)`` of the step ``v' = lin v + push force + amp xi``."""
    if scheme == "exponential":
        r = math.exp(-dt / tau)
        return r, tau * (1.0 - r), math.sqrt(tau / g * (1.0 - r * r))
    return 1.0 - dt / tau, dt, math.sqrt(2.0 * dt / g)


def _stepped(model, v, n_steps, per, dt, scheme, parts, noise_rng, kick_rng):
    """The exponential/Euler schemes of the module docstring; family terms (cubic, Stribeck
    via ``model.coulomb``, spring with the position ``x0 + x``) enter the friction held over
    the step; shot kicks are added at the end of each step as the exact compound-Poisson sum
    of the step (count ~ Poisson(rate dt), sum of that many exponentials: a Gamma variable).

    ``parts``: None (standard normals from ``noise_rng``) or the given noise as
    ``((noise, hold), ...)``, each ``noise`` (rows, n_steps / hold) driving the next rows of
    ``v``, each of its columns ``hold`` consecutive steps.  Returns ``(v_out, x_out, kicks)``.

    Bit for bit :func:`_stepped_reference` (the same floating-point operations on every
    element in the same order; ``tests/unit/test_montecarlo_fast_loop.py``), only with fewer
    numpy calls per step, since at a few hundred rows each call's overhead (~0.5 us) costs more
    than its arithmetic: the noise enters as ``amp * xi`` computed per block while the block is
    filled; the force is built in preallocated buffers from constant arrays (numpy 2's
    ufuncs take an array operand faster than a Python float); the new velocity is written
    into its row of a block buffer, so that the trapezoid increments ``0.5 dt (v + v')`` of
    the position are two vectorised operations per block and the position one addition
    per step (added in the same order: a cumulative sum along the step axis would be as
    exact but is 10x slower on a C-ordered block).  A spring feeds the position back into
    the force at every step: that member keeps the reference loop."""
    if model.dimension == 2:
        return _stepped_reference(model, v, n_steps, per, dt, scheme, parts, noise_rng,
                                  kick_rng)
    lin, push, amp = _coefficients(scheme, dt, model.tau_m, model.gamma)
    rows = v.size
    n_out = n_steps // per + 1
    v_out = np.empty((rows, n_out))
    x_out = np.empty((rows, n_out))
    v_out[:, 0] = v
    x_out[:, 0] = 0.0
    # blocks of whole holds (each given noise column drives `hold` steps)
    unit = 1
    for _, h in parts or ():
        unit = unit * h // math.gcd(unit, h)
    block = unit * max(1, _BLOCK_NUMBERS // (rows * unit))
    buf = np.empty((block + 1, rows))     # row 0: v at the block's start, row j: after step j
    noise = np.empty((block, rows))       # amp * xi of the block's steps
    incr = np.empty((block, rows))        # the position's increments
    x_samples = np.empty((block // per + 1, rows))
    row_views = list(buf)
    buf[0] = v
    x = np.zeros(rows)
    a, lin_a, push_a = (np.full(rows, c) for c in (model.a, lin, push))
    force = np.empty(rows)
    # the friction law's force a - Delta(v) sgn v (- cubic v^3) and the noise's kicks, chosen
    # once by the variants (analogue.variants)
    force_into = model.friction.force_into(a, rows)
    kicks = model.noise_kind.kicker()
    half_dt = 0.5 * dt
    multiply, add = np.multiply, np.add
    n_kicks = 0
    for start in range(0, n_steps, block):
        m = min(n_steps, start + block) - start
        xi = noise[:m]
        if parts is None:
            noise_rng.standard_normal(out=xi)
            xi *= amp
        else:
            _fill_given(xi, parts, start, amp)
        v = row_views[0]
        for new, noise_j in zip(row_views[1:m + 1], xi):   # (7 % cheaper than indexing)
            # force = a - Delta tanh(v / eps)  (or sgn v, or the Stribeck law), - cubic v^3
            force_into(v, force)
            # v' = (lin v + push force) + amp xi (+ kick)
            multiply(lin_a, v, new)
            multiply(push_a, force, force)
            add(new, force, new)
            add(new, noise_j, new)
            if kicks is not None:
                kick = kicks(dt, rows, kick_rng)
                n_kicks += int(np.count_nonzero(kick))
                add(new, kick, new)
            v = new
        # x += 0.5 dt (v + v') step by step (np.add.reduce along the steps would be cheaper,
        # but sums pairwise, in another order, when there is one row); outputs at the ends of
        # whole intervals
        d = incr[:m]
        add(buf[:m], buf[1:m + 1], d)
        multiply(half_dt, d, d)
        # the block's outputs: after its steps j with (start + j) % per == 0
        first = per - start % per
        ends = range(first, m + 1, per)
        xs = x_samples[:len(ends)]
        done = 0
        for i, end in enumerate(ends):
            for dj in d[done:end]:
                x += dj
            xs[i] = x
            done = end
        for dj in d[done:]:
            x += dj
        if len(ends):
            # the outputs are (rows, n_out): written once per block (a column per output
            # interval would touch a page per row, ~10 % of the loop)
            i0 = (start + first) // per
            v_out[:, i0:i0 + len(ends)] = buf[first::per][:len(ends)].T
            x_out[:, i0:i0 + len(ends)] = xs.T
        buf[0] = buf[m]
    return v_out, x_out, n_kicks


def _fill_given(out, parts, start, amp):
    """``out[:] = amp * xi`` for the steps ``start ...`` of a given noise: each part's
    columns repeated over its hold (``start`` and ``len(out)`` are whole holds)."""
    steps, rows = out.shape
    lo = 0
    for noise, hold in parts:
        hi = lo + noise.shape[0]
        cols = noise[:, start // hold:(start + steps) // hold].T
        # a view: the contiguous block split into (holds, hold, rows), the part's rows
        dest = out.reshape(steps // hold, hold, rows)[:, :, lo:hi]
        np.multiply(amp, cols[:, None, :], out=dest)
        lo = hi


def _stepped_reference(model, v, n_steps, per, dt, scheme, parts, noise_rng, kick_rng):
    """The plain loop (one numpy expression per term and step): used with a spring (the
    position enters the force at every step), and the reference :func:`_stepped` is tested
    against bit for bit."""
    tau, g = model.tau_m, model.gamma
    replicas = v.size
    lin, push, amp = _coefficients(scheme, dt, tau, g)
    n_out = n_steps // per + 1
    v_out = np.empty((replicas, n_out))
    x_out = np.empty((replicas, n_out))
    x = np.zeros(replicas)
    v_out[:, 0] = v
    x_out[:, 0] = 0.0
    # blocks of whole holds (a given noise's columns each drive `hold` steps)
    hold = max((h for _, h in parts), default=1) if parts else 1
    block = hold * max(1, _BLOCK_NUMBERS // (replicas * hold))
    a, law, restoring = model.a, model.friction, model.restoring
    coulomb = _coulomb_fn(model)
    kicks = model.noise_kind.kicker()
    n_kicks = 0
    for start in range(0, n_steps, block):
        stop = min(n_steps, start + block)
        if parts is None:
            xi = noise_rng.standard_normal((stop - start, replicas))
        else:
            xi = np.concatenate([_given_blocks(n, h)(start, stop) for n, h in parts], axis=1)
        for j, k in enumerate(range(start, stop)):
            force = restoring.add_force(law.add_drift(a - coulomb(v), v), model.x0 + x)
            v_new = lin * v + push * force + amp * xi[j]
            if kicks is not None:
                kick = kicks(dt, replicas, kick_rng)
                n_kicks += int(np.count_nonzero(kick))
                v_new = v_new + kick
            x += 0.5 * dt * (v + v_new)
            v = v_new
            if (k + 1) % per == 0:
                i = (k + 1) // per
                v_out[:, i] = v
                x_out[:, i] = x
    return v_out, x_out, n_kicks


# ------------------------------------------------------------ event-driven (pure shot noise)
def _closed_form_flow(model) -> bool:
    """True when the flow between kicks is the paper's closed form (linear viscous friction and
    a constant sgn friction, no spring): the event-driven scheme is then exact."""
    return model.closed_form and model.epsilon == 0


_FLOW_ROUTES = {"exact": "event-driven, exact between kicks",
                "table": "event-driven, tabulated flow between kicks",
                "rk4": "event-driven, RK4 between kicks"}


def _flow_route(model, tabulate: bool = True) -> str:
    """How the event-driven scheme moves between kicks: the closed form, a table of the
    one-dimensional flow, or RK4 (with a spring: the position feeds back)."""
    if _closed_form_flow(model):
        return "exact"
    return "table" if model.dimension == 1 and tabulate else "rk4"


def _flow_exact(model, v, s):
    """Noise-free flow of the paper's law over durations ``s`` (arrays): ``(v(s), int_0^s v)``.

    Mirrored so that the start lies on the upper half line (u = sgn v >= 0, a' = sgn a): there
    ``u(t) = (u + b) e^{-t/tau} - b`` with ``b = (Delta - a') tau`` (eq. (16)), which
    reaches 0 at ``t1 = tau ln(1 + u/b)`` if b > 0; then the object sticks (|a| <= Delta) or
    crosses and relaxes on the other side, ``-|b2| (1 - e^{-t'/tau})``, b2 = (Delta + a') tau."""
    tau, d, a = model.tau_m, model.delta, model.a
    leave = math.copysign(1.0, a) if abs(a) > d else 0.0
    sgn = np.where(v != 0, np.sign(v), leave)
    u = sgn * v
    ap = sgn * a
    b = (d - ap) * tau
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = np.where(b > 0, tau * np.log1p(np.where(b > 0, u / np.where(b > 0, b, 1.0), 0.0)), np.inf)
    s1 = np.minimum(s, t1)
    e1 = np.exp(-s1 / tau)
    u_end = (u + b) * e1 - b
    dx = (u + b) * tau * (1.0 - e1) - b * s1
    after = s > t1
    if abs(a) <= d:
        u_end = np.where(after, 0.0, u_end)
    else:
        t2 = np.where(after, s - t1, 0.0)
        b2 = np.abs((d + ap) * tau)
        e2 = np.exp(-t2 / tau)
        u_end = np.where(after, -b2 * (1.0 - e2), u_end)
        dx = dx + np.where(after, -b2 * (t2 - tau * (1.0 - e2)), 0.0)
    u_end = np.where(sgn == 0, 0.0, u_end)
    dx = np.where(sgn == 0, 0.0, dx)
    return sgn * u_end, sgn * dx


def _rhs(model, v, pos, sgn):
    """dv/dt with the friction sign fixed to ``sgn`` (0: the smooth tanh law)."""
    fr = model.coulomb(v) if model.epsilon > 0 else sgn * model.friction_magnitude(v)
    out = model.a - v / model.tau_m - fr
    return model.restoring.add_force(model.friction.add_drift(out, v), pos)


def _flow_rk4(model, v, x, s, dt):
    """Noise-free flow of any member over durations ``s`` by RK4 substeps of at most ``dt``
    (per replica: ``s/n`` with n common), the friction sign fixed over each substep.  A sign
    change within a substep means v reached 0: the replica sticks (v = 0, x frozen) if
    ``|a - spring (x0 + x)| <= Delta(0)``, else it crosses (its new side is kept).  A stuck
    replica stays until a kick, or leaves at once when the static force exceeds Delta(0)."""
    n = max(1, int(math.ceil(float(np.max(s)) / dt - 1e-9))) if s.size else 0
    h = s / max(n, 1)
    smooth = model.epsilon > 0
    for _ in range(n):
        pos = model.x0 + x
        if smooth:
            sgn = np.zeros_like(v)
        else:
            f0 = model.a - model.spring * pos
            leave = np.where(np.abs(f0) > model.static_friction, np.sign(f0), 0.0)
            sgn = np.where(v != 0, np.sign(v), leave)
        moving = (sgn != 0) | smooth
        k1v = _rhs(model, v, pos, sgn)
        k1x = v
        k2v = _rhs(model, v + 0.5 * h * k1v, pos + 0.5 * h * k1x, sgn)
        k2x = v + 0.5 * h * k1v
        k3v = _rhs(model, v + 0.5 * h * k2v, pos + 0.5 * h * k2x, sgn)
        k3x = v + 0.5 * h * k2v
        k4v = _rhs(model, v + h * k3v, pos + h * k3x, sgn)
        k4x = v + h * k3v
        v_new = v + h / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v)
        dx = h / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x)
        if not smooth:
            crossed = moving & (np.sign(v_new) != sgn)
            if crossed.any():
                # linear estimate of the arrival at 0 for the position; then stick or cross
                theta = np.where(crossed, np.abs(v) / np.maximum(np.abs(v) + np.abs(v_new), 1e-300), 1.0)
                pos_c = pos + theta * dx
                stick = crossed & (np.abs(model.a - model.spring * pos_c) <= model.static_friction)
                dx = np.where(stick, theta * 0.5 * h * v, dx)
                v_new = np.where(stick, 0.0, v_new)
        v = np.where(moving, v_new, 0.0)
        x = x + np.where(moving, dx, 0.0)
    return v, x


def _table_for(model, v):
    """The tabulated flow (:mod:`analogue.theory.flow_table`) over twice the range the
    Kolmogorov-Feller grid covers (the stationary reach plus 45 kick means) and the starts."""
    lo, hi = _grid_range(model)
    span = hi - lo
    return flow_table(model, min(lo - 0.5 * span, float(v.min())),
                      max(hi + 0.5 * span, float(v.max())))


def _flow_tabulated(model, table, v, x, s, dt):
    """The tabulated flow for replicas inside the table, RK4 for any kicked beyond it."""
    inside = table.covers(v)
    if inside.all():
        v_new, dx = table.flow(v, s)
        return v_new, x + dx
    v, x = v.copy(), x.copy()
    v[inside], dx = table.flow(v[inside], s[inside])
    x[inside] += dx
    out = ~inside
    v[out], x[out] = _flow_rk4(model, v[out], x[out], s[out], dt)
    return v, x


def _event_driven(model, v, n_out, sample_dt, dt, rng, tabulate=True):
    """Pure shot noise (gamma = inf): kicks at exact exponential waiting times per replica;
    between kicks the noise-free flow, exact (:func:`_flow_exact`) for the paper's friction law,
    tabulated once (:mod:`analogue.theory.flow_table`, ~1e-9 of the velocity scale) for the
    other one-dimensional members, RK4 (:func:`_flow_rk4`) with a spring.  Vectorised over replicas: each round
    moves every replica to its next kick or the next output time, whichever is first."""
    noise = model.noise_kind
    replicas = v.size
    v = v.astype(float).copy()
    x = np.zeros(replicas)
    v_out = np.empty((replicas, n_out))
    x_out = np.empty((replicas, n_out))
    v_out[:, 0], x_out[:, 0] = v, 0.0
    t_now = np.zeros(replicas)
    t_kick = rng.exponential(1.0 / noise.shot.rate, replicas)
    route = _flow_route(model, tabulate)
    exact = route == "exact"
    table = _table_for(model, v) if route == "table" else None
    n_kicks = 0
    for i in range(1, n_out):
        t_stop = i * sample_dt
        while True:
            target = np.minimum(t_kick, t_stop)
            s = target - t_now
            if exact:
                v_new, dx = _flow_exact(model, v, s)
                v, x = v_new, x + dx
            elif table is not None:
                v, x = _flow_tabulated(model, table, v, x, s, dt)
            else:
                v, x = _flow_rk4(model, v, x, s, dt)
            t_now = target
            kicked = t_kick <= t_stop
            if not kicked.any():
                break
            m = int(kicked.sum())
            n_kicks += m
            v[kicked] += noise.kick(m, rng)
            t_kick[kicked] += rng.exponential(1.0 / noise.shot.rate, m)
        t_now[:] = t_stop
        v_out[:, i], x_out[:, i] = v, x
    return v_out, x_out, n_kicks
