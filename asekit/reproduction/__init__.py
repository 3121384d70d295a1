"""One module per thesis chapter, each with ``run(figures: bool) -> ChapterResult``.

Used by :mod:`asekit.reproduction.driver` (``python -m asekit reproduce``). A chapter module computes its
values with asekit and returns them keyed by the stable dotted names of ``data/thesis.toml``.
"""
