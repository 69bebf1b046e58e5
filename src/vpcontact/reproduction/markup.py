"""The report's markup: its blocks (headings, paragraphs, bullet lists, tables, figures), their two
renderings, and how a number is written in its text.

A report is one list of blocks rendered twice: Markdown with the figures as relative links
(figures/figNN.png), and a self-contained HTML page with the PNGs inlined (base64) and links to the
PDFs. Inline text may use **bold**, `code` and [links](target); Markdown keeps the star of u_* from
being emphasis.
"""

from __future__ import annotations

import base64
import html
import re
from dataclasses import dataclass
from pathlib import Path


@dataclass
class Heading:
    level: int
    text: str


@dataclass
class Paragraph:
    text: str


@dataclass
class Bullets:
    items: list


@dataclass
class Table:
    header: list
    rows: list


@dataclass
class Picture:
    key: str
    """The figure id (fig02 …)."""
    caption: str


# --- rendering -----------------------------------------------------------------------------------
def _md(text) -> str:
    """Markdown-safe text: the star of u_* is not emphasis."""
    return str(text).replace("_*", "_\\*")


def to_markdown(blocks: list, figures: dict) -> str:
    """The blocks as Markdown; a picture is its PNG as a relative link, its caption and a link to its PDF
    (``figures``: the figure id → its title and the relative paths of its PNG and PDF)."""
    lines = []
    for block in blocks:
        if isinstance(block, Heading):
            lines += ["#" * block.level + " " + _md(block.text), ""]
        elif isinstance(block, Paragraph):
            lines += [_md(block.text), ""]
        elif isinstance(block, Bullets):
            lines += [f"- {_md(item)}" for item in block.items] + [""]
        elif isinstance(block, Table):
            cell = lambda v: _md(v).replace("|", "\\|").replace("\n", " ")  # noqa: E731
            lines.append("| " + " | ".join(cell(h) for h in block.header) + " |")
            lines.append("|" + "---|" * len(block.header))
            lines += ["| " + " | ".join(cell(v) for v in row) + " |" for row in block.rows]
            lines.append("")
        elif isinstance(block, Picture):
            figure = figures[block.key]
            title = _md(figure["title"])
            lines += [
                f"![{title}]({figure['png']})",
                "",
                f"**{title}.** {_md(block.caption)} ([PDF]({figure['pdf']}))",
                "",
            ]
    return "\n".join(lines)


def _inline(text: str) -> str:
    """Inline text as HTML: escaped, with its **bold**, `code` and [links](target)."""
    text = html.escape(str(text), quote=False)
    text = re.sub(r"\*\*(.+?)\*\*", r"<strong>\1</strong>", text)
    text = re.sub(r"`(.+?)`", r"<code>\1</code>", text)
    return re.sub(r"\[([^\]]+)\]\(([^)\s]+)\)", r'<a href="\2">\1</a>', text)


STYLE = """body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;max-width:1200px;margin:2em auto;
padding:0 1em;line-height:1.45;color:#222}table{border-collapse:collapse;margin:1em 0;font-size:0.9em}
th,td{border:1px solid #bbb;padding:4px 8px;text-align:left;vertical-align:top}th{background:#eee}
figure{margin:1.5em 0}img{max-width:100%;border:1px solid #ddd}figcaption{font-size:0.9em;color:#444}
code{background:#f3f3f3;padding:0 3px}"""


def to_html(blocks: list, figures: dict, folder: Path, title: str) -> str:
    """The blocks as one self-contained HTML page: each picture's PNG read from ``folder`` and inlined
    (base64), with a link to its PDF."""
    parts = [
        f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{html.escape(title)}</title>'
        f"<style>{STYLE}</style></head><body>"
    ]
    for block in blocks:
        if isinstance(block, Heading):
            parts.append(f"<h{block.level}>{_inline(block.text)}</h{block.level}>")
        elif isinstance(block, Paragraph):
            parts.append(f"<p>{_inline(block.text)}</p>")
        elif isinstance(block, Bullets):
            parts.append("<ul>" + "".join(f"<li>{_inline(item)}</li>" for item in block.items) + "</ul>")
        elif isinstance(block, Table):
            head = "".join(f"<th>{_inline(h)}</th>" for h in block.header)
            body = "".join("<tr>" + "".join(f"<td>{_inline(v)}</td>" for v in row) + "</tr>" for row in block.rows)
            parts.append(f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>")
        elif isinstance(block, Picture):
            figure = figures[block.key]
            encoded = base64.b64encode((folder / figure["png"]).read_bytes()).decode("ascii")
            parts.append(
                f'<figure id="{block.key}"><img alt="{html.escape(figure["title"])}" '
                f'src="data:image/png;base64,{encoded}"><figcaption><strong>{_inline(figure["title"])}.</strong> '
                f'{_inline(block.caption)} (<a href="{figure["pdf"]}">PDF</a>)</figcaption></figure>'
            )
    parts.append("</body></html>\n")
    return "\n".join(parts)


# --- numbers in the text ---------------------------------------------------------------------------
def significant(value, digits=4) -> str:
    """``value`` to ``digits`` significant digits; a dash for a value not measured (None)."""
    return "–" if value is None else f"{value:.{digits}g}"


def percent_change(value, reference) -> str:
    """The change from ``reference`` to ``value`` in per cent, signed, to 0.1 % ("0.0 %" below 0.05 %)."""
    change = 100.0 * (value - reference) / reference
    return "0.0 %" if abs(change) < 0.05 else f"{change:+.1f} %"
