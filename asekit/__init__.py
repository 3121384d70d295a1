"""asekit: an open Python workbench for the aeroservoelastic modelling of control surfaces.

One road from a surface to its answers: a case (a TOML case file, a Nastran deck or frozen
dataclasses built in Python) goes through the case pipeline -- structure (plate FE -> modes) ->
aerodynamics (boxes -> doublet lattice, Mach box or piston theory -> GAFs) -> rational function
approximation -> flutter and the aeroservoelastic loop. SI units everywhere inside the package;
degrees and Hz only at the edges (plots, tables); conventions in ``docs/conventions.md``, the
layout in ``docs/architecture.md``.

The public API is small:

- :func:`load_case`, :class:`Case`, :class:`CaseError` (:mod:`asekit.case`);
- :mod:`pipeline` (:mod:`asekit.case.pipeline`): ``modal_model(case)``, ``box_mesh(case)``,
  ``gaf_database(case)``, ``flutter(case)``, ``ase(case)``.

Examples
--------
>>> import asekit
>>> case = asekit.load_case(asekit.FIN_FILE)
>>> case.name
'nalci2013_fin'
"""

import logging

from asekit.case import Case, CaseError, load_case
from asekit.util.paths import CASES_DIR, FIN_FILE
from asekit.util.version import __version__

# Library etiquette (Python's logging HOWTO, "Configuring Logging for a Library"): every module
# logs to its own logger (``logging.getLogger(__name__)``, children of "asekit"); the package
# adds only a NullHandler and configures nothing else. The command line shows the messages
# (-v, --log-file: asekit.cli.main); in Python, ``logging.basicConfig(level=logging.INFO)``.
logging.getLogger(__name__).addHandler(logging.NullHandler())

__all__ = ["CASES_DIR", "Case", "CaseError", "FIN_FILE", "load_case", "pipeline", "__version__"]


def __getattr__(name):
    """``asekit.pipeline`` imported on first use (PEP 562): ``python -m asekit`` then reports a
    refused input before the pipeline's imports (python-control, matplotlib) are paid for."""
    if name == "pipeline":
        from asekit.case import pipeline
        return pipeline
    raise AttributeError(f"module 'asekit' has no attribute {name!r}")
