"""Shared look of the theory figures: colours, figure creation without pyplot, saving."""
from __future__ import annotations

from pathlib import Path

import matplotlib as mpl
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.layout_engine import ConstrainedLayoutEngine

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
    """A Figure (Agg canvas, no pyplot state) with a grid of Axes of the given panel size.

    The Figure is made at the saving resolution :data:`DPI`, so that its constrained layout,
    computed once in :func:`save`, measures text with the renderer that draws the PNG."""
    fig = Figure(figsize=(width * ncols, height * nrows), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, ncols, squeeze=squeeze)
    return fig, axes


def freeze_layout(fig: Figure) -> None:
    """Run the figure's constrained layout once and fix the Axes where it put them.

    ``savefig`` on a figure with a layout engine draws it twice (a draw without rendering so
    that the layout can settle, then the real one), and each draw runs the whole constrained
    layout (tight boxes of every Axes: its ticks, tick labels and text, twice per pass): in
    ``analogue report work --quick`` that was 5.5 s of the 10 s of savefig.  The second layout
    starts from the first one's result and moves nothing the PNG shows (bench_figures compares
    the pixels), so the layout is computed once here and the figure is then saved with no
    engine: one draw."""
    engine = fig.get_layout_engine()
    if not isinstance(engine, ConstrainedLayoutEngine):
        return
    engine.execute(fig)
    # None, not "none": "none" leaves a placeholder engine, and savefig pre-draws for any engine
    with mpl.rc_context({"figure.autolayout": False, "figure.constrained_layout.use": False}):
        fig.set_layout_engine(None)


def save(fig: Figure, path: Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    freeze_layout(fig)
    fig.savefig(path, dpi=DPI)
    return path
