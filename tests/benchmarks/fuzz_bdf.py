"""Mutation fuzzer of the BDF import (issue 22): random field mutations, deletions and
duplications of the cards of a shipped deck (HA145E, its structure include inlined), each
mutated deck read with ``asekit.io.bdf.read_bdf`` and, if it reads, its modes computed
(``pipeline.modal_model``); the outcomes are counted by class.

Run on demand, against any asekit on the path (e.g. an older checkout for a before/after):

    PYTHONPATH=. /work/venv-nastran/bin/python tests/benchmarks/fuzz_bdf.py [--decks 400]

The mutations are derandomised (``--seed``, the same decks for every checkout). Outcome
classes: ``ok`` (read and modes computed, no warning), ``ok+warning`` (the same with an
asekit warning other than UnsupportedCardWarning), ``BdfError`` (refused with asekit's error),
``timeout`` and the class name of any other exception (pyNastran's, numpy's, ...). Prints the
counts and a few samples of each class that is not ``ok`` / ``BdfError``.
"""

from __future__ import annotations

import argparse
import random
import re
import signal
import sys
import tempfile
import warnings
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DECK = ROOT / "data" / "benchmarks" / "ha145e" / "ha145e.bdf"

#: Replacement values a field mutation draws from (plus the field scaled, negated or moved).
VALUES = ("", "0", "0.0", "-1", "-1.0", "1", "2", "1.+30", "-1.+30", "1.-30", "abc", "99999",
          "1.5", ".5", "7", "THRU", "+", "1e", "3.0", "123456789")


class _Timeout(BaseException):
    pass


def _alarm(signum, frame):
    raise _Timeout()


def inlined_deck(path: Path = DECK) -> list[str]:
    """The deck's lines with its INCLUDE files inlined."""
    out = []
    for line in path.read_text().splitlines():
        m = re.match(r"\s*INCLUDE\s+'([^']+)'", line, re.I)
        if m:
            out += inlined_deck(path.parent / m.group(1))
        else:
            out.append(line)
    return out


def split_cards(lines: list[str]) -> tuple[list[str], list[list[str]], list[str]]:
    """(head up to BEGIN BULK, bulk cards as lists of lines, tail from ENDDATA)."""
    upper = [ln.upper() for ln in lines]
    i0 = next((i for i, ln in enumerate(upper) if ln.startswith("BEGIN BULK")), -1) + 1
    i1 = next(i for i, ln in enumerate(upper) if ln.startswith("ENDDATA"))
    cards: list[list[str]] = []
    for ln in lines[i0:i1]:
        if not ln.strip() or ln.lstrip().startswith("$"):
            continue
        if ln[0] in " +*" and cards:
            cards[-1].append(ln)
        else:
            cards.append([ln])
    return lines[:i0], cards, lines[i1:]


def _fields(line: str) -> list[str]:
    line = line.ljust(72)[:72]
    return [line[i:i + 8] for i in range(0, 72, 8)]


def _mutate_field(rng: random.Random, card: list[str]) -> list[str]:
    card = list(card)
    j = rng.randrange(len(card))
    f = _fields(card[j])
    k = rng.randrange(1, 9)
    old = f[k].strip()
    choice = rng.random()
    if choice < 0.25 and old:
        try:
            v = float(old.replace("+", "e+").replace("-", "e-").lstrip("e")
                      if re.search(r"\d[+-]\d", old) else old)
            new = repr(v * rng.choice([-1.0, 10.0, 0.1, 1e6, 0.0]))[:8]
        except ValueError:
            new = rng.choice(VALUES)
    elif choice < 0.35:
        new = f[rng.randrange(1, 9)].strip()
    else:
        new = rng.choice(VALUES)
    f[k] = new[:8].ljust(8)
    card[j] = "".join(f).rstrip()
    return card


def mutate(rng: random.Random, cards: list[list[str]]) -> tuple[list[list[str]], str]:
    """One mutation of the card list: a field changed, a card or a continuation line deleted,
    a card duplicated (as it is, or with a field changed: the same id twice)."""
    cards = [list(c) for c in cards]
    i = rng.randrange(len(cards))
    name = cards[i][0][:8].strip()
    kind = rng.choices(["field", "delete", "duplicate", "duplicate+field", "drop-line"],
                       weights=[6, 1.5, 1, 1.5, 0.5])[0]
    if kind == "field":
        cards[i] = _mutate_field(rng, cards[i])
    elif kind == "delete":
        del cards[i]
    elif kind == "duplicate":
        cards.insert(i + 1, list(cards[i]))
    elif kind == "duplicate+field":
        cards.insert(i + 1, _mutate_field(rng, cards[i]))
    elif len(cards[i]) > 1:
        del cards[i][rng.randrange(1, len(cards[i]))]
    else:
        del cards[i]
    return cards, f"{kind} {name}"


def outcome(path: Path, timeout: float, units: str = "in-lbf-s") -> tuple[str, str]:
    """(class, detail) of reading ``path`` and computing its modes."""
    from asekit.case import pipeline
    from asekit.io import bdf
    signal.setitimer(signal.ITIMER_REAL, timeout)
    try:
        with warnings.catch_warnings(record=True) as rec:
            warnings.simplefilter("always")
            case = bdf.read_bdf(path, units=units)
            pipeline.modal_model(case)
        mine = [w for w in rec if not issubclass(w.category, bdf.UnsupportedCardWarning)
                and w.category.__module__.startswith("asekit")]
        if mine:
            return "ok+warning", str(mine[0].message)[:160]
        return "ok", ""
    except _Timeout:
        return "timeout", f"> {timeout} s"
    except Exception as exc:                      # noqa: BLE001 - the census of failures
        kind = "BdfError" if type(exc).__name__ == "BdfError" else type(exc).__name__
        return kind, str(exc).strip().splitlines()[0][:160] if str(exc).strip() else ""
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)


def run(decks: int, seed: int, timeout: float, show: int, deck: Path = DECK,
        units: str = "in-lbf-s") -> Counter:
    import contextlib
    import io
    head, cards, tail = split_cards(inlined_deck(Path(deck)))
    seen: Counter = Counter()
    samples: dict[str, list] = {}
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "mutant.bdf"
        for n in range(decks):
            rng = random.Random(seed * 100003 + n)
            mutated, what = cards, []
            for _ in range(rng.choice([1, 1, 1, 2, 3])):
                mutated, w = mutate(rng, mutated)
                what.append(w)
            path.write_text("\n".join(head + [ln for c in mutated for ln in c] + tail) + "\n")
            with contextlib.redirect_stdout(io.StringIO()):   # pyNastran prints its errors
                kind, detail = outcome(path, timeout, units)
            seen[kind] += 1
            if kind not in ("ok", "BdfError") or len(samples.get(kind, [])) < 1:
                if len(samples.setdefault(kind, [])) < show:
                    samples[kind].append(f"deck {n} ({', '.join(what)}): {detail}")
    order = ["ok", "ok+warning", "BdfError"]
    keys = order + sorted(k for k in seen if k not in order)
    print(f"{decks} mutated decks of {Path(deck).name} (seed {seed}):")
    for k in keys:
        print(f"  {k:24s}{seen.get(k, 0):6d}")
    print("samples:")
    for k in keys:
        for s in samples.get(k, []):
            print(f"  [{k}] {s}")
    return seen


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--decks", type=int, default=400)
    ap.add_argument("--seed", type=int, default=22)
    ap.add_argument("--timeout", type=float, default=20.0)
    ap.add_argument("--show", type=int, default=3, help="samples printed per class")
    ap.add_argument("--deck", type=Path, default=DECK, help="the deck mutated (default HA145E)")
    ap.add_argument("--units", default="in-lbf-s", help="its units (read_bdf's units)")
    args = ap.parse_args(argv)
    import asekit.case.pipeline  # noqa: F401  (imported before any alarm)
    import asekit.io.bdf  # noqa: F401
    signal.signal(signal.SIGALRM, _alarm)
    run(args.decks, args.seed, args.timeout, args.show, args.deck, args.units)
    return 0


if __name__ == "__main__":
    sys.exit(main())
