"""``asekit cases [--copy NAME DIR]``: the case files shipped with asekit, one line each (name and
its ``case.reference``), and a copy of one to edit. A shipped case is run by name from any
directory: ``asekit analyse agard445_6`` (:func:`resolve_case`)."""

from __future__ import annotations

import shutil
import sys
import tomllib
from pathlib import Path

from asekit.util.paths import CASES_DIR, shipped_case, shipped_cases


def add_parser(sub) -> None:
    p = sub.add_parser("cases", help="list the shipped case files (or copy one to edit)",
                       description="List the case files shipped with asekit; `asekit analyse "
                                   "NAME` runs one by name from any directory.")
    p.add_argument("--copy", nargs=2, metavar=("NAME", "DIR"),
                   help="write the shipped case NAME to DIR/NAME.toml (DIR is created)")
    p.set_defaults(func=run)


def describe(path: Path) -> str:
    """One line for a shipped case: its ``case.reference`` (or ``case.name``)."""
    try:
        table = tomllib.loads(path.read_text(encoding="utf-8")).get("case", {})
    except (OSError, tomllib.TOMLDecodeError) as exc:     # a damaged install: say so, go on
        return f"(unreadable: {exc})"
    return str(table.get("reference") or table.get("name") or "")


def resolve_case(arg: str) -> Path:
    """The file a case argument names: an existing path as given, else a shipped case by name.

    Raises
    ------
    FileNotFoundError
        Neither: the message says where shipped cases live and how to list them.
    """
    path = Path(arg)
    if path.exists():
        return path
    shipped = shipped_case(arg)
    if shipped is not None:
        return shipped
    raise FileNotFoundError(f"{arg} not found, and no shipped case of that name (`asekit "
                            f"cases` lists them; they live in {CASES_DIR})")


def run(args) -> int:
    if args.copy:
        name, folder = args.copy
        src = shipped_case(name)
        if src is None:
            print(f"error: cases --copy: no shipped case {name!r}; choose from "
                  f"{', '.join(shipped_cases())}", file=sys.stderr)
            return 2
        dest_dir = Path(folder)
        if dest_dir.exists() and not dest_dir.is_dir():
            print(f"error: cases --copy: {dest_dir} exists and is not a folder", file=sys.stderr)
            return 2
        dest = dest_dir / src.name
        if dest.exists():
            print(f"error: cases --copy: {dest} exists; not overwritten", file=sys.stderr)
            return 2
        dest_dir.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(src, dest)
        print(dest)
        return 0
    cases = shipped_cases()
    width = max(len(n) for n in cases)
    for name, path in cases.items():
        print(f"{name:<{width}}  {describe(path)}")
    print(f"({len(cases)} cases in {CASES_DIR}; run one with `asekit analyse NAME`, copy one "
          f"to edit with `asekit cases --copy NAME DIR`)")
    return 0
