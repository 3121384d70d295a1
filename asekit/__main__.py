"""Command line: ``python -m asekit reproduce [--json PATH] [--figures DIR] [--only CH ...]`` and
``python -m asekit analyse CASE.toml [--json PATH] [--report DIR]``."""

from __future__ import annotations

import argparse
import sys


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m asekit",
                                     description="asekit: aeroservoelastic workbench")
    sub = parser.add_subparsers(dest="command", required=True)
    rep = sub.add_parser("reproduce", help="run the thesis reproduction and print the "
                                           "thesis-vs-asekit table")
    rep.add_argument("--json", metavar="PATH", help="also write the table as JSON")
    rep.add_argument("--figures", metavar="DIR", help="write every chapter figure as PNG")
    rep.add_argument("--only", nargs="+", metavar="CHAPTER",
                     help="run only these chapters (servo, structure, aero, flutter, ase)")
    from .cli_analyse import add_parser as add_analyse
    add_analyse(sub)
    from .cli_sweep import add_parser as add_sweep
    add_sweep(sub)
    args = parser.parse_args(argv)
    if hasattr(args, "func"):
        try:
            return args.func(args)
        except KeyboardInterrupt:
            print("interrupted", file=sys.stderr)
            return 130
    if args.command == "reproduce":
        import matplotlib
        matplotlib.use("Agg")
        from .reproduce import reproduce
        try:
            reproduce(chapters=args.only, figures_dir=args.figures, json_path=args.json)
        except KeyboardInterrupt:
            print("interrupted", file=sys.stderr)
            return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
