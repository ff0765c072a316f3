"""Argument checks shared by the physics modules: a clear ValueError naming the parameter."""
from __future__ import annotations

import math

import numpy as np

__all__ = ["ArgumentTypeError", "finite", "finite_array", "nonnegative", "positive"]


def finite(name: str, value) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number, got {value!r}") from None
    if not math.isfinite(x):
        raise ValueError(f"{name} must be finite, got {x!r}")
    return x


def positive(name: str, value) -> float:
    x = finite(name, value)
    if not x > 0:
        raise ValueError(f"{name} must be > 0, got {x!r}")
    return x


def nonnegative(name: str, value) -> float:
    x = finite(name, value)
    if not x >= 0:
        raise ValueError(f"{name} must be >= 0, got {x!r}")
    return x


def finite_array(name: str, value) -> np.ndarray:
    try:
        x = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be real numbers, got {value!r}") from None
    if not np.all(np.isfinite(x)):
        raise ValueError(f"{name} must be finite")
    return x


class ArgumentTypeError(TypeError, ValueError):
    """An argument of the wrong type (a TypeError).  Also a ValueError, because these were
    reported as ValueError before and callers may catch that."""
