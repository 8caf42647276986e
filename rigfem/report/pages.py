"""HTML pages from the package's jinja2 templates (``rigfem/templates``), Markdown through mistune.

One home for the page machinery of the check report, the sweep pages and the explorer:
autoescaping is on, so every text from a user's file shows as text; only the HTML that
mistune made from the project's own Markdown, and the data URIs, are marked safe.
"""

from __future__ import annotations

import base64
import json
from functools import lru_cache
from pathlib import Path

import jinja2
import mistune
from markupsafe import Markup
from mistune.plugins.table import render_table_cell
from mistune.util import escape

from rigfem.report.figures import number

__all__ = ["render_page", "markdown_html", "png_uri", "json_script"]


@lru_cache(maxsize=1)
def _env() -> jinja2.Environment:
    env = jinja2.Environment(loader=jinja2.PackageLoader("rigfem", "templates"),
                             autoescape=True, undefined=jinja2.StrictUndefined,
                             trim_blocks=True, lstrip_blocks=True)
    env.filters["num"] = number
    from rigfem.report.scale import scale_json

    env.globals["utilisation_scale"] = json_script(scale_json())  # the pages' colours: rigfem.report.scale
    return env


def render_page(template: str, **context) -> str:
    """The page ``template`` (a file of rigfem/templates) filled with ``context``, escaped."""
    return _env().get_template(template).render(**context)


class _Escaped(mistune.HTMLRenderer):
    """Raw HTML in the Markdown shown as text (entities such as ``&lt;`` stay entities, which
    mistune's own ``escape=True`` would escape again); ``\\|`` in a table cell is a ``|`` (GFM)."""

    def inline_html(self, html: str) -> str:
        return escape(html)

    def block_html(self, html: str) -> str:
        return "<p>" + escape(html.strip()) + "</p>\n"

    def table_cell(self, text: str, align: str | None = None, head: bool = False) -> str:
        return render_table_cell(self, text.replace("\\|", "|"), align, head)


@lru_cache(maxsize=1)
def _markdown():
    return mistune.create_markdown(renderer=_Escaped(escape=False), plugins=["table"])


def markdown_html(text: str) -> Markup:
    """HTML of the project's Markdown (CommonMark with GFM tables); raw HTML in it is escaped, not passed."""
    return Markup(_markdown()(text))


def png_uri(path: Path) -> str | None:
    """A PNG file as a data URI (the page stays one file), or None if it is absent."""
    if not path.is_file():
        return None
    return "data:image/png;base64," + base64.b64encode(path.read_bytes()).decode("ascii")


def json_script(data) -> Markup:
    """``data`` as JSON safe inside a ``<script type="application/json">`` (no ``</`` can close it)."""
    text = json.dumps(data, separators=(",", ":"), allow_nan=False)
    return Markup(text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026"))
