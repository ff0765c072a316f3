"""Everything that may reach a SPICE deck passes through here.

A deck is a program for ngspice (``.control`` blocks can run shell commands), so no user
string may reach one unchecked: names must match a strict identifier pattern and numbers are
formatted here from finite floats, never copied from user text.
"""
from __future__ import annotations

import re

from .. import checks

__all__ = ["NAME_PATTERN", "check_name", "finite", "positive", "nonnegative", "spice_number"]

NAME_PATTERN = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,31}")


def check_name(value, what: str = "name") -> str:
    """Return ``value`` if it is a safe SPICE identifier, else raise ValueError."""
    if not isinstance(value, str) or NAME_PATTERN.fullmatch(value) is None:
        raise ValueError(f"{what} must match ^[A-Za-z][A-Za-z0-9_]{{0,31}}$ "
                         f"(letters, digits, underscore; at most 32 characters), got {value!r}")
    return value


def _number(value, what: str):
    # Stricter than analogue.checks: a bool or a string is never meant as a number in a deck
    # (float("1e3") would otherwise let text through).
    if isinstance(value, (bool, str, bytes)):
        raise ValueError(f"{what} must be a finite real number, got {value!r}")
    return value


def finite(value, what: str) -> float:
    """A finite float (bools and strings are refused: they are never meant as numbers here)."""
    return checks.finite(what, _number(value, what))


def positive(value, what: str) -> float:
    return checks.positive(what, _number(value, what))


def nonnegative(value, what: str) -> float:
    return checks.nonnegative(what, _number(value, what))


def spice_number(value, what: str = "value") -> str:
    """Format a finite float for a deck: 15 significant digits (decks must be deterministic
    and round-trip to the same double up to 1e-15 relative), no SPICE unit suffixes."""
    x = finite(value, what)
    if x == 0:
        return "0"
    return format(x, ".15g")
