"""asekit's version (``asekit.__version__``), one place: pyproject.toml's ``version`` must match
(tests/test_packaging.py). Written into cache metadata (GAF databases, supersonic results)."""

__version__ = "0.1.0"
