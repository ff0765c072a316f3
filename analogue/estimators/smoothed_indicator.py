"""Integration differences of indicator observables by smoothed perturbation analysis.

The report's integration term (:mod:`analogue.study.runs`) is the mean path-by-path
difference ``d`` between the nominal circuit run and a re-run with 100x tighter tolerances on
the same noise.  For a smooth observable (a mean, a variance, a work rate) ``d`` is a smooth
function of the path-wise integration error ``delta`` and averages down quickly.  For an
indicator observable, ``1[v in (lo, hi)]`` (the stick fraction, P(v > 0), P(v < 0) at time
t), ``d`` counts the rare samples that fall on the other side of an edge in the two runs: a
few discrete flips, whose noise is ~10x the smooth observables' and decides how many paths
the check must re-run (issue 10: the check was half the stationary run, at 4-5x the nominal
cost per unit time).

Smoothed perturbation analysis (Fu & Hu 1997; Glasserman 2004, Monte Carlo Methods in
Financial Engineering, sect. 7.2.3) replaces the indicator by its convolution with a Gaussian
of width ``h``,

    S_h(v) = Phi((hi - v)/h) - Phi((lo - v)/h),

so that the difference of the two runs, ``S_h(v + delta) - S_h(v) ~ delta S_h'(v)``, is smooth
in ``delta``.  Its mean differs from the indicator's by the kernel's bias: ``g = 1_A - S_h``
is odd about each edge, so ``int g (p_nominal - p_check) dv = -(h^2/2) Dp'(edge) + O(h^4)``
with ``Dp`` the change of the density the integration error makes.  That bias is estimated
from ``h`` and ``h/2`` by one Richardson step, ``(4/3) |d_h - d_{h/2}|``, and booked with the
term (:func:`analogue.study.budget.integration_term`).

Measured (work experiment's model, trap reltol 3e-5 against gear 3e-7 on the same noise, 32
stationary replicas x 48 time units after the burn-in, two noise seeds; per-path values in
units of the observable's spread over paths, mean +- SE):

=================  ==================================  ===================================
observable         indicator (flips)                   smoothed, h = threshold / 4 .. / 16
=================  ==================================  ===================================
stick fraction     -0.0031 +- 0.0014, sd 0.0080        -0.0022 .. -0.0024 +- 0.0001, sd 0.0005-0.0009
                   -0.0012 +- 0.0021, sd 0.0118        -0.0022 .. -0.0026 +- 0.0002, sd 0.0006-0.0013
P(v > 0)           +0.0025 +- 0.0013, sd 0.0075        +0.0013 .. +0.0016 +- 0.0002, sd 0.0006-0.0010
                   +0.0015 +- 0.0010, sd 0.0057        +0.0015 .. +0.0016 +- 0.0002, sd 0.0006-0.0015
=================  ==================================  ===================================

The smoothed means agree with the flip counts within the latter's errors at every ``h`` from
``threshold/4`` down to ``epsilon/16``, with 5-15x smaller spread: for the check's own noise
(2 SE) to stay below 0.05 statistical errors of a 256-path run, counting flips needs 14-59
re-run paths, the smoothed indicator 1-3 (``benchmarks/bench_integration_check.py``).  The
report's check was 128 paths (half the work experiment's stationary run, at 3.3-4.5x the
nominal cost per unit time); it is now 16.

Limits: the Richardson step assumes the density change ``Dp`` is smooth on the scale ``h``
at each edge.  A path-wise error that jumped exactly at an edge would break it (then ``d_h
-> -delta p(edge)/2``, not the indicator's 0, as ``h -> 0``; tested).  The circuit's edges are
the stick threshold, where nothing happens to the dynamics, and v = 0, where the diode
bridge's tanh law varies on the scale ``epsilon >= 4 h``; the measurement above and the
Richardson terms the report books (at most a few 1e-5 of the observable) show no such jump.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.special import ndtr

__all__ = ["KERNEL_FRACTION", "kernel_width", "window"]

# h = KERNEL_FRACTION x the smaller of the stick threshold and the circuit's smoothing width
# epsilon: the edges at +-threshold sit in the sliding law's exponential tail (scale
# 1/(gamma (Delta + |a|)) >> threshold), the edge at v = 0 inside the stuck peak (scale
# epsilon), so h << both keeps the kernel's bias small; the Richardson term measures what
# is left.
KERNEL_FRACTION = 0.25


def kernel_width(threshold: float, epsilon: float) -> float:
    """The smoothing width ``h`` for the integration differences of indicator observables:
    ``KERNEL_FRACTION * min(threshold, epsilon)`` over the positive ones (0 when both are 0:
    then the indicators are left as they are)."""
    scales = [s for s in (float(threshold), float(epsilon)) if s > 0 and math.isfinite(s)]
    return KERNEL_FRACTION * min(scales) if scales else 0.0


def window(v: np.ndarray, lo: float = -math.inf, hi: float = math.inf,
           h: float = 0.0) -> np.ndarray:
    """``1[lo < v < hi]`` as floats (``h = 0``) or its Gaussian-smoothed version
    ``Phi((hi - v)/h) - Phi((lo - v)/h)`` (an infinite edge contributes 0 or 1)."""
    v = np.asarray(v, dtype=float)
    if not h > 0:
        if math.isinf(lo):
            return (v < hi).astype(float)
        if math.isinf(hi):
            return (v > lo).astype(float)
        return ((v > lo) & (v < hi)).astype(float)
    upper = ndtr((hi - v) / h) if math.isfinite(hi) else 1.0
    lower = ndtr((lo - v) / h) if math.isfinite(lo) else 0.0
    return np.asarray(upper - lower, dtype=float)
