"""Monte Carlo reference: the reduced Langevin equation (paper, eq. bm) integrated in numpy.

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

from .ensemble import Ensemble
from .model import Model
from .theory.stationary import sample_stationary

__all__ = ["simulate_sde", "standard_noise", "default_dt", "SCHEMES"]

SCHEMES = ("exponential", "euler")
_ALIASES = {"em": "euler", "euler-maruyama": "euler", "euler_maruyama": "euler",
            "ou": "exponential", "exact-ou": "exponential", "exact_ou": "exponential"}
_MAX_OUTPUT_POINTS = 1000
_BLOCK_NUMBERS = 1 << 20  # normals generated per block (8 MB)


def default_dt(model: Model) -> float:
    """``min(tau_m/500, t_kink/50, 0.1 epsilon/Delta)``.

    ``t_kink = 2/(gamma (Delta + |a|)^2)`` is the time in which the friction drift carries a
    particle as far as the noise spreads it near ``v = 0`` (the stick time of a thermal
    excursion), which for large gamma is much shorter than tau_m; ``epsilon/Delta`` is the
    relaxation time of the smooth law at ``v = 0``.
    """
    dt = model.tau_m / 500.0
    if model.delta > 0:
        t_kink = 2.0 / (model.gamma * (model.delta + abs(model.a)) ** 2)
        dt = min(dt, t_kink / 50.0)
        if model.epsilon > 0:
            dt = min(dt, 0.1 * model.epsilon / model.delta)
    return dt


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
    init, noise = root.spawn(2)
    return init, noise


def standard_noise(seed, replicas: int, n_steps: int) -> np.ndarray:
    """The standard normals (shape (replicas, n_steps)) that :func:`simulate_sde` draws for
    ``seed`` (an int or SeedSequence): passing them as ``noise=`` reproduces the seeded run."""
    _, rng = _streams(seed)
    return rng.standard_normal((int(n_steps), int(replicas))).T


def _positive_float(name, value) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number > 0, got {value!r}") from None
    if not (math.isfinite(x) and x > 0):
        raise ValueError(f"{name} must be finite and > 0, got {value!r}")
    return x


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


def simulate_sde(model: Model, *, v0, t_end: float, replicas: int, seed=None, dt: float | None = None,
                 sample_dt: float | None = None, noise: np.ndarray | None = None,
                 scheme: str = "exponential") -> Ensemble:
    """Integrate eq. (bm) for ``replicas`` independent trajectories from t = 0 to ``t_end``.

    Parameters
    ----------
    v0 : float, array (replicas,), or "stationary"
        Initial velocities; "stationary" draws them from ``p_s`` (eq. p_stat) with
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

    Returns
    -------
    Ensemble with t (n_out,), v and x (replicas, n_out), meta: source="sde", seed, dt,
    sample_dt, scheme, noise ("seeded" or "given"), v0, model parameters.
    """
    if not isinstance(model, Model):
        raise ValueError(f"model must be an analogue.Model, got {type(model).__name__}")
    scheme = _ALIASES.get(scheme, scheme) if isinstance(scheme, str) else scheme
    if scheme not in SCHEMES:
        raise ValueError(f"scheme must be one of {SCHEMES} (or an alias), got {scheme!r}")
    t_end = _positive_float("t_end", t_end)
    if isinstance(replicas, (bool, np.bool_)) or not isinstance(replicas, numbers.Integral) or replicas < 1:
        raise ValueError(f"replicas must be an int >= 1, got {replicas!r}")
    replicas = int(replicas)
    dt = None if dt is None else _positive_float("dt", dt)
    sample_dt = None if sample_dt is None else _positive_float("sample_dt", sample_dt)
    if sample_dt is not None and sample_dt > t_end * (1 + 1e-12):
        raise ValueError(f"sample_dt={sample_dt!r} must be <= t_end={t_end!r}")
    dt, per, n_steps = _time_grid(model, t_end, dt, sample_dt)
    init_rng, noise_rng = _streams(seed)

    if noise is not None:
        noise = np.asarray(noise, dtype=float)
        if noise.shape != (replicas, n_steps):
            raise ValueError(f"noise must have shape (replicas, n_steps) = {(replicas, n_steps)}, "
                             f"got {noise.shape}")
        if not np.all(np.isfinite(noise)):
            raise ValueError("noise must be finite")

    if isinstance(v0, str):
        if v0 != "stationary":
            raise ValueError(f"v0 must be a number, an array (replicas,), or 'stationary', got {v0!r}")
        v = sample_stationary(model, replicas, seed=init_rng)
        v0_meta = "stationary"
    else:
        try:
            v = np.broadcast_to(np.asarray(v0, dtype=float), (replicas,)).copy()
        except (ValueError, TypeError):
            raise ValueError(f"v0 must be a number, an array of shape ({replicas},) or "
                             f"'stationary', got shape {np.shape(v0)}") from None
        if not np.all(np.isfinite(v)):
            raise ValueError("v0 must be finite")
        v0_meta = float(v0) if np.ndim(v0) == 0 else "array"

    tau, g = model.tau_m, model.gamma
    if scheme == "exponential":
        r = math.exp(-dt / tau)
        lin, push, amp = r, tau * (1.0 - r), math.sqrt(tau / g * (1.0 - r * r))
    else:
        lin, push, amp = 1.0 - dt / tau, dt, math.sqrt(2.0 * dt / g)

    n_out = n_steps // per + 1
    v_out = np.empty((replicas, n_out))
    x_out = np.empty((replicas, n_out))
    x = np.zeros(replicas)
    v_out[:, 0] = v
    x_out[:, 0] = 0.0
    block = max(1, _BLOCK_NUMBERS // replicas)
    a = model.a
    for start in range(0, n_steps, block):
        stop = min(n_steps, start + block)
        xi = (noise[:, start:stop].T if noise is not None
              else noise_rng.standard_normal((stop - start, replicas)))
        for j, k in enumerate(range(start, stop)):
            v_new = lin * v + push * (a - model.coulomb(v)) + amp * xi[j]
            x += 0.5 * dt * (v + v_new)
            v = v_new
            if (k + 1) % per == 0:
                i = (k + 1) // per
                v_out[:, i] = v
                x_out[:, i] = x

    t = np.arange(n_out) * (per * dt)
    meta = {"source": "sde", "seed": int(seed) if isinstance(seed, numbers.Integral) else None,
            "dt": dt, "sample_dt": per * dt, "scheme": scheme,
            "noise": "given" if noise is not None else "seeded", "v0": v0_meta,
            "replicas": replicas, "model": model.as_dict()}
    return Ensemble(t, v_out, x_out, meta)
