"""Count the outcomes of the property targets (tests/property_targets.py) over many examples:
crashes, silent NaNs, implausible results, unnamed errors, timeouts (issue 11's fuzz counts).

Run on demand, against any asekit on the path (e.g. an older checkout for a before/after):

    PYTHONPATH=. python tests/benchmarks/fuzz_count.py [--examples 200] [--timeout 5]

Examples are derandomized (the same for every checkout); each call gets ``--timeout`` seconds
(SIGALRM) and counts as ``timeout`` past it. Prints one row per target and the totals.
"""

from __future__ import annotations

import argparse
import signal
import sys
import warnings
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from hypothesis import HealthCheck, given, settings  # noqa: E402

from property_targets import ALL_TARGETS, Outcome, classify  # noqa: E402

KINDS = ("ok", "refused", "unnamed", "nan", "implausible", "crash", "timeout")


class _Timeout(BaseException):     # not caught by classify's "except Exception"
    pass


_ACTIVE = {"on": False}


def _alarm(signum, frame):
    if _ACTIVE["on"]:                # only while a target call runs (not while handling one)
        raise _Timeout()


def count(target, examples: int, timeout: float, show: int = 3):
    seen: Counter = Counter()
    samples: dict[str, list] = {}

    @settings(max_examples=examples, deadline=None, database=None, derandomize=True,
              suppress_health_check=list(HealthCheck))
    @given(target.strategy)
    def run(kwargs):
        _ACTIVE["on"] = True
        signal.setitimer(signal.ITIMER_REAL, timeout, timeout)   # re-fires if swallowed
        try:
            out = classify(target, kwargs)
        except _Timeout:
            _ACTIVE["on"] = False
            out = Outcome("timeout", f"> {timeout} s")
        finally:
            _ACTIVE["on"] = False
            signal.setitimer(signal.ITIMER_REAL, 0)
        seen[out.kind] += 1
        if out.kind not in ("ok", "refused") and len(samples.setdefault(out.kind, [])) < show:
            samples[out.kind].append((kwargs, out.detail))

    run()
    return seen, samples


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--examples", type=int, default=200)
    ap.add_argument("--timeout", type=float, default=5.0)
    ap.add_argument("--only", nargs="*", default=None)
    ap.add_argument("--show", type=int, default=2, help="sample failures printed per kind")
    args = ap.parse_args(argv)
    # import everything first: an alarm inside a first import leaves a half-initialised module
    import asekit.aero.dlm, asekit.aero.vlm, asekit.atmosphere, asekit.aeroelastic.flutter  # noqa: E401,F401
    import asekit.io.op4, asekit.rfa, asekit.servo.actuator, asekit.servo.simulate  # noqa: E401,F401
    signal.signal(signal.SIGALRM, _alarm)
    warnings.simplefilter("ignore")
    total: Counter = Counter()
    print(f"{'target':14s}" + "".join(f"{k:>12s}" for k in KINDS))
    details = []
    for t in ALL_TARGETS:
        if args.only and t.name not in args.only:
            continue
        seen, samples = count(t, args.examples, args.timeout, args.show)
        total.update(seen)
        print(f"{t.name:14s}" + "".join(f"{seen.get(k, 0):12d}" for k in KINDS), flush=True)
        for kind, items in samples.items():
            for kw, detail in items:
                details.append(f"  {t.name} [{kind}] {detail}\n      {kw}")
    print(f"{'total':14s}" + "".join(f"{total.get(k, 0):12d}" for k in KINDS))
    bad = sum(total.get(k, 0) for k in ("unnamed", "nan", "implausible", "crash", "timeout"))
    print(f"calls {sum(total.values())}; crashes {total.get('crash', 0)}, silent NaN "
          f"{total.get('nan', 0)}, implausible {total.get('implausible', 0)}, timeouts "
          f"{total.get('timeout', 0)}, unnamed errors {total.get('unnamed', 0)}; not ok {bad}")
    if details:
        print("samples:")
        print("\n".join(details))
    return 0


if __name__ == "__main__":
    sys.exit(main())
