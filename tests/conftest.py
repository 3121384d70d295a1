import os

os.environ.setdefault("MPLBACKEND", "Agg")


def pytest_configure(config):
    """hypothesis keeps its example database (disabled by the profiles in test_properties.py)
    and its constants cache in ``.hypothesis/`` under the working directory; put them in the
    user cache instead, so that a test run writes nothing into the checkout."""
    try:
        from hypothesis.configuration import set_hypothesis_home_dir
    except ImportError:                     # hypothesis absent: nothing to redirect
        return
    from asekit.util.paths import user_cache_dir
    set_hypothesis_home_dir(str(user_cache_dir() / "hypothesis"))
