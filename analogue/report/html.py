"""A self-contained HTML page (figures embedded as base64 PNG; no network, no scripts)."""
from __future__ import annotations

import base64
import html
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["Figure", "Table", "Section", "write_page"]


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
    title: str
    paragraphs: list = field(default_factory=list)
    figures: list = field(default_factory=list)
    tables: list = field(default_factory=list)
    anchor: str = ""


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
"""


def _fmt(x) -> str:
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
    return html.escape(str(x))


def _img(path: Path) -> str:
    data = base64.b64encode(Path(path).read_bytes()).decode("ascii")
    return f'<img alt="{html.escape(Path(path).name)}" src="data:image/png;base64,{data}">'


def write_page(path: Path, title: str, intro: list, sections: list) -> Path:
    """Write ``path`` (index.html) with every figure inlined."""
    out = ["<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
           f"<title>{html.escape(title)}</title><style>{_CSS}</style></head><body>",
           f"<h1>{html.escape(title)}</h1>"]
    out += [f"<p>{p}</p>" for p in intro]
    out.append("<nav><b>Contents</b><ol>")
    for i, s in enumerate(sections):
        s.anchor = s.anchor or f"s{i + 1}"
        out.append(f"<li><a href='#{s.anchor}'>{html.escape(s.title)}</a></li>")
    out.append("</ol></nav>")
    for s in sections:
        out.append(f"<h2 id='{s.anchor}'>{html.escape(s.title)}</h2>")
        out += [f"<p>{p}</p>" for p in s.paragraphs]
        for t in s.tables:
            if t.collapsed:
                out.append(f"<details><summary>{html.escape(t.caption)}</summary>")
            out.append(f"<table><caption>{html.escape(t.caption)}</caption><tr>")
            out += [f"<th>{html.escape(str(h))}</th>" for h in t.header]
            out.append("</tr>")
            for j, row in enumerate(t.rows):
                cls = f" class='{t.row_classes[j]}'" if t.row_classes else ""
                out.append(f"<tr{cls}>" + "".join(
                    f"<td class='text'>{_fmt(c)}</td>" if isinstance(c, str) else f"<td>{_fmt(c)}</td>"
                    for c in row) + "</tr>")
            out.append("</table>")
            if t.collapsed:
                out.append("</details>")
        for f in s.figures:
            out.append(f"<figure>{_img(f.path)}<figcaption>{f.caption}</figcaption></figure>")
    out.append("</body></html>")
    path = Path(path)
    tmp = path.with_suffix(".tmp")
    tmp.write_text("\n".join(out), encoding="utf-8")
    tmp.replace(path)
    return path
