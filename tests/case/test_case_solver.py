"""The case key aero.solver (asekit.aero.hmatrix): parsed and checked, in the fingerprint only
when it is not the default "dense" (the fingerprints of existing cases stay)."""

from __future__ import annotations

import tomllib

import pytest

from asekit.case import CaseError, case_from_dict
from asekit.util.paths import CASES_DIR

FIN = CASES_DIR / "nalci2013_fin.toml"


def _dict() -> dict:
    with open(FIN, "rb") as fh:
        return tomllib.load(fh)


def test_solver_key():
    base = case_from_dict(_dict())
    assert base.aero.solver == "dense"
    d = _dict()
    d["aero"]["solver"] = "dense"
    assert case_from_dict(d).fingerprint() == base.fingerprint()
    d["aero"]["solver"] = "hmatrix"
    c = case_from_dict(d)
    assert c.aero.solver == "hmatrix" and c.fingerprint() != base.fingerprint()
    d["aero"]["solver"] = "lu"
    with pytest.raises(CaseError, match="aero.solver"):
        case_from_dict(d)
