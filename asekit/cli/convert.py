"""``python -m asekit convert DECK.bdf CASE.toml [--units U] [--name NAME]``: a Nastran
stick-model deck (CBAR / CBEAM) written as a ``[[beam]]`` case file
(:func:`asekit.io.stick_case.write_stick_case`), which ``asekit analyse CASE.toml`` then runs
with asekit's own p-k.

What the case format cannot express is refused before anything is written, in one line naming
the card, its id and the field (exit 2, as every input error of the command line).
"""

from __future__ import annotations

import sys
from pathlib import Path

from asekit.cli import outputs


def add_parser(sub) -> None:
    p = sub.add_parser("convert", help="write a Nastran stick-model deck as a [[beam]] case file",
                       description="Write a CBAR / CBEAM stick-model deck (with CAERO1, SPLINE2, "
                                   "MKAERO1 and FLUTTER) as a [[beam]] case file "
                                   "(asekit.io.stick_case).")
    p.add_argument("deck", metavar="DECK.bdf", help="the Nastran deck (needs pyNastran)")
    p.add_argument("out", metavar="CASE.toml", help="the case file to write (overwritten)")
    p.add_argument("--units", default="SI", choices=("SI", "mm-t-s", "in-lbf-s"),
                   help="the deck's unit system (default SI); the case is SI")
    p.add_argument("--name", default=None, help="case.name (default: the deck's stem)")
    p.set_defaults(func=run)


def run(args) -> int:
    """Convert ``args.deck`` to ``args.out``; print the written path."""
    from asekit.io.stick_case import write_stick_case

    deck = Path(args.deck)
    if not deck.is_file():
        raise FileNotFoundError(f"deck not found: {deck}")
    reason = outputs.check_file("CASE.toml", args.out, dash=False)
    if reason:
        raise ValueError(reason)
    try:
        path = write_stick_case(deck, args.out, units=args.units, name=args.name)
    except ImportError as exc:          # no pyNastran: the user's to install (exit 2)
        raise ValueError(str(exc)) from None
    print(f"wrote {path}", file=sys.stdout)
    return 0
