"""Shared look of the theory figures: colours, figure creation without pyplot, saving."""
from __future__ import annotations

import threading
from collections import OrderedDict
from pathlib import Path

import matplotlib as mpl
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg, RendererAgg
from matplotlib.figure import Figure
from matplotlib.layout_engine import ConstrainedLayoutEngine
from matplotlib.mathtext import MathTextParser
from matplotlib.ticker import FixedLocator, Locator, NullLocator

from ..files import atomic_path

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
    _Canvas(fig)
    axes = fig.subplots(nrows, ncols, squeeze=squeeze)
    return fig, axes


# One mathtext parser (and so one parse cache) for every figure: each Agg renderer makes its
# own, so the log axes' "10^{-3}" labels and the like were parsed again in every figure
# (108 parses for the 21 figures of stick, slip and work, 55 distinct strings).
_MATHTEXT = MathTextParser("path")
_RENDERERS = threading.local()
# renderers kept per thread (most recently used sizes): a report's figures come in about six
# sizes (the budget figures' heights vary); a 1920x768 renderer holds 6 MB of pixels
_RENDERERS_KEPT = 6


class _Canvas(FigureCanvasAgg):
    """An Agg canvas whose renderer is shared by every figure of the same pixel size drawn in
    this thread (figures are drawn one after the other: the renderer is cleared before each
    draw).  matplotlib caches text extents per renderer, so a new renderer per figure measured
    every tick label and axis label again (732 measurements for the 21 figures)."""

    def get_renderer(self):
        w, h = self.get_width_height(physical=True)
        key = (w, h, self.figure.dpi)
        cache: OrderedDict = _RENDERERS.__dict__.setdefault("by_size", OrderedDict())
        renderer = cache.pop(key, None)
        if renderer is None:
            renderer = RendererAgg(w, h, self.figure.dpi)
            renderer.mathtext_parser = _MATHTEXT
        cache[key] = renderer
        while len(cache) > _RENDERERS_KEPT:
            cache.popitem(last=False)
        self.renderer = renderer
        return renderer


class _InView(Locator):
    """Another locator's ticks, less those outside the view: matplotlib makes a Tick (three
    lines, two texts) for every location a locator returns and draws only those in view; a
    log axis over 5 decades got 40-48 minor ticks, half of them outside."""

    def __init__(self, base: Locator):
        self.base = base

    def set_axis(self, axis):
        super().set_axis(axis)
        self.base.set_axis(axis)

    def __call__(self):
        locs = np.asarray(self.base(), dtype=float)
        if locs.size == 0 or self.axis is None:
            return locs
        tr = self.axis.get_transform()
        lo, hi = sorted(tr.transform(np.asarray(self.axis.get_view_interval(), dtype=float)))
        with np.errstate(invalid="ignore", divide="ignore"):
            t = tr.transform(locs)
        # wider than matplotlib's own test (1e-10 of the span): every tick it draws is kept
        slack = 1e-6 * (hi - lo)
        return locs[(t >= lo - slack) & (t <= hi + slack)]

    def tick_values(self, vmin, vmax):
        return self.base.tick_values(vmin, vmax)

    def nonsingular(self, v0, v1):
        return self.base.nonsingular(v0, v1)

    def view_limits(self, vmin, vmax):
        return self.base.view_limits(vmin, vmax)


def _ticks_in_view(fig: Figure) -> None:
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            for get, put in ((axis.get_major_locator, axis.set_major_locator),
                             (axis.get_minor_locator, axis.set_minor_locator)):
                loc = get()
                if not isinstance(loc, (FixedLocator, NullLocator, _InView)):
                    put(_InView(loc))


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
    _ticks_in_view(fig)
    engine.execute(fig)
    # None, not "none": "none" leaves a placeholder engine, and savefig pre-draws for any engine
    with mpl.rc_context({"figure.autolayout": False, "figure.constrained_layout.use": False}):
        fig.set_layout_engine(None)


def save(fig: Figure, path: Path) -> Path:
    """Write ``fig`` as a PNG at :data:`DPI`, its layout computed once (:func:`freeze_layout`);
    the last thing done with a figure (its layout is fixed afterwards)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    freeze_layout(fig)
    with atomic_path(path) as tmp:   # never a half-written PNG (a full disk names the file)
        fig.savefig(tmp, dpi=DPI, format="png")
    return path
