"""Property-based tests over the public entry points (issue 11): every call returns finite,
plausible results or raises ValueError/TypeError naming an argument -- no crash, no silent NaN,
no unreported instability. Targets and the outcome classes: tests/property_targets.py.

Example counts: the ``asekit-default`` hypothesis profile (small, fast: the default test run);
``ASEKIT_HYPOTHESIS_PROFILE=thorough pytest tests/test_properties.py`` for the large profile.
The before/after crash counts of issue 11 come from ``python tests/benchmarks/fuzz_count.py``.
"""

import os

import pytest
from hypothesis import HealthCheck, given, settings
from property_targets import TARGETS, classify

settings.register_profile("asekit-default", max_examples=12, deadline=None, database=None,
                          derandomize=True,
                          suppress_health_check=[HealthCheck.too_slow,
                                                 HealthCheck.filter_too_much])
settings.register_profile("thorough", max_examples=400, deadline=None, database=None,
                          suppress_health_check=[HealthCheck.too_slow,
                                                 HealthCheck.filter_too_much])
settings.load_profile(os.environ.get("ASEKIT_HYPOTHESIS_PROFILE", "asekit-default"))


def _make(target):
    @given(target.strategy)
    def check(kwargs):
        outcome = classify(target, kwargs)
        assert outcome.kind in ("ok", "refused"), f"{target.name}{kwargs}: {outcome}"
    return check


@pytest.mark.parametrize("target", TARGETS, ids=[t.name for t in TARGETS])
def test_entry_point_never_lies(target):
    _make(target)()
