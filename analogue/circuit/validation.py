"""Everything that may reach a SPICE deck passes through here.

A deck is a program for ngspice (``.control`` blocks can run shell commands), so no user
string may reach one unchecked: names must match a strict identifier pattern and numbers are
formatted here from finite floats, never copied from user text.
"""
from __future__ import annotations

import math
import re

from .. import checks

__all__ = ["NAME_PATTERN", "check_name", "finite", "positive", "nonnegative", "spice_number",
           "check_spec_ranges", "check_mapping_values", "SPEC_RANGES"]

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


# Ranges of the circuit choices a deck can be built from.  Outside them the derived component
# values leave the range ngspice computes with (time_scale = 1e300 gives R = 1e307 ohm and
# currents of 1e-307 A, far below abstol; 1e-300 overflows the currents), so they are refused
# naming the parameter.  Wide on purpose: a picosecond to 1000 s per model time unit, a
# femtofarad to a kilofarad, a microvolt to a kilovolt per unit velocity.
SPEC_RANGES = {
    "time_scale": (1e-12, 1e3),
    "capacitance": (1e-15, 1e3),
    "volts_per_velocity": (1e-6, 1e3),
}


def check_spec_ranges(spec, where: str = "circuit") -> None:
    """Refuse circuit choices outside :data:`SPEC_RANGES` (ValueError naming the parameter)."""
    for name, (lo, hi) in SPEC_RANGES.items():
        value = getattr(spec, name, None)
        if value is not None and not lo <= value <= hi:
            raise ValueError(f"{where}.{name} must be in [{lo:g}, {hi:g}], got {value!r} (the "
                             f"derived component values would leave the range ngspice computes "
                             f"with)")


# Component values (mapping.table() rows) that must be > 0 when present in the deck.
_POSITIVE = ("theta", "kappa", "C", "R", "R_total", "noise_TS", "noise_gain", "C_x", "g_x", "vntol")
_TINY = 1e-300  # below this a "positive" value is an underflow, not a component


def check_mapping_values(mapping, what: str = "circuit") -> None:
    """Every derived component value finite, and the positive ones not underflowed: a value
    that overflowed or underflowed is refused naming it and the circuit choices it comes from."""
    spec = mapping.spec
    inputs = (f"time_scale={spec.time_scale:g}, capacitance={spec.capacitance:g}, "
              f"volts_per_velocity={mapping.kappa:g}, noise_dt={mapping.noise_dt:g}")
    for name, value, unit, _ in mapping.table():
        x = float(value)
        if not math.isfinite(x) or (name in _POSITIVE and not abs(x) >= _TINY):
            raise ValueError(f"{what} circuit: {name}={x:g} {unit} is out of range (derived from "
                             f"{inputs} and the model); change circuit.time_scale, "
                             f"circuit.capacitance or the [model] values")
