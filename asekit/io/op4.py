"""A small reader for formatted (ASCII) Nastran OUTPUT4 (OP4) matrix files.

Format (MSC Nastran DMAP Programmer's Guide, module OUTPUT4, formatted non-sparse form):

* header record per matrix: ``NCOL NROW NFORM NTYPE NAME FORMAT`` in (4I8, 2A4 name, format
  string such as ``1P,5E16.9``). NTYPE 1/2 = real single/double, 3/4 = complex single/double.
* then, per stored column, a record ``ICOL IROW NW`` (3I8): column number (1-based), first
  row stored (1-based) and the number of *words* that follow (a complex value is two words),
  followed by the NW values in the stated Fortran E format (5 per line for ``5E16.9``).
* a terminating record with ``ICOL = NCOL + 1`` and one dummy word.

Columns not listed are zero. The sparse "BIGMAT" form (negative NW or row-index strings) is not
supported and raises a ValueError naming the matrix. Values are parsed by fixed field width
read from the format string, so adjacent negative numbers without spaces read correctly.

The fixed-width records are read strictly (issue 22): a data line must hold exactly its
fields (``min(per_line, remaining words) * width`` characters, trailing blanks allowed), every
field a number; a header or column record may hold nothing after its fields. A line one
character short, whose last field would otherwise still parse with one digit of its exponent
lost (``2.743123126E+01`` read as ``2.743123126E+0``, ten times too small), and a stray token
after a record are errors naming the file, the matrix and the 1-based line.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from asekit.util.paths import DATA_DIR
from asekit.util.validate import integer


@dataclass(frozen=True)
class Op4Matrix:
    """One matrix of an OP4 file: ``name``, ``form`` (Nastran form code: 1 square,
    2 rectangular, 6 symmetric, ...), ``ntype`` (1..4) and the dense ``data`` array
    (nrow x ncol, float or complex)."""

    name: str
    form: int
    ntype: int
    data: np.ndarray


_FMT = re.compile(r"(?:\d*P,)?(\d+)[EeDd](\d+)\.(\d+)")


def _field_width(fmt: str) -> tuple[int, int]:
    """(values per line, field width) from a Fortran format like ``1P,5E16.9``: the whole
    format field must be that one token (an optional scale factor ``kP,``, then ``nEw.d``)."""
    m = _FMT.fullmatch(fmt)
    if m is None:
        raise ValueError(f"unsupported OP4 number format {fmt!r} (expected one token like "
                         "'1P,5E16.9')")
    per_line, width, digits = int(m.group(1)), int(m.group(2)), int(m.group(3))
    if per_line < 1 or width < 2 or digits >= width:
        raise ValueError(f"OP4 number format {fmt!r} must have >= 1 value per line and a field "
                         "width larger than its digits (like '1P,5E16.9')")
    return per_line, width


#: Fortran E output drops the 'E' of three-digit exponents: 1.234567890+100
_NO_E = re.compile(r"^([+-]?[0-9.]+)([+-][0-9]{3})$")


def _to_float(field: str) -> float:
    f = field.replace("D", "E").replace("d", "e")
    m = _NO_E.match(f)
    if m:
        f = m.group(1) + "E" + m.group(2)
    try:
        return float(f)
    except ValueError:
        raise ValueError(f"value {field!r} is not a number") from None


def _parse_line(s: str, n_fields: int, width: int, lineno: int) -> list[float]:
    """The ``n_fields`` fixed-width fields of one data line, read strictly.

    A line must hold exactly ``n_fields * width`` characters (blanks after them are allowed,
    nothing else), and every field must be a number: a line one character short would
    otherwise shift its last field by a digit (``2.743123126E+01`` read as ``2.743123126E+0``,
    a value ten times too small) and still parse.
    """
    need = n_fields * width
    if len(s) < need:
        raise ValueError(f"line {lineno} holds {len(s)} characters; its {n_fields} value(s) "
                         f"of field width {width} need exactly {need} (a truncated line)")
    if s[need:].strip():
        raise ValueError(f"line {lineno} has unexpected text {s[need:].strip()!r} after its "
                         f"{n_fields} value(s) of field width {width}")
    vals = []
    for j in range(0, need, width):
        field = s[j:j + width]
        if not field.strip():
            raise ValueError(f"line {lineno}: field {j // width + 1} (columns {j + 1}-"
                             f"{j + width}) is blank")
        try:
            vals.append(_to_float(field.strip()))
        except ValueError as exc:
            raise ValueError(f"line {lineno}: {exc}") from None
    return vals


def _parse_values(lines: list[str], nwords: int, width: int, per_line: int,
                  first_lineno: int) -> np.ndarray:
    """The ``nwords`` values of one column record, ``per_line`` to a line (the last line holds
    the remainder); ``first_lineno`` is the 1-based line number of ``lines[0]``."""
    n_lines = -(-nwords // per_line)
    if len(lines) < n_lines:
        raise ValueError(f"the record needs {n_lines} data line(s) for its {nwords} words; the "
                         f"file ends after {len(lines)}")
    vals: list[float] = []
    for r, line in enumerate(lines[:n_lines]):
        n_fields = min(per_line, nwords - r * per_line)
        vals.extend(_parse_line(line, n_fields, width, first_lineno + r))
    return np.asarray(vals)


def _int_fields(line: str, n: int, what: str, lineno: int) -> tuple[int, ...]:
    """The first ``n`` integer fields (I8) of a header or column record."""
    try:
        return tuple(int(line[j:j + 8]) for j in range(0, 8 * n, 8))
    except ValueError:
        raise ValueError(f"line {lineno} is not an OP4 {what}: {line!r}") from None


def _read_header(line: str, lineno: int) -> tuple[int, int, int, int, str, int, int]:
    """``(ncol, nrow, form, ntype, name, per_line, width)`` of a matrix header record
    ``NCOL NROW NFORM NTYPE NAME FORMAT`` (4I8, the name in 8 columns, the format)."""
    ncol, nrow, form, ntype = _int_fields(line, 4, "header", lineno)
    rest = line[32:]
    name = rest[:8].strip()
    fmt = rest[8:].strip()
    if not name or " " in name:
        raise ValueError(f"line {lineno}: matrix name {rest[:8]!r} (columns 33-40) must be "
                         "1-8 characters without blanks")
    if ntype not in (1, 2, 3, 4):
        raise ValueError(f"matrix {name!r} has unsupported type {ntype} (1..4)")
    if ncol <= 0 or nrow <= 0:
        raise ValueError(f"matrix {name!r} has a sparse/BIGMAT header "
                         f"(ncol={ncol}, nrow={nrow}); not supported")
    try:
        per_line, width = _field_width(fmt)
    except ValueError as exc:
        raise ValueError(f"matrix {name!r}, header line {lineno}: {exc}") from None
    return ncol, nrow, form, ntype, name, per_line, width


def _read_column_record(line: str, lineno: int) -> tuple[int, int, int]:
    """``(icol, irow, nw)`` of a column record (3I8); any other text on the line is an error."""
    icol, irow, nw = _int_fields(line, 3, "column record (ICOL IROW NW, 3I8)", lineno)
    if line[24:].strip():
        raise ValueError(f"line {lineno}: unexpected text {line[24:].strip()!r} after the "
                         "column record ICOL IROW NW (3I8)")
    if nw < 0 or irow < 0:
        raise ValueError(f"line {lineno}: the sparse (BIGMAT) layout is not supported")
    return icol, irow, nw


def _read_matrix(lines: list[str], i: int) -> tuple[Op4Matrix, int]:
    """The matrix whose header is ``lines[i]``, and the index of the line after it."""
    ncol, nrow, form, ntype, name, per_line, width = _read_header(lines[i], i + 1)
    is_complex = ntype in (3, 4)
    data = np.zeros((nrow, ncol), dtype=complex if is_complex else float)
    i += 1
    while True:
        if i >= len(lines):
            raise ValueError(f"matrix {name!r} ends without its terminating record")
        try:
            icol, irow, nw = _read_column_record(lines[i], i + 1)
            nlines = -(-nw // per_line)
            vals = _parse_values(lines[i + 1:i + 1 + nlines], nw, width, per_line, i + 2)
        except ValueError as exc:
            raise ValueError(f"matrix {name!r}: {exc}") from None
        i += 1 + nlines
        if icol > ncol:
            break
        if icol < 1 or irow < 1:
            raise ValueError(f"matrix {name!r}, line {i - nlines}: column/row index < 1")
        if is_complex:
            if nw % 2:
                raise ValueError(f"complex matrix {name!r} has an odd word count at line "
                                 f"{i - nlines}")
            col = vals[0::2] + 1j * vals[1::2]
        else:
            col = vals
        if irow - 1 + len(col) > nrow:
            raise ValueError(f"matrix {name!r} column {icol} overruns {nrow} rows")
        data[irow - 1:irow - 1 + len(col), icol - 1] = col
    if not np.all(np.isfinite(data)):
        raise ValueError(f"matrix {name!r} holds non-finite values")
    return Op4Matrix(name=name, form=form, ntype=ntype, data=data), i


def read_op4(path: str | Path) -> dict[str, Op4Matrix]:
    """Read every matrix of a formatted OP4 file.

    Parameters
    ----------
    path : the ``.op4`` file (ASCII, written with OUTPUT4 ``form=formatted``).

    Returns
    -------
    dict name -> :class:`Op4Matrix`, in file order. Symmetric matrices (form 6) stored as one
    triangle are NOT symmetrised: the columns are returned exactly as stored.

    Raises
    ------
    ValueError
        Naming the file, the matrix and the 1-based line: on a malformed header or column
        record, unexpected text after a record's fields, a data line shorter than its fields
        (a truncated line) or with a blank or misaligned field, an unsupported (sparse/BIGMAT)
        layout, a matrix named twice, or a file holding no matrix.
    """
    lines = Path(path).read_text().splitlines()
    if not any(line.strip() for line in lines):
        raise ValueError(f"{path}: the OP4 file holds no matrix (it is empty)")
    out: dict[str, Op4Matrix] = {}
    i = 0
    while i < len(lines):
        if not lines[i].strip():
            i += 1
            continue
        try:
            mat, i_next = _read_matrix(lines, i)
        except ValueError as exc:
            raise ValueError(f"{path}: {exc}") from None
        if mat.name in out:
            raise ValueError(f"{path}: matrix {mat.name!r} at line {i + 1} is already in the "
                             "file (names must be unique)")
        out[mat.name] = mat
        i = i_next
    return out


def split_qhhl(qhhl: np.ndarray, n_k: int) -> np.ndarray:
    """Split Nastran's QHHL (n x n*n_k, blocks side by side per reduced frequency) into an
    array (n_k, n, n)."""
    n, ncol = qhhl.shape
    if ncol != n * n_k:
        raise ValueError(f"QHHL has {ncol} columns; expected n * n_k = {n} * {n_k}")
    return np.stack([qhhl[:, j * n:(j + 1) * n] for j in range(n_k)])


def write_op4(path: str | Path, matrices: dict[str, np.ndarray], digits: int = 9) -> Path:
    """Write dense matrices as a formatted OP4 file (``1P,5E{digits+7}.{digits}``); used to
    test :func:`read_op4` round trip and to export models to other codes.

    Values with a three-digit exponent are written the Fortran way, without the 'E'
    (``1.000000000+100``), so every field keeps its width. ``matrices``: name (1-8 characters,
    no spaces) -> finite 1-D or 2-D real or complex array; ``digits`` an integer in [1, 16].
    """
    digits = integer("digits", digits, low=1, high=16)
    if not isinstance(matrices, dict) or not matrices:
        raise ValueError("matrices must be a non-empty dict of name -> array")
    width = digits + 7
    fmt = f"1P,5E{width}.{digits}"
    lines = []

    def one(v: float) -> str:
        t = f"{v: .{digits}E}"
        if len(t) > width:                               # E+100 .. E+308: drop the 'E'
            t = t.replace("E", "")
        return t.rjust(width)

    def fmt_vals(vals):
        s = [one(float(v)) for v in vals]
        return ["".join(s[j:j + 5]) for j in range(0, len(s), 5)]

    for name, a in matrices.items():
        if not isinstance(name, str) or not 1 <= len(name) <= 8 or not name.isprintable() \
                or " " in name:
            raise ValueError(f"matrix names must be 1-8 printable characters without spaces, "
                             f"got {name!r}")
        a = np.asarray(a)
        if a.ndim > 2 or a.size == 0 or not (np.issubdtype(a.dtype, np.number)
                                            and not np.issubdtype(a.dtype, np.timedelta64)):
            raise ValueError(f"matrix {name!r} must be a non-empty 1-D or 2-D numeric array, "
                             f"got shape {a.shape}, dtype {a.dtype}")
        a = np.atleast_2d(a)
        if not np.all(np.isfinite(a)):
            raise ValueError(f"matrix {name!r} holds non-finite values")
        cplx = np.iscomplexobj(a)
        nrow, ncol = a.shape
        lines.append(f"{ncol:8d}{nrow:8d}{2:8d}{4 if cplx else 2:8d}{name:<8s}{fmt}")
        for j in range(ncol):
            col = a[:, j]
            nz = np.nonzero(col)[0]
            if nz.size == 0:
                continue
            r0, r1 = nz[0], nz[-1] + 1
            seg = col[r0:r1]
            words = np.column_stack([seg.real, seg.imag]).ravel() if cplx else seg
            lines.append(f"{j + 1:8d}{r0 + 1:8d}{len(words):8d}")
            lines.extend(fmt_vals(words))
        lines.append(f"{ncol + 1:8d}{1:8d}{1:8d}")
        lines.extend(fmt_vals([1.0]))
    Path(path).write_text("\n".join(lines) + "\n")
    return Path(path)


# --------------------------------------------------------------------------------------------
# MSC Nastran example HA145B (BAH wing), shipped in ../shared/benchmarks/bah_ha145b/
# --------------------------------------------------------------------------------------------
#: Facts of the HA145B deck (from the benchmark's README): Nastran k = omega (refc/2) / V.
HA145B_K = (0.000001, 0.001, 0.05, 0.10, 0.20, 0.50, 1.0)
HA145B_REFC = 131.232          # in
HA145B_RHO = 1.1468e-7         # lbf s^2 / in^4
HA145B_VELOCITIES = (4800.0, 25200.0)   # in/s, the p-k sweep range of the deck


@dataclass(frozen=True)
class NastranFlutterCase:
    """A modal flutter case read from Nastran output: M, K (n x n), Q (n_k, n, n) at
    reduced frequencies k, semi-chord b_ref, density rho (consistent units), label."""

    M: np.ndarray
    K: np.ndarray
    Q: np.ndarray
    k: np.ndarray
    b_ref: float
    rho: float
    label: str


def ha145b_path() -> Path:
    """Location of ``ha145b.op4``: the copy shipped in ``data/benchmarks/ha145b/`` (MSC
    Nastran's own output for its example HA145B, with its README)."""
    return DATA_DIR / "benchmarks" / "ha145b" / "ha145b.op4"


def load_ha145b(path: str | Path | None = None) -> NastranFlutterCase:
    """Read Nastran's HA145B matrices (KHH, MHH, QHHL) with :func:`read_op4`.

    Units inch, lbf, s. Raises FileNotFoundError if the benchmark file is absent.
    """
    path = ha145b_path() if path is None else Path(path)
    if not path.exists():
        raise FileNotFoundError(f"HA145B benchmark file not found: {path}")
    mats = read_op4(path)
    k = np.array(HA145B_K)
    return NastranFlutterCase(M=mats["MHH"].data, K=mats["KHH"].data,
                              Q=split_qhhl(mats["QHHL"].data, k.size), k=k,
                              b_ref=HA145B_REFC / 2, rho=HA145B_RHO,
                              label="MSC Nastran HA145B (BAH wing, Mach 0)")
