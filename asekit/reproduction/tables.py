"""Result tables for the notebooks: a header with units, numbers with set digits, no numpy reprs.

A :class:`Table` renders as an HTML table in JupyterLab (``_repr_html_``: the front-end sizes the
columns, so a wide table scrolls instead of wrapping a header mid-word) and as aligned plain
text everywhere else (``str``, ``print``, nbval's text output). Cells are formatted once, when
the table is built, by :func:`cell`: a float with its column's format, ``None`` as "-", a list
as "a, b, c", a numpy scalar as the Python number it holds (never ``np.float64(0.75)``).

Example
-------
>>> t = Table(["quantity", "thesis", "asekit"], [("root thickness", 4.0, 4.0)],
...           units=["", "mm", "mm"], formats=["", ".1f", ".2f"])
>>> print(t)
quantity        thesis (mm)  asekit (mm)
--------------  -----------  -----------
root thickness          4.0         4.00
"""

from __future__ import annotations

import html
import numbers
from dataclasses import dataclass

import numpy as np


def significant(value, digits: int = 4) -> str:
    """A number with ``digits`` significant digits and no exponent for large values: whole
    numbers of ``digits`` or more digits print as integers with thousands separators, small ones
    in ``g`` notation.

    >>> significant(157100.0), significant(0.719156), significant(2.958e-4), significant(-1.5e-7)
    ('157,100', '0.7192', '0.0002958', '-1.5e-07')
    """
    v = float(value)
    if np.isfinite(v) and abs(v) >= 10 ** (digits - 1):
        return f"{v:,.0f}"
    return f"{v:.{digits}g}"


def cell(value, fmt="") -> str:
    """One table cell as text.

    Parameters
    ----------
    value : a number (Python or numpy scalar), a string, ``None`` (shown as "-"), a bool
        ("yes"/"no") or a sequence of numbers (shown as "a, b, c", each with ``fmt``).
    fmt : a :func:`format` spec for numbers, e.g. ``".2f"``, ``".4g"``, ``"+.1%"`` (empty: ``"g"``
        for floats), or a function of the number returning its text (e.g. :func:`significant`).

    Returns
    -------
    str : the cell's text.

    Examples
    --------
    >>> cell(np.float64(0.7512), ".3f"), cell(None), cell([86.8891, 159.6022], ".1f")
    ('0.751', '-', '86.9, 159.6')
    >>> cell(np.int64(3)), cell(True), cell(float("inf"), ".1f")
    ('3', 'yes', 'inf')
    """
    if value is None:
        return "-"
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, str):
        return value
    if callable(fmt) and isinstance(value, numbers.Real):
        return fmt(value)
    if isinstance(value, numbers.Integral):
        return format(int(value), fmt) if fmt else str(int(value))
    if isinstance(value, numbers.Real):
        return format(float(value), fmt or "g")
    if isinstance(value, numbers.Complex):
        z = complex(value)
        spec = fmt if isinstance(fmt, str) and fmt else "g"
        return f"{format(z.real, spec)}{format(z.imag, '+' + spec.lstrip('+'))}j"
    if isinstance(value, (list, tuple, np.ndarray)):
        return ", ".join(cell(v, fmt) for v in np.asarray(value, dtype=object).ravel())
    return str(value)


@dataclass(frozen=True)
class Table:
    """A small result table (see the module docstring).

    Parameters
    ----------
    columns : column names.
    rows : rows of raw values (numbers, strings, None, sequences), one per row, ``len(columns)``
        each.
    units : per column, the unit shown in the header as "name (unit)"; "" or None for none.
    formats : per column, the :func:`format` spec of its numbers or a function (see
        :func:`cell`).
    title : an optional caption (HTML caption, or a first line of the text form).
    """

    columns: tuple
    rows: tuple
    units: tuple | None = None
    formats: tuple | None = None
    title: str = ""

    def __post_init__(self):
        n = len(self.columns)
        for name in ("units", "formats"):
            v = getattr(self, name)
            if v is not None and len(v) != n:
                raise ValueError(f"Table {name} must have one entry per column ({n}), got {len(v)}")
        for i, r in enumerate(self.rows):
            if len(r) != n:
                raise ValueError(f"Table row {i} has {len(r)} values, expected {n} (columns)")
        object.__setattr__(self, "columns", tuple(self.columns))
        object.__setattr__(self, "rows", tuple(tuple(r) for r in self.rows))

    @property
    def header(self) -> list[str]:
        """Column headers with their units, "name (unit)"."""
        units = self.units or ("",) * len(self.columns)
        return [f"{c} ({u})" if u else str(c) for c, u in zip(self.columns, units)]

    @property
    def cells(self) -> list[list[str]]:
        """Every row's cells as text (:func:`cell` with the column's format)."""
        fmts = self.formats or ("",) * len(self.columns)
        return [[cell(v, f if f else "") for v, f in zip(r, fmts)] for r in self.rows]

    def _numeric(self) -> list[bool]:
        """Per column: True if every value is a number or None and one at least is a number
        (right-aligned)."""
        def number(v):
            return isinstance(v, numbers.Number) and not isinstance(v, (bool, np.bool_))

        return [all(number(r[j]) or r[j] is None for r in self.rows)
                and any(number(r[j]) for r in self.rows) for j in range(len(self.columns))]

    def __str__(self) -> str:
        head, body, right = self.header, self.cells, self._numeric()
        widths = [max([len(h)] + [len(r[j]) for r in body]) for j, h in enumerate(head)]

        def line(items):
            return "  ".join(s.rjust(w) if rj else s.ljust(w)
                             for s, w, rj in zip(items, widths, right)).rstrip()

        out = [self.title] if self.title else []
        out += [line(head), "  ".join("-" * w for w in widths)]
        out += [line(r) for r in body]
        return "\n".join(out)

    def __repr__(self) -> str:
        return str(self)

    def _repr_html_(self) -> str:
        right = self._numeric()

        def td(tag, s, rj):
            style = ' style="text-align:right"' if rj else ' style="text-align:left"'
            return f"<{tag}{style}>{html.escape(s)}</{tag}>"

        cap = f"<caption>{html.escape(self.title)}</caption>" if self.title else ""
        head = "".join(td("th", h, rj) for h, rj in zip(self.header, right))
        body = "".join("<tr>" + "".join(td("td", s, rj) for s, rj in zip(r, right)) + "</tr>"
                       for r in self.cells)
        return f"<table>{cap}<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"
