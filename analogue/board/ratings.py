"""Parts inside their datasheet limits, read off a simulated board (issue 21).

:func:`opamp_instances` lists every op-amp of a board deck (instance, non-inverting and
inverting input nodes, role); :func:`common_mode_margins` measures, over a transient saved
with every node (``build_board_deck(..., save_all=True)``), how far each op-amp's inputs stay
inside the *guaranteed* input common-mode range of its part (the ``_worst`` set): a negative
margin is a part outside its datasheet range, where a TL07x inverts its output.
"""
from __future__ import annotations

import re

import numpy as np

from .design import BoardDesign
from .netlist import BoardInstance, role_part
from .opamp import get_opamp

__all__ = ["common_mode_margins", "opamp_instances"]

_X = re.compile(r"^(X\S+)\s+(\S+)\s+(\S+)\s+vcc\s+vee\s+\S+\s+opa_(\w+)\s*$", re.MULTILINE)


def opamp_instances(deck_text: str) -> list[tuple[str, str, str, str]]:
    """(instance, in+ node, in- node, role) of every op-amp in a board deck."""
    return [(m.group(1), m.group(2), m.group(3), m.group(4)) for m in _X.finditer(deck_text)]


def _node(plot, node: str) -> np.ndarray | None:
    if node == "0":
        return np.zeros(len(plot["time"]))
    name = f"v({node.lower()})"
    return plot[name] if name in plot.names else None


def common_mode_margins(design: BoardDesign, board: BoardInstance, deck_text: str, plot) -> dict:
    """Per op-amp instance: the part, its guaranteed common-mode range at the board's rails,
    the extreme input voltages over the transient, and the margins (V) to the lower and upper
    limits (positive: inside).  ``plot`` must hold every node (``save_all``)."""
    out = {}
    for inst, inp, inn, role in opamp_instances(deck_text):
        part = get_opamp(role_part(design, role))
        lo, hi = part.guaranteed.common_mode_range(board.rails)
        volts = [v for v in (_node(plot, inp), _node(plot, inn)) if v is not None]
        if not volts:
            raise ValueError(f"the plot holds neither input of {inst}; build the deck with save_all=True")
        vmin = float(min(np.min(v) for v in volts))
        vmax = float(max(np.max(v) for v in volts))
        out[inst] = {"part": part.name, "role": role, "range": [lo, hi], "min": vmin,
                     "max": vmax, "margin_low": vmin - lo, "margin_high": hi - vmax}
    return out
