"""Noise-free motion of every member of the model family (cubic, Stribeck, spring).

The paper's model has the closed form of :meth:`analogue.Model.deterministic`; the
extensions are integrated numerically.  With the exact sgn law the motion is split at
``v = 0``: on each half line the friction sign is fixed, so the ODE is smooth and an
8th-order Runge-Kutta with the event ``v = 0`` locates the arrival exactly.  At rest the
object sticks for good (without noise) if the net static force obeys
``|a - spring x| <= Delta(0)``, else it leaves in the direction of that force.

The solver itself is :mod:`analogue.noise_free` (below the model, which calls it); this module is
its home in the theory package, where it has always been imported from.
"""
from __future__ import annotations

from ..noise_free import flow, stick_time

__all__ = ["flow", "stick_time"]
