"""Mutate a shipped case file one value at a time and count how the loader and the pipeline end
(issue 22's "pipeline errors escape as tracebacks after the case file passed validation").

Run on demand, against any asekit on the path (e.g. an older checkout for a before/after):

    PYTHONPATH=. python tests/benchmarks/fuzz_case.py [--case nalci2013_fin] [--mutations 200]
        [--seed 22] [--timeout 20]

Each mutation changes one leaf of the case's TOML table (scaled by 0, -1, 1e-6, 3, 10, 100, 1e6 or 1e30,
replaced by NaN, a string, a bool, an empty list or a non-integer, or deleted), then runs
``case_from_dict`` and the pipeline's modal model, boxes, GAF database and flutter (GAFs cached in
a temporary folder). Outcomes:

* ``ok``: the pipeline ran;
* ``refused``: a ``ValueError`` (CaseError, ...) or asekit's ``SolverError``, one line;
* ``unnamed``: any other exception (a traceback at the command line), or a multi-line message;
* ``timeout``: longer than ``--timeout`` s.

Mutations are derandomized (``--seed``): the same list for every checkout.
"""

from __future__ import annotations

import argparse
import copy
import math
import os
import random
import signal
import sys
import tempfile
import tomllib
import warnings
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
KINDS = ("ok", "refused", "unnamed", "timeout")


def leaves(d, path=()):
    """Every (path, value) of the nested dict/list ``d`` whose value is a scalar or a list of
    scalars."""
    if isinstance(d, dict):
        for k, v in d.items():
            yield from leaves(v, path + (k,))
    elif isinstance(d, list) and d and isinstance(d[0], (dict, list)):
        for i, v in enumerate(d):
            yield from leaves(v, path + (i,))
    else:
        yield path, d


def _scale(v, f):
    if isinstance(v, bool) or not isinstance(v, (int, float, list)):
        return None
    if isinstance(v, list):
        return [x * f if isinstance(x, (int, float)) and not isinstance(x, bool) else x for x in v]
    return v * f


MUTATIONS = {
    "zero": lambda v: _scale(v, 0),
    "negate": lambda v: _scale(v, -1),
    "tiny": lambda v: _scale(v, 1e-6),
    "x3": lambda v: _scale(v, 3),
    "x10": lambda v: _scale(v, 10),
    "x100": lambda v: _scale(v, 100),
    "huge": lambda v: _scale(v, 1e6),
    "1e30": lambda v: _scale(v, 1e30),
    "nan": lambda v: math.nan,
    "string": lambda v: "x",
    "bool": lambda v: True,
    "empty_list": lambda v: [],
    "half": lambda v: v + 0.5 if isinstance(v, int) and not isinstance(v, bool) else None,
    "delete": lambda v: KeyError,
}


def mutations(base: dict, n: int, seed: int):
    """``n`` (description, mutated dict) pairs."""
    rng = random.Random(seed)
    paths = list(leaves(base))
    out = []
    while len(out) < n:
        path, value = paths[rng.randrange(len(paths))]
        name = rng.choice(sorted(MUTATIONS))
        new = MUTATIONS[name](value)
        if new is None:
            continue
        d = copy.deepcopy(base)
        parent = d
        for p in path[:-1]:
            parent = parent[p]
        if new is KeyError:
            del parent[path[-1]]
        else:
            parent[path[-1]] = new
        out.append((f"{'.'.join(map(str, path))} {name}", d))
    return out


class _Timeout(BaseException):
    pass


def _alarm(signum, frame):
    raise _Timeout()


def run_one(raw: dict) -> tuple[str, str]:
    from asekit.case import pipeline
    from asekit.case.schema import case_from_dict
    try:
        case = case_from_dict(raw)
        pipeline.modal_model(case)
        pipeline.box_mesh(case)
        pipeline.flutter(case)
    except _Timeout:
        return "timeout", ""
    except Exception as exc:              # noqa: BLE001 -- classifying is the point
        msg = str(exc)
        named = isinstance(exc, ValueError) or type(exc).__name__ == "SolverError"
        if named and "\n" not in msg.strip():
            return "refused", f"{type(exc).__name__}: {msg[:100]}"
        return "unnamed", f"{type(exc).__name__}: {msg[:100]}"
    return "ok", ""


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default="nalci2013_fin")
    ap.add_argument("--mutations", type=int, default=200)
    ap.add_argument("--seed", type=int, default=22)
    ap.add_argument("--timeout", type=float, default=20.0)
    ap.add_argument("--show", type=int, default=12, help="unnamed outcomes printed")
    args = ap.parse_args(argv)
    os.environ["ASEKIT_CACHE_DIR"] = tempfile.mkdtemp(prefix="asekit-fuzz-case-")
    import asekit.case.pipeline  # noqa: F401  (imported before any alarm)
    base = tomllib.loads((ROOT / "data" / "cases" / f"{args.case}.toml").read_text())
    signal.signal(signal.SIGALRM, _alarm)
    warnings.simplefilter("ignore")
    seen: Counter = Counter()
    by_class: Counter = Counter()
    shown = []
    for what, raw in mutations(base, args.mutations, args.seed):
        signal.setitimer(signal.ITIMER_REAL, args.timeout)
        try:
            kind, detail = run_one(raw)
        except _Timeout:
            kind, detail = "timeout", ""
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
        seen[kind] += 1
        if kind == "unnamed":
            by_class[detail.split(":")[0]] += 1
            if len(shown) < args.show:
                shown.append(f"  {what}: {detail}")
    print(f"case {args.case}, {args.mutations} mutations, seed {args.seed}: "
          + ", ".join(f"{k} {seen.get(k, 0)}" for k in KINDS))
    if by_class:
        print("unnamed by class: " + ", ".join(f"{k} {v}" for k, v in by_class.most_common()))
    print("\n".join(shown))
    return 0


if __name__ == "__main__":
    sys.exit(main())
