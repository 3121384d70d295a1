"""The main job: ``python -m asekit reproduce --json`` runs and writes the published schema."""

import json
import math
import subprocess
import sys

import pytest

from asekit.reproduction.driver import available_chapters
from asekit.reproduction.thesis import all_keys


def _reproduce_json(tmp_path, *only):
    out = tmp_path / "r.json"
    args = [sys.executable, "-m", "asekit", "reproduce", "--json", str(out)]
    if only:
        args += ["--only", *only]
    proc = subprocess.run(args, capture_output=True, text=True, timeout=1800)
    assert proc.returncode == 0, proc.stderr
    assert "quantity" in proc.stdout and "verdict" in proc.stdout
    assert max(len(line) for line in proc.stdout.splitlines()) <= 100
    return json.loads(out.read_text())


def _check_schema(data, chapters):
    assert set(data) == {"quantities", "seconds", "failures", "counts"}
    assert data["failures"] == {}
    assert set(data["seconds"]) == set(chapters)
    # issue 30: the counts of the table, "not computed" apart from "not reported"; every
    # thesis row is in the table or counted as not run
    counts = data["counts"]
    verdicts = [e["verdict"] for e in data["quantities"].values()]
    assert {k: v for k, v in counts.items() if k not in ("not run", "chapters not run")} == \
        {v: verdicts.count(v) for v in set(verdicts)}
    assert counts["not run"] + len(data["quantities"]) == len(all_keys())
    assert set(counts["chapters not run"]).isdisjoint(chapters)
    known = set(all_keys())
    assert data["quantities"]
    for key, entry in data["quantities"].items():
        assert key in known
        assert set(entry) == {"thesis", "asekit", "unit", "note", "verdict"}
        v = entry["asekit"]
        flat = v if isinstance(v, list) else [v]
        for x in flat:
            assert x is None or isinstance(x, (bool, str)) or math.isfinite(x)


def test_reproduce_cli_writes_schema_one_chapter(tmp_path):
    # the JSON schema and the table's width through the command line, on the cheapest
    # chapter; every chapter: the slow test below
    _check_schema(_reproduce_json(tmp_path, "aero"), ["aero"])


@pytest.mark.slow
def test_reproduce_cli_writes_schema(tmp_path):
    # the whole reproduction (every chapter) through the command line: about 20-60 s
    _check_schema(_reproduce_json(tmp_path), available_chapters())


def test_reproduce_rejects_unknown_chapter():
    proc = subprocess.run([sys.executable, "-m", "asekit", "reproduce", "--only", "nope"],
                          capture_output=True, text=True)
    assert proc.returncode == 2                                   # an argparse error
    assert "unknown chapter 'nope'; choose from servo" in proc.stderr
    assert "Traceback" not in proc.stderr
