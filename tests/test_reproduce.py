"""The main job: ``python -m asekit reproduce --json`` runs and writes the published schema."""

import json
import math
import subprocess
import sys

from asekit.reproduce import available_chapters
from asekit.thesis import all_keys


def test_reproduce_cli_writes_schema(tmp_path):
    out = tmp_path / "r.json"
    proc = subprocess.run([sys.executable, "-m", "asekit", "reproduce", "--json", str(out)],
                          capture_output=True, text=True, timeout=1800)
    assert proc.returncode == 0, proc.stderr
    assert "quantity" in proc.stdout and "verdict" in proc.stdout
    assert max(len(line) for line in proc.stdout.splitlines()) <= 100
    data = json.loads(out.read_text())
    assert set(data) == {"quantities", "seconds", "failures"}
    assert data["failures"] == {}
    assert set(data["seconds"]) == set(available_chapters())
    known = set(all_keys())
    for key, entry in data["quantities"].items():
        assert key in known
        assert set(entry) == {"thesis", "asekit", "unit", "note", "verdict"}
        v = entry["asekit"]
        flat = v if isinstance(v, list) else [v]
        for x in flat:
            assert x is None or isinstance(x, (bool, str)) or math.isfinite(x)


def test_reproduce_rejects_unknown_chapter():
    proc = subprocess.run([sys.executable, "-m", "asekit", "reproduce", "--only", "nope"],
                          capture_output=True, text=True)
    assert proc.returncode == 2                                   # an argparse error
    assert "unknown chapter 'nope'; choose from servo" in proc.stderr
    assert "Traceback" not in proc.stderr
