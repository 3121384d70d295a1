"""``python -m asekit trajectory CASE PROFILE.csv [--json PATH] [--plot PATH]``: the flutter
and divergence margins, dynamic pressure and steady hinge moment of a case along a flight
trajectory, beside the NACA TN 4197 screening boundary (:mod:`asekit.case.trajectory`).

``CASE`` is a case file (TOML), a Nastran deck or a shipped case's name (as for ``analyse``);
``PROFILE.csv`` has the columns ``time_s``, ``mach``, ``altitude_m`` and optionally
``alpha_deg``, ``deflection_deg`` (``data/profiles/fin_boost.csv`` is shipped; a path that does
not exist may name a shipped profile, e.g. ``fin_boost``). The command prints one line per
point; ``--json`` writes ``{"trajectory": [{"time_s", "mach", "altitude_m",
"dynamic_pressure_Pa", "flutter_speed_ms", "flutter_margin_pct", "divergence_margin_pct",
"hinge_moment_Nm", "tn4197_flutter_speed_ms", "transonic_gap", "mach_extrapolated", "note"}],
"units", ...}`` and ``--plot`` a PNG of the margins against time with the transonic gap
shaded. The outputs, the case and the whole profile are checked before any computation; a bad
input is one line and exit status 2.
"""

from __future__ import annotations

import json
import logging
import sys
from pathlib import Path

from asekit.cli import outputs

_log = logging.getLogger(__name__)


def add_parser(sub) -> None:
    p = sub.add_parser("trajectory", help="flutter and divergence margins along a flight "
                                          "trajectory (CSV profile)",
                       description="Flutter and divergence margins, dynamic pressure and "
                                   "steady hinge moment of a case along a trajectory, beside "
                                   "the NACA TN 4197 fin-flutter boundary.")
    p.add_argument("case", metavar="CASE", help="a case file (TOML), a Nastran deck or a "
                                                "shipped case's name")
    p.add_argument("profile", metavar="PROFILE.csv",
                   help="columns time_s, mach, altitude_m [, alpha_deg, deflection_deg]")
    p.add_argument("--json", metavar="PATH", help="write the rows as JSON ('-': stdout)")
    p.add_argument("--plot", metavar="PATH", help="write the margins against time (PNG)")
    p.set_defaults(func=run)


def _error(msg: str) -> int:
    return outputs.print_error(f"error: {msg}", 2, _log)


def _profile_path(value: str) -> Path:
    """The profile's path; a name without a file may name a shipped profile."""
    path = Path(value)
    if path.exists():
        return path
    from asekit.util.paths import DATA_DIR
    shipped = DATA_DIR / "profiles" / (path.name if path.suffix else f"{path.name}.csv")
    return shipped if shipped.exists() and path.parent == Path(".") else path


def _inputs(args):
    """(case, points) or the error line."""
    from asekit.case import CaseError, load_case
    from asekit.case.trajectory import read_profile
    from asekit.cli.analyse import _named, _read_case
    name = Path(args.case).name
    try:
        case = _read_case(args, load_case)
    except FileNotFoundError:
        return f"case file {args.case} not found"
    except (CaseError, ValueError) as exc:
        return _named(name, exc)
    except OSError as exc:
        return f"{name}: cannot read the case file ({exc.strerror or exc})"
    try:
        points = read_profile(_profile_path(args.profile))
    except ValueError as exc:
        return str(exc)
    if case.flight is None or case.aero is None:
        return (f"{name}: a trajectory needs the case's [aero] and [flight] (its "
                "flight.velocities sweep)")
    return case, points


def run(args) -> int:
    for opt, dash in (("--json", True), ("--plot", False)):
        reason = outputs.check_file(opt, getattr(args, opt[2:]), dash=dash)
        if reason:
            return _error(reason)
    got = _inputs(args)
    if isinstance(got, str):
        return _error(got)
    case, points = got
    from asekit.case.schema import SolverError
    from asekit.case.trajectory import format_trajectory, trajectory, trajectory_json
    try:
        rows = trajectory(case, points, progress=not getattr(args, "quiet", False))
    except (ValueError, SolverError) as exc:
        return _error(f"{Path(args.case).name}: {exc}")
    to_stdout = args.json == "-"
    print(format_trajectory(case, rows), file=sys.stderr if to_stdout else sys.stdout)
    if args.json:
        text = json.dumps(trajectory_json(case, rows, args.profile), indent=2)
        if to_stdout:
            print(text)
        else:
            from asekit.case.report import write_text_atomic
            write_text_atomic(args.json, text + "\n")
    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from asekit.case.trajectory import plot_trajectory
        fig, _ = plot_trajectory(rows, f"{case.name}: margins along {Path(args.profile).name}")
        fig.tight_layout()
        fig.savefig(args.plot)
        plt.close(fig)
        print(f"plot: {args.plot}", file=sys.stderr)
    return 0
