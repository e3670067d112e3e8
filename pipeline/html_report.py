"""Pieces shared by the self-contained HTML reports (``rockmass run`` and ``rockmass study``).

A report is one HTML file with no script and no network: every image is embedded as a base64
``data:`` URI (PNG, or SVG), tables are plain HTML, and the style is a short CSS block that also reads
well when printed. This module holds the embedding (matplotlib figure or image file → data URI), the
figure and table markup and the number formatting; it imports nothing heavy (matplotlib is imported
by :func:`pyplot`, only when a plot is drawn).
"""

from __future__ import annotations

import base64
import html
import io
import json
import math
from pathlib import Path

__all__ = ["BASE_CSS", "PRINT_CSS", "figure", "file_data_uri", "fmt", "note", "png_base64",
           "pyplot", "table"]

#: Style of both reports (the study report adds its thumbnails grid).
BASE_CSS = """body { font-family: sans-serif; margin: 2em; max-width: 1200px; color: #222; }
table { border-collapse: collapse; font-size: 12px; margin: 1em 0; }
th, td { border: 1px solid #ccc; padding: 2px 6px; text-align: right; }
th { background: #f2f2f2; }
figure { margin: 1em 0; } img { max-width: 100%; }
figcaption { font-size: 13px; color: #555; }
"""

#: Printing: no page break inside a figure, a table row or right after a heading.
PRINT_CSS = """@media print {
  body { margin: 0; max-width: none; font-size: 11pt; }
  figure, tr { break-inside: avoid; } h2, h3 { break-after: avoid; }
  img { max-height: 22cm; } nav { display: none; }
}
"""

_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_PNG_END = b"IEND\xaeB`\x82"


def pyplot():
    """``matplotlib.pyplot`` on the Agg backend (imported on first use)."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt


def png_base64(fig, dpi: int = 110) -> str:
    """A matplotlib figure as base64 PNG text (tight bounding box)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
    return base64.b64encode(buf.getvalue()).decode("ascii")


def file_data_uri(path: str | Path) -> str:
    """A PNG or SVG file as a ``data:`` URI.

    Raises
    ------
    OSError
        The file cannot be read.
    ValueError
        It is not a complete PNG (signature and end chunk) or an SVG document.
    """
    data = Path(path).read_bytes()
    if data.startswith(_PNG_SIGNATURE):
        if not data.rstrip(b"\0").endswith(_PNG_END):
            raise ValueError("truncated PNG (no end chunk)")
        kind = "png"
    elif b"<svg" in data[:1024] and data.lstrip().startswith((b"<svg", b"<?xml")):
        kind = "svg+xml"
    else:
        raise ValueError("neither a PNG nor an SVG image")
    return f"data:image/{kind};base64," + base64.b64encode(data).decode("ascii")


def figure(caption: str, src: str, cls: str | None = None) -> str:
    """``<figure>`` with an embedded image; ``src`` is a ``data:`` URI or base64 PNG text."""
    if not src.startswith("data:"):
        src = "data:image/png;base64," + src
    attr = f' class="{cls}"' if cls else ""
    cap = html.escape(caption)
    return f'<figure{attr}><img alt="{cap}" src="{src}"><figcaption>{cap}</figcaption></figure>'


def table(header: list[str], rows: list[list[str]], table_id: str | None = None) -> str:
    """A plain HTML table of text cells (escaped)."""
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in r) + "</tr>" for r in rows)
    attr = f' id="{html.escape(table_id)}"' if table_id else ""
    return f"<table{attr}><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def fmt(v, digits: int = 4) -> str:
    """A cell's text: floats to ``digits`` significant digits, booleans yes/no, None empty."""
    if v is None:
        return ""
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return f"{v:.{digits}g}" if math.isfinite(v) else ""
    if isinstance(v, (list, dict)):
        return json.dumps(v)
    return str(v)


def note(text: str) -> str:
    """A short remark in place of missing or unreadable content."""
    return f'<p class="note">{html.escape(text)}</p>'
