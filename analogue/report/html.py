"""A self-contained HTML page (figures embedded as base64 PNG; no network, no scripts).

Rendered by jinja2 with autoescape on: every text (titles, paragraphs, captions, table cells;
experiment names and descriptions come from the user's files) is escaped.  Markup is only
ever what the template writes, or text explicitly wrapped in :class:`markupsafe.Markup` by the
code that builds the page.
"""
from __future__ import annotations

import base64
from dataclasses import dataclass, field
from pathlib import Path

import jinja2
from ..files import write_text

__all__ = ["Figure", "Table", "Section", "write_page", "render_page"]


@dataclass
class Figure:
    path: Path
    caption: str


@dataclass
class Table:
    caption: str
    header: list
    rows: list
    row_classes: list | None = None
    collapsed: bool = False


@dataclass
class Section:
    """One section of the page; ``error`` (text) marks a section whose work failed: it is
    written with its error instead of its content, and the rest of the page is kept."""

    title: str
    paragraphs: list = field(default_factory=list)
    figures: list = field(default_factory=list)
    tables: list = field(default_factory=list)
    anchor: str = ""
    error: str | None = None


_CSS = """
body{font-family:Georgia,'DejaVu Serif',serif;max-width:1100px;margin:2em auto;padding:0 1em;
color:#222;line-height:1.45}
h1{font-size:1.7em;border-bottom:2px solid #446;padding-bottom:.2em}
h2{font-size:1.3em;margin-top:2em;border-bottom:1px solid #ccd}
figure{margin:1.2em 0;text-align:center}
figure img{max-width:100%;border:1px solid #ddd}
figcaption{font-size:.92em;color:#444;text-align:left;margin-top:.3em}
table{border-collapse:collapse;margin:1em 0;font-size:.88em;font-family:'DejaVu Sans',sans-serif}
th,td{border:1px solid #ccc;padding:.25em .5em;text-align:right}
th{background:#eef}
td:first-child,th:first-child,td.text{text-align:left}
tr.fail td{background:#fde8e8} tr.ok td{background:#f3fbf3}
caption{caption-side:top;text-align:left;font-style:italic;margin-bottom:.3em}
nav{background:#f6f6fb;padding:.6em 1em;border:1px solid #dde}
code{background:#f4f4f4;padding:0 .2em}
summary{cursor:pointer;margin:.6em 0;font-style:italic}
.failed{background:#fde8e8;border:1px solid #d99;padding:.6em 1em}
.failed pre{white-space:pre-wrap;margin:.3em 0 0 0}
"""

_TEMPLATE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<title>{{ title }}</title><style>{{ css | safe }}</style></head><body>
<h1>{{ title }}</h1>
{% for p in intro %}<p>{{ p }}</p>
{% endfor %}<nav><b>Contents</b><ol>
{% for s in sections %}<li><a href="#{{ s.anchor }}">{{ s.title }}</a>{% if s.error is not none %} (failed){% endif %}</li>
{% endfor %}</ol></nav>
{% for s in sections %}
<h2 id="{{ s.anchor }}">{{ s.title }}</h2>
{% if s.error is not none %}<div class="failed"><b>This section failed</b>; the rest of the report is complete.<pre>{{ s.error }}</pre></div>
{% endif %}{% for p in s.paragraphs %}<p>{{ p }}</p>
{% endfor %}{% for t in s.tables %}{% if t.collapsed %}<details><summary>{{ t.caption }}</summary>{% endif %}
<table><caption>{{ t.caption }}</caption>
<tr>{% for h in t.header %}<th>{{ h }}</th>{% endfor %}</tr>
{% for row in t.rows %}<tr{% if t.row_classes %} class="{{ t.row_classes[loop.index0] }}"{% endif %}>{% for c in row %}<td{% if c is string %} class="text"{% endif %}>{{ c | cell }}</td>{% endfor %}</tr>
{% endfor %}</table>
{% if t.collapsed %}</details>{% endif %}
{% endfor %}{% for f in s.figures %}<figure><img alt="{{ f.alt }}" src="data:image/png;base64,{{ f.data }}"><figcaption>{{ f.caption }}</figcaption></figure>
{% endfor %}{% endfor %}
</body></html>
"""


def _fmt(x) -> str:
    """Table cells: numbers formatted, everything else as text (escaped by the template)."""
    if isinstance(x, bool):
        return "yes" if x else "NO"
    if isinstance(x, float):
        if x != x:
            return "–"
        if x == 0:
            return "0"
        if abs(x) >= 1e4 or abs(x) < 1e-3:
            return f"{x:.3e}"
        return f"{x:.4g}"
    return str(x)


_ENV = jinja2.Environment(autoescape=True, undefined=jinja2.StrictUndefined,
                          keep_trailing_newline=True)
_ENV.filters["cell"] = _fmt
_PAGE = _ENV.from_string(_TEMPLATE)


def render_page(title: str, intro: list, sections: list) -> str:
    """The page as text (every figure inlined)."""
    for i, s in enumerate(sections):
        s.anchor = s.anchor or f"s{i + 1}"
    views = []
    for s in sections:
        figs = [{"alt": Path(f.path).name, "caption": f.caption,
                 "data": base64.b64encode(Path(f.path).read_bytes()).decode("ascii")}
                for f in s.figures]
        views.append({"title": s.title, "anchor": s.anchor, "error": s.error,
                      "paragraphs": s.paragraphs, "tables": s.tables, "figures": figs})
    return _PAGE.render(title=title, css=_CSS, intro=intro, sections=views)


def write_page(path: Path, title: str, intro: list, sections: list) -> Path:
    """Write ``path`` (index.html) with every figure inlined (atomically: a reader never sees
    half a page)."""
    # UTF-8 whatever the locale, the path named as it is on disk; a full disk names the page
    return write_text(Path(path), render_page(title, intro, sections))
