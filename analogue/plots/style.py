"""Shared look of the theory figures: colours, figure creation without pyplot, saving."""
from __future__ import annotations

from pathlib import Path

from matplotlib.figure import Figure

__all__ = ["KIND_COLOURS", "DPI", "new_figure", "save", "VELOCITY", "TIME"]

DPI = 120
VELOCITY = "velocity v (model units)"
TIME = "time t (units of tau_m)"

# one colour per optimal-path kind, the same in every figure
KIND_COLOURS = {
    "direct": "tab:blue",
    "direct-crossing": "tab:red",
    "indirect": "tab:purple",
    "indirect-crossing": "tab:green",
    "twice-crossing": "tab:orange",
}


def new_figure(nrows: int = 1, ncols: int = 1, *, width: float = 5.0, height: float = 3.6,
               squeeze: bool = True):
    """A Figure (Agg canvas, no pyplot state) with a grid of Axes of the given panel size."""
    fig = Figure(figsize=(width * ncols, height * nrows), layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=squeeze)
    return fig, axes


def save(fig: Figure, path: Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=DPI)
    return path
