"""Argument checks: the one home of every check the package makes on its arguments.

Every check takes ``(name, value)`` (also by keyword: ``positive(name="t_end", value=x)``),
returns the value in its canonical type and raises an error that names the parameter and the
allowed range: :class:`ArgumentTypeError` (a ``TypeError``) for a wrong type, ``ValueError``
for a wrong value.  Options are keyword-only.

Numbers are strict: a bool or a string is never meant as a number (``float("1e3")`` would
otherwise let text into a SPICE deck, and ``True`` would pass as 1.0).  Numeric types
(``int``, ``float``, numpy scalars and 0-d arrays, anything with ``__float__``) are accepted.

The deck-safety checks are here too.  A SPICE deck is a program for ngspice (``.control``
blocks can run shell commands), so no user string may reach one unchecked: names must match
:data:`NAME_PATTERN` (:func:`identifier`) and numbers are formatted from finite floats by
:func:`spice_number`, never copied from user text.
"""
from __future__ import annotations

import math
import re
from numbers import Integral
from typing import TypeVar

import numpy as np

__all__ = ["ArgumentTypeError", "NAME_PATTERN", "finite", "finite_array", "flag", "identifier",
           "in_range", "instance", "integer", "nonnegative", "optional_flag", "positive", "real",
           "spice_number"]


class ArgumentTypeError(TypeError, ValueError):
    """An argument of the wrong type (a TypeError).  Also a ValueError, because these were
    reported as ValueError before and callers may catch that."""


T = TypeVar("T")


# ----------------------------------------------------------------------------- numbers
def real(name: str, value: object, *, allow_inf: bool = False) -> float:
    """A real number as a float: NaN refused, infinities refused unless ``allow_inf`` (then
    only +inf, as ``gamma = inf`` switching the Gaussian noise off)."""
    if isinstance(value, (bool, np.bool_, str, bytes)):
        raise ArgumentTypeError(f"{name} must be a real number, got {type(value).__name__} "
                                f"{value!r}")
    try:
        x = float(value)  # type: ignore[arg-type]
    except OverflowError:  # an int beyond the float range
        x = math.inf if value > 0 else -math.inf  # type: ignore[operator]
    except (TypeError, ValueError):
        raise ArgumentTypeError(f"{name} must be a real number, got {type(value).__name__} "
                                f"{value!r}") from None
    if math.isnan(x) or (math.isinf(x) and not (allow_inf and x > 0)):
        raise ValueError(f"{name} must be finite, got {x!r}")
    return x


def finite(name: str, value: object) -> float:
    """A finite real number."""
    return real(name, value)


def positive(name: str, value: object, *, allow_inf: bool = False) -> float:
    """A real number > 0 (finite unless ``allow_inf``)."""
    x = real(name, value, allow_inf=allow_inf)
    if not x > 0:
        raise ValueError(f"{name} must be > 0, got {x!r}")
    return x


def nonnegative(name: str, value: object) -> float:
    """A finite real number >= 0."""
    x = real(name, value)
    if not x >= 0:
        raise ValueError(f"{name} must be >= 0, got {x!r}")
    return x


def in_range(name: str, value: object, low: float, high: float, *, closed: bool = True,
             why: str = "") -> float:
    """A finite real number in ``[low, high]`` (``(low, high)`` if not ``closed``); ``why``
    (e.g. "the derived component values would leave ...") is appended to the message."""
    x = real(name, value)
    if not (low <= x <= high if closed else low < x < high):
        interval = f"[{low:g}, {high:g}]" if closed else f"({low:g}, {high:g})"
        raise ValueError(f"{name} must be in {interval}, got {x!r}" + (f" ({why})" if why else ""))
    return x


def integer(name: str, value: object, *, minimum: int | None = None,
            maximum: int | None = None) -> int:
    """An int (or numpy integer) in ``[minimum, maximum]``; bools, floats and strings are
    refused (a float count is a mistake, not something to round)."""
    if minimum is not None and maximum is not None:
        rule = f"an integer in [{minimum}, {maximum}]"
    elif minimum is not None or maximum is not None:
        rule = f"an integer >= {minimum}" if minimum is not None else f"an integer <= {maximum}"
    else:
        rule = "an integer"
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, Integral):
        raise ArgumentTypeError(f"{name} must be {rule}, got {value!r}")
    n = int(value)
    if (minimum is not None and n < minimum) or (maximum is not None and n > maximum):
        raise ValueError(f"{name} must be {rule}, got {n}")
    return n


def flag(name: str, value: object) -> bool:
    """True or False (numpy bools too), nothing else (not 0 or 1: a flag given as a number
    is a mistake)."""
    if not isinstance(value, (bool, np.bool_)):
        raise ArgumentTypeError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def optional_flag(name: str, value: object, *, none_means: str) -> bool | None:
    """True, False or None; ``none_means`` (e.g. ``"auto"``) says what None does."""
    if value is None:
        return None
    if not isinstance(value, (bool, np.bool_)):
        raise ArgumentTypeError(f"{name} must be True, False or None ({none_means}), "
                                f"got {value!r}")
    return bool(value)


def instance(name: str, value: object, kind: type[T], *, description: str) -> T:
    """``value`` if it is an instance of ``kind`` (``description`` says what in the message:
    "an analogue.Model"), else :class:`ArgumentTypeError`."""
    if not isinstance(value, kind):
        raise ArgumentTypeError(f"{name} must be {description}, got {type(value).__name__}")
    return value


def finite_array(name: str, value: object) -> np.ndarray:
    """An array of finite floats (any shape)."""
    try:
        x = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be real numbers, got {value!r}") from None
    if not np.all(np.isfinite(x)):
        raise ValueError(f"{name} must be finite")
    return x


# ----------------------------------------------------------------------------- deck safety
NAME_PATTERN = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,31}")


def identifier(name: str, value: object) -> str:
    """``value`` if it is a safe SPICE identifier (:data:`NAME_PATTERN`), else ValueError."""
    if not isinstance(value, str) or NAME_PATTERN.fullmatch(value) is None:
        raise ValueError(f"{name} must match ^[A-Za-z][A-Za-z0-9_]{{0,31}}$ "
                         f"(letters, digits, underscore; at most 32 characters), got {value!r}")
    return value


def spice_number(name: str, value: object) -> str:
    """A finite real number formatted for a deck: 15 significant digits (decks must be
    deterministic and round-trip to the same double up to 1e-15 relative), no SPICE unit
    suffixes."""
    x = finite(name, value)
    if x == 0:
        return "0"
    return format(x, ".15g")
