"""report.md and report.html of a comparison: one list of blocks, written twice.

The HTML is self-contained (PNGs embedded as base64), so it can be mailed or
archived alone; the Markdown links the PNGs relatively.
"""

from __future__ import annotations

import base64
import html
import math
from pathlib import Path


# -- blocks ----------------------------------------------------------------

def heading(text, level=2):
    return ("h", level, text)


def para(text):
    return ("p", text)


def table(header, rows):
    return ("table", list(header), [list(r) for r in rows])


def image(relpath, caption):
    return ("img", str(relpath), caption)


def code(text):
    return ("code", text)


def verdict_block(passed, text):
    return ("verdict", bool(passed), text)


def fmt(value, digits=3) -> str:
    """A number for a table: NaN as '—', booleans as yes/no."""
    if isinstance(value, bool):
        return "yes" if value else "no"
    if value is None:
        return "—"
    if isinstance(value, float):
        if math.isnan(value):
            return "—"
        if math.isinf(value):
            return "∞"
        return f"{value:.{digits}g}"
    return str(value)


# -- writers ---------------------------------------------------------------

def _md_cell(value) -> str:
    """A Markdown table cell: a literal '|' would end the cell."""
    return str(value).replace("|", "\\|")


def to_markdown(blocks) -> str:
    out = []
    for b in blocks:
        kind = b[0]
        if kind == "h":
            out.append("#" * b[1] + " " + b[2])
        elif kind == "p":
            out.append(b[1])
        elif kind == "table":
            header, rows = b[1], b[2]
            cell = _md_cell
            out.append("| " + " | ".join(cell(h) for h in header) + " |")
            out.append("|" + "---|" * len(header))
            out.extend("| " + " | ".join(cell(c) for c in row) + " |" for row in rows)
        elif kind == "img":
            out.append(f"![{b[2]}]({b[1]})\n\n*{b[2]}*")
        elif kind == "code":
            out.append("```\n" + b[1].rstrip("\n") + "\n```")
        elif kind == "verdict":
            out.append(f"**{'PASS' if b[1] else 'FAIL'}** — {b[2]}")
        out.append("")
    return "\n".join(out)


_CSS = """
body { font-family: sans-serif; max-width: 1100px; margin: 2em auto; color: #222; }
table { border-collapse: collapse; font-size: 0.85em; margin: 0.5em 0 1em; }
th, td { border: 1px solid #bbb; padding: 2px 6px; text-align: right; }
th { background: #eee; }
td:first-child, th:first-child { text-align: left; }
img { max-width: 100%; border: 1px solid #ddd; }
figure { margin: 1em 0; }
figcaption { font-size: 0.85em; color: #555; }
pre { background: #f6f6f6; padding: 0.6em; overflow-x: auto; font-size: 0.8em; }
.pass { background: #dfd; border: 2px solid #3a3; padding: 0.6em; font-size: 1.1em; }
.fail { background: #fdd; border: 2px solid #c33; padding: 0.6em; font-size: 1.1em; }
"""


def to_html(blocks, base: Path, title: str) -> str:
    """HTML with every image embedded (read from ``base / relpath``)."""
    esc = html.escape
    out = ["<!DOCTYPE html>", "<html><head><meta charset='utf-8'>",
           f"<title>{esc(title)}</title><style>{_CSS}</style></head><body>"]
    for b in blocks:
        kind = b[0]
        if kind == "h":
            out.append(f"<h{b[1]}>{esc(b[2])}</h{b[1]}>")
        elif kind == "p":
            out.append(f"<p>{esc(b[1])}</p>")
        elif kind == "table":
            out.append("<table><tr>" + "".join(f"<th>{esc(h)}</th>" for h in b[1]) + "</tr>")
            for row in b[2]:
                out.append("<tr>" + "".join(f"<td>{esc(str(c))}</td>" for c in row) + "</tr>")
            out.append("</table>")
        elif kind == "img":
            path = Path(base) / b[1]
            if path.is_file():
                data = base64.b64encode(path.read_bytes()).decode("ascii")
                src = f"data:image/png;base64,{data}"
            else:
                src = esc(b[1])
            out.append(f"<figure><img src='{src}' alt='{esc(b[2])}'>"
                       f"<figcaption>{esc(b[2])}</figcaption></figure>")
        elif kind == "code":
            out.append(f"<pre>{esc(b[1])}</pre>")
        elif kind == "verdict":
            cls = "pass" if b[1] else "fail"
            out.append(f"<div class='{cls}'><b>{'PASS' if b[1] else 'FAIL'}</b> — "
                       f"{esc(b[2])}</div>")
    out.append("</body></html>")
    return "\n".join(out) + "\n"


def write(directory: Path, blocks, title: str) -> tuple[Path, Path]:
    """Write report.md and report.html into ``directory``."""
    directory = Path(directory)
    md = directory / "report.md"
    md.write_text(f"# {title}\n\n" + to_markdown(blocks), encoding="utf-8")
    page = directory / "report.html"
    page.write_text(to_html([heading(title, 1)] + list(blocks), directory, title),
                    encoding="utf-8")
    return md, page
