"""The thesis's reference fin as a case (``data/cases/nalci2013_fin.toml``,
:data:`asekit.util.paths.FIN_FILE`) and the few thesis constants its chapters share.

Every model of the reproduction is built by the case pipeline (:mod:`asekit.case.pipeline`) on
:func:`fin_case` or on a variant of it (:mod:`asekit.case.variants`: FN1, refined meshes, the
distributed shaft, the symmetry wall); nothing here builds a model.
"""

from __future__ import annotations

from functools import lru_cache

from asekit.case.schema import Case, load_case
from asekit.case.variants import with_mesh, with_shaft
from asekit.util.paths import FIN_FILE

#: Radius (m) of the fin's physical shaft region assumed for the distributed-shaft model (the
#: case file holds the thesis's single-node shaft; the thesis gives no radius).
DEFAULT_SHAFT_RADIUS = 0.005

#: The fin corners reported in Fig 71-72, as planform fractions (chord xi, span eta); the same
#: points, in the same order, as :func:`asekit.case.pipeline.corner_points`.
CORNERS = {"root_le": (0.0, 0.0), "root_te": (1.0, 0.0), "tip_le": (0.0, 1.0),
           "tip_te": (1.0, 1.0)}


@lru_cache(maxsize=1)
def fin_case() -> Case:
    """The reference fin's case (read once per process; a frozen :class:`asekit.case.Case`)."""
    return load_case(FIN_FILE)


def distributed_case(n_chord: int | None = None, n_span: int | None = None,
                     radius: float | None = None, case: Case | None = None) -> Case:
    """The fin (default :func:`fin_case`) with the distributed (rigid-region) shaft of
    ``radius`` m (default the case's, else :data:`DEFAULT_SHAFT_RADIUS`) on an
    ``n_chord x n_span`` mesh (default the case's)."""
    case = fin_case() if case is None else case
    if radius is None:
        radius = DEFAULT_SHAFT_RADIUS if case.support.radius is None else case.support.radius
    return with_mesh(with_shaft(case, radius=radius), n_chord, n_span)


def fn1_case(case: Case | None = None) -> Case:
    """The thesis's model FN1 of the fin (shaft spring to ground, no rigid mode; Sec. 3.1.1,
    Fig 12)."""
    return with_shaft(fin_case() if case is None else case, model="FN1")
