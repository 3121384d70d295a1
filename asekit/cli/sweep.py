"""``python -m asekit sweep SWEEP.toml --out results.csv [--executor serial|processes|dask]
[--scheduler tcp://HOST:8786] [--workers N]``: run a sweep file (:mod:`asekit.sweep`) and
write one row per sample. An existing partial output file of the same sweep is resumed. Bad
input (unknown key path, invalid distribution, unknown output, unreachable scheduler) gets one
line and exit status 2; samples that fail (their rows say why) give exit status 1 and one line
with their count, and the same command run again retries them."""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

from asekit.cli import outputs

_log = logging.getLogger(__name__)


def add_parser(sub) -> None:
    p = sub.add_parser("sweep", help="run a flight-envelope / uncertainty sweep of a case file")
    p.add_argument("sweep", metavar="SWEEP.toml", help="the sweep file (see data/sweeps/)")
    p.add_argument("--out", metavar="PATH", required=True,
                   help="the results table: .csv (resumed if it holds rows of this sweep) or "
                        ".parquet (needs pyarrow; journaled to PATH.partial.csv)")
    p.add_argument("--executor", choices=("serial", "processes", "dask"), default="serial")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="a running Dask scheduler (tcp://HOST:8786); default: a LocalCluster")
    p.add_argument("--workers", type=int, metavar="N",
                   help="local processes or LocalCluster workers (default 2)")
    p.add_argument("--samples", type=int, metavar="N",
                   help="override sweep.samples (the Monte Carlo sample count)")
    p.add_argument("--keep-failed", dest="retry_failed", action="store_false",
                   help="on resume, keep the failed rows of --out (default: run them again)")
    p.add_argument("--retry-failed", dest="retry_failed", action="store_true",
                   help=argparse.SUPPRESS)     # the default since issue 22; still accepted
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def _error(msg: str) -> int:
    return outputs.print_error(f"error: {msg}", 2, _log)


def _missing_extra(args) -> str | None:
    """The one-line reason (with its pip install) when an extra the run needs is missing."""
    from asekit.util.extras import MissingExtra, require
    try:
        require("pandas", "asekit sweep (the results table)")
        if args.executor == "dask":
            require("dask.distributed", "--executor dask")
    except MissingExtra as exc:
        return str(exc)
    return None


def _argument_error(args) -> str | None:
    """Why the executor options cannot run (or an extra is missing), else None."""
    if args.scheduler and args.executor != "dask":
        return "--scheduler needs --executor dask"
    if args.workers is not None and args.workers < 1:
        return f"--workers must be >= 1, got {args.workers}"
    return _missing_extra(args)


def run(args) -> int:
    import dataclasses
    if (why := _argument_error(args)) is not None:
        return _error(why)
    out = Path(args.out)
    if out.suffix.lower() not in (".csv", ".parquet"):
        return _error(f"--out {out}: give a .csv or .parquet path")
    parquet = out.suffix.lower() == ".parquet"
    if parquet:
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            return _error("--out *.parquet needs pyarrow (pip install pyarrow); or write .csv")
    reason = outputs.check_file("--out", args.out, dash=False)
    if reason:
        return _error(reason)
    from asekit import sweep as S
    from asekit.case.schema import SolverError
    try:
        sw = S.load_sweep(args.sweep)
        if args.samples is not None:
            if args.samples < 1:
                return _error(f"--samples must be >= 1, got {args.samples}")
            if not sw.random:
                return _error("--samples needs a parameter with a distribution")
            sw = dataclasses.replace(sw, samples=args.samples)
    except FileNotFoundError:
        return _error(f"sweep file {args.sweep} not found")
    except S.SweepError as exc:
        return _error(f"{Path(args.sweep).name}: {exc}")
    journal = out.with_name(out.name + ".partial.csv") if parquet else out
    try:
        df = S.run_sweep(sw, out=journal, executor=args.executor, workers=args.workers,
                         scheduler=args.scheduler, progress=not args.quiet,
                         retry_failed=args.retry_failed)
    except S.SweepError as exc:
        return _error(str(exc))
    except (ValueError, SolverError) as exc:   # a base case the pipeline refuses (e.g. its DLM)
        return _error(f"{Path(args.sweep).name}: {type(exc).__name__}: {exc}")
    return _summary(df, out, journal if parquet else None)


def _summary(df, out: Path, journal: Path | None) -> int:
    """Write the Parquet table (keeping its journal while rows failed, so that a rerun resumes
    from it) and print one line: exit 0 if every sample is ok, else 1 with the count, the
    first error and how to run the failed samples again."""
    failed = df[df["status"] != "ok"]
    if journal is not None:
        df.to_parquet(out, index=False)
        if failed.empty:
            journal.unlink()
    if failed.empty:
        print(f"{len(df)} samples (0 failed) -> {out}", file=sys.stderr)
        return 0
    first = failed.iloc[0]
    print(f"error: {len(failed)} of {len(df)} samples failed -> {out} (first, sample "
          f"{int(first['sample'])}: {first['error']}); run the same command again to retry "
          f"them (the finished rows are kept; --keep-failed keeps the failed ones)",
          file=sys.stderr)
    return 1
