"""Cells and tables of the HTML report (private helpers of :mod:`asbuilt.report.html`)."""

from __future__ import annotations

import html as _html
from collections.abc import Iterable

import numpy as np

from .figures import anchor

__all__ = ["_e", "_num", "_mm", "_table", "_td", "_link"]


def _e(value) -> str:
    """Escaped text; empty for None."""
    return "" if value is None else _html.escape(str(value), quote=True)


def _num(value, decimals: int = 3, scale: float = 1.0) -> str:
    if value is None:
        return ""
    number = float(value) * scale
    return f"{number:,.{decimals}f}" if np.isfinite(number) else ""


def _mm(value, decimals: int = 1) -> str:
    return _num(value, decimals, 1000.0)


def _table(headers: Iterable[tuple[str, bool]], rows: Iterable[str], cls: str = "") -> str:
    numeric = ' class="num"'
    head = "".join(f"<th{numeric if num else ''}>{_e(h)}</th>" for h, num in headers)
    body = "\n".join(rows)
    attr = f' class="{cls}"' if cls else ""
    return f"<table{attr}><thead><tr>{head}</tr></thead><tbody>\n{body}\n</tbody></table>"


def _td(value: str, num: bool = False) -> str:
    return f'<td class="num">{value}</td>' if num else f"<td>{value}</td>"


def _link(oid: str) -> str:
    return f'<a href="#{anchor(oid)}">{_e(oid)}</a>'
