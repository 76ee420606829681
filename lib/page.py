"""The HTML page shell shared by every report (continuum, compare, demo index)."""
from __future__ import annotations

import html

STYLE = """body{font-family:sans-serif;max-width:1150px;margin:2em auto;line-height:1.4}
img{max-width:100%;border:1px solid #ddd}table{border-collapse:collapse}
td,th{border:1px solid #ccc;padding:3px 8px;vertical-align:top}th{background:#f3f3f3;text-align:left}
td{font-variant-numeric:tabular-nums}.how{color:#444}"""


def page(title: str, body: str) -> str:
    """A complete HTML document around ``body`` (already HTML)."""
    return (f"<!doctype html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
            f"<style>{STYLE}</style></head><body>{body}</body></html>")
