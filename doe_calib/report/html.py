"""A tiny self-contained HTML document builder: no external resources, all text escaped.

Fragments built here are :class:`Html` (already safe); any plain ``str``
handed to the builder is escaped, so measured names or notes can never
inject markup.
"""
from __future__ import annotations

import base64
import html
import re
from pathlib import Path

CSS = """
body { font-family: sans-serif; max-width: 1100px; margin: 2em auto; color: #222; }
h1 { border-bottom: 2px solid #446; } h2 { margin-top: 1.6em; color: #334; }
table { border-collapse: collapse; margin: 0.8em 0; font-size: 0.9em; max-width: 100%; }
th, td { border: 1px solid #bbb; padding: 2px 8px; text-align: right; }
th { background: #e8e8f0; } td.text, th.text { text-align: left; }
figure { margin: 1em 0; } figcaption { font-size: 0.9em; color: #555; }
img { max-width: 100%; height: auto; }
pre { background: #f4f4f4; padding: 0.6em; overflow-x: auto; font-size: 0.85em; }
"""


class Html(str):
    """A fragment of markup that is already safe (built by this module)."""


def escape(text) -> Html:
    """``text`` as safe HTML: fragments pass through, anything else is escaped."""
    return text if isinstance(text, Html) else Html(html.escape(str(text)))


def paragraph(text) -> Html:
    """A ``<p>`` of escaped text."""
    return Html(f"<p>{escape(text)}</p>")


def preformatted(text) -> Html:
    """A ``<pre>`` block, e.g. a ``summary()``."""
    return Html(f"<pre>{escape(text)}</pre>")


def _cell(value, tag: str, digits: int) -> str:
    if isinstance(value, float):
        return f"<{tag}>{value:.{digits}g}</{tag}>"
    if isinstance(value, int) and not isinstance(value, bool):
        return f"<{tag}>{value}</{tag}>"
    return f'<{tag} class="text">{_breakable(value)}</{tag}>'


def _breakable(value) -> str:
    """Escaped text whose runs of 30 or more characters without a space may break after a
    comma or semicolon (a long effect string keeps its table inside the page)."""
    if isinstance(value, Html):
        return value
    runs = re.split(r"(\S{30,})", str(value))
    return "".join("<wbr>".join(escape(p) for p in re.split(r"(?<=[,;])", run)) if k % 2
                   else escape(run) for k, run in enumerate(runs))


def table(header, rows, digits: int = 6) -> Html:
    """A table of ``rows`` under ``header``: numbers right-aligned (floats to ``digits``
    significant digits), text left-aligned.

    Examples
    --------
    >>> str(table(["a", "b"], [["x<y", 1.5]]))[:40]
    '<table><tr><th class="text">a</th><th cl'
    """
    head = "".join(_cell(str(h), "th", digits) for h in header)
    body = "".join("<tr>" + "".join(_cell(v, "td", digits) for v in r) + "</tr>" for r in rows)
    return Html(f"<table><tr>{head}</tr>{body}</table>")


def figure(png: bytes, alt: str, caption: str = "") -> Html:
    """A figure embedding ``png`` (bytes) as a base64 data URI, with alt text and a caption."""
    data = base64.b64encode(png).decode("ascii")
    cap = f"<figcaption>{escape(caption)}</figcaption>" if caption else ""
    return Html(f'<figure><img src="data:image/png;base64,{data}" '
                f'alt="{html.escape(alt, quote=True)}">{cap}</figure>')


def collapsible(summary, *blocks) -> Html:
    """Blocks folded under a one-line ``summary`` the reader can open (``<details>``)."""
    body = "\n".join(b if isinstance(b, Html) else paragraph(b) for b in blocks)
    return Html(f"<details><summary>{escape(summary)}</summary>\n{body}\n</details>")


def section(heading, *blocks) -> Html:
    """A ``<section>`` with an ``<h2>`` and blocks (fragments, or text made paragraphs)."""
    body = "\n".join(b if isinstance(b, Html) else paragraph(b) for b in blocks)
    return Html(f"<section><h2>{escape(heading)}</h2>\n{body}\n</section>")


def document(title, sections) -> Html:
    """A complete HTML document: the title, the CSS, then the ``sections``, each an
    :class:`Html` fragment or a pair ``(heading, blocks)`` of fragments or text."""
    parts = [s if isinstance(s, Html) else section(s[0], *s[1]) for s in sections]
    return Html("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
                f"<title>{escape(title)}</title><style>{CSS}</style></head>\n"
                f"<body><h1>{escape(title)}</h1>\n" + "\n".join(parts) + "\n</body></html>\n")


def write_report(path, title, sections) -> Path:
    """Write the :func:`document` of ``title`` and ``sections`` to ``path`` (UTF-8); return it.

    Examples
    --------
    >>> import tempfile, os
    >>> p = write_report(os.path.join(tempfile.mkdtemp(), "r.html"), "T",
    ...                  [("Notes", ["a & b"])])
    >>> "a &amp; b" in p.read_text()
    True
    """
    path = Path(path)
    path.write_text(document(title, sections), encoding="utf-8")
    return path
