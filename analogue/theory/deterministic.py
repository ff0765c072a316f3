"""Noise-free motion of every member of the model family: the theory package's name for
:mod:`analogue.noise_free` (the solver lives there, below the model, which calls it; its
docstring says how the motion is integrated).  Imported from here since before the move.
"""
from __future__ import annotations

from ..noise_free import flow, stick_time

__all__ = ["flow", "stick_time"]
