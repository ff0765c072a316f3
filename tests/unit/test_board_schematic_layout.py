"""schematic.svg has no overlapping labels (issue 21, item 9): the board's drawing is rendered
on a matplotlib canvas, every text's box is measured by the renderer, and no two boxes may
overlap, nor may a box cross a wire or another element's body."""
import pytest

from analogue import Model
from analogue.board.design import design_board

pytest.importorskip("schemdraw")
matplotlib = pytest.importorskip("matplotlib")

DESIGN = design_board(Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0), v0=[2.0, -2.0])
PAD = 1.0   # display pixels (72 dpi): boxes closer than a point count as touching


def _seg_hits_box(p, q, box) -> bool:
    """Whether the segment p-q passes through the open box (x0, y0, x1, y1) (Liang-Barsky)."""
    x0, y0, x1, y1 = box
    t0, t1 = 0.0, 1.0
    dx, dy = q[0] - p[0], q[1] - p[1]
    for den, num in ((-dx, p[0] - x0), (dx, x1 - p[0]), (-dy, p[1] - y0), (dy, y1 - p[1])):
        if den == 0:
            if num <= 0:
                return False
            continue
        t = num / den
        if den < 0:
            t0 = max(t0, t)
        else:
            t1 = min(t1, t)
        if t0 >= t1:
            return False
    return True


def _overlap(a, b) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def layout(drawing):
    """(texts, bodies, wires) in display pixels: texts as (owner index, string, box) from the
    renderer; bodies as (owner index, class name, box) of each non-wire element's strokes;
    wires as (owner index, segment) of each line-like element."""
    import schemdraw.elements as elm
    from schemdraw.segments import Segment, SegmentText
    matplotlib.use("Agg")
    fig = drawing.draw(show=False, canvas="matplotlib")
    ax = fig.ax
    fig.getfig()          # sets the limits and the figure size (inches per drawing unit)
    fig.fig.canvas.draw()
    renderer = fig.fig.canvas.get_renderer()
    to_px = ax.transData.transform
    texts, bodies, wires = [], [], []
    artists = iter(ax.texts)
    for i, e in enumerate(drawing.elements):
        # the mpl backend makes one Text per SegmentText, in drawing order
        for seg in e.segments:
            if isinstance(seg, SegmentText):
                t = next(artists)
                assert t.get_text() == seg.text
                bb = t.get_window_extent(renderer)
                texts.append((i, seg.text, (bb.x0 + PAD, bb.y0 + PAD, bb.x1 - PAD, bb.y1 - PAD)))
        strokes = [s.xform(e.transform) for s in e.segments if isinstance(s, Segment)]
        if isinstance(e, (elm.Line, elm.Wire)):
            for s in strokes:
                pts = to_px(s.path)
                wires += [(i, (pts[k], pts[k + 1])) for k in range(len(pts) - 1)]
        elif strokes and not isinstance(e, (elm.Dot, elm.Label)):
            pts = to_px([p for s in strokes for p in s.path])
            bodies.append((i, type(e).__name__, (*pts.min(axis=0), *pts.max(axis=0))))
    assert next(artists, None) is None
    matplotlib.pyplot.close(fig.fig)
    return texts, bodies, wires


def collisions(drawing) -> list[str]:
    texts, bodies, wires = layout(drawing)
    bad = []
    for k, (i, s, a) in enumerate(texts):
        for _j, s2, b in texts[k + 1:]:
            if _overlap(a, b):
                bad.append(f"text {s!r} overlaps text {s2!r}")
        for j, name, b in bodies:
            if j != i and _overlap(a, b):
                bad.append(f"text {s!r} overlaps {name} #{j}")
        for j, (p, q) in wires:
            if j != i and _seg_hits_box(p, q, a):
                bad.append(f"text {s!r} crosses a wire (#{j})")
                break
    return bad


def test_the_geometry_helpers():
    box = (0.0, 0.0, 10.0, 5.0)
    assert _seg_hits_box((-5, 2), (15, 2), box)
    assert not _seg_hits_box((-5, 6), (15, 6), box)
    assert not _seg_hits_box((-5, 0), (15, 0), box)       # along an edge: touching only
    assert _seg_hits_box((5, -1), (5, 1), box)
    assert not _seg_hits_box((11, -1), (20, 9), box)
    assert _overlap((0, 0, 2, 2), (1, 1, 3, 3)) and not _overlap((0, 0, 2, 2), (2, 0, 3, 2))


def test_a_drawing_with_an_overlap_is_caught():
    import schemdraw
    import schemdraw.elements as elm
    d = schemdraw.Drawing(show=False)
    d.add(elm.Resistor().right().label("R1 a long label"))
    d.add(elm.Label().at((1.5, 0.45)).label("R2 right on top"))
    assert any("overlaps text" in c for c in collisions(d))


def test_board_schematic_has_no_overlapping_labels():
    from analogue.board.schematic import build_schematic
    bad = collisions(build_schematic(DESIGN))
    assert not bad, "\n".join(bad)
