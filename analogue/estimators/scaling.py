"""Local exponent of a measured curve on log-log axes (issue 23: diffusion against noise
strength, whose exponent experiments quote -- 1.61 measured by Goohpattader, Mettu &
Chaudhury, Langmuir 2009; the exact one is :func:`analogue.theory.bias_transport.
diffusion_exponent`).

Between neighbouring points ``(x_i, y_i)`` and ``(x_{i+1}, y_{i+1})`` of a sweep, independent
estimates with standard errors ``s_i``:

    e = ln(y_{i+1}/y_i) / ln(x_{i+1}/x_i)     at     x_mid = sqrt(x_i x_{i+1}),
    se(e) = sqrt((s_i/y_i)^2 + (s_{i+1}/y_{i+1})^2) / |ln(x_{i+1}/x_i)|

(first-order error propagation; the points of a sweep are independent runs).  The chord
slope is the local exponent at ``x_mid`` up to O((ln x_{i+1}/x_i)^2) times the curvature.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .. import checks

__all__ = ["local_exponent"]


def local_exponent(x: ArrayLike, y: ArrayLike, y_se: ArrayLike | None = None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(x_mid, exponent, stderr)`` of the chord slopes of ``ln y`` against ``ln x``
    (module docstring).  ``x`` strictly monotone and > 0, ``y`` > 0; without ``y_se`` the
    standard errors are NaN."""
    xs = checks.finite_array("x", x)
    ys = checks.finite_array("y", y)
    if xs.ndim != 1 or xs.size < 2 or ys.shape != xs.shape:
        raise ValueError("x and y must be 1-D of the same length >= 2")
    if np.any(xs <= 0) or np.any(ys <= 0):
        raise ValueError("x and y must be > 0 (log-log axes)")
    step = np.diff(np.log(xs))
    if not (np.all(step > 0) or np.all(step < 0)):
        raise ValueError("x must be strictly monotone")
    exponent = np.diff(np.log(ys)) / step
    mid = np.sqrt(xs[1:] * xs[:-1])
    if y_se is None:
        return mid, exponent, np.full(exponent.shape, np.nan)
    se = checks.finite_array("y_se", y_se)
    if se.shape != ys.shape or np.any(se < 0):
        raise ValueError("y_se must be >= 0 with the shape of y")
    rel = se / ys
    return mid, exponent, np.sqrt(rel[1:] ** 2 + rel[:-1] ** 2) / np.abs(step)
