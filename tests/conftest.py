"""Shared fixtures of the test suite: the reference fin as a :class:`asekit.case.Case`
(``data/cases/nalci2013_fin.toml``) and what the case pipeline builds from it.

Every fixture goes through :mod:`asekit.case` (``load_case`` and ``asekit.case.pipeline``), never
through ``asekit.reproduction``: the physics tests test the physics layer, the reproduction tests
(``tests/reproduction/``) test the reproduction. The fin's variants are ``dataclasses.replace``
of its case (:func:`fin_variant`).

Session-scoped objects are shared by every test, so what they hand out cannot be changed: the
case is frozen, :class:`~asekit.aero.boxes.BoxMesh` arrays are read-only already, and the
modal models and GAF databases are read-only copies (the pipeline memoises its models and would
otherwise hand the same arrays to every caller). A test that needs to modify one copies it
(``np.array(model.M)``, ``dataclasses.replace``).
"""

import dataclasses
import os

import numpy as np
import pytest

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


# ---------------------------------------------------------------------------------------------
# helpers (plain functions; the fixtures below hand them out)
# ---------------------------------------------------------------------------------------------
def _read_only(a) -> np.ndarray:
    a = np.array(a)                         # a copy: the original stays writeable for its owner
    a.setflags(write=False)
    return a


def read_only_model(model):
    """A copy of a :class:`~asekit.structure.modes.ModalModel` whose arrays are read-only."""
    return dataclasses.replace(model, **{f.name: _read_only(getattr(model, f.name))
                                         for f in dataclasses.fields(model)
                                         if isinstance(getattr(model, f.name), np.ndarray)})


def read_only_database(db):
    """A copy of a :class:`~asekit.aero.gaf.GafDatabase` whose arrays are read-only."""
    return dataclasses.replace(db, machs=_read_only(db.machs), k=_read_only(db.k),
                               Q=_read_only(db.Q), metadata=dict(db.metadata))


_KEEP = object()


def fin_variant_of(case, *, model=None, radius=_KEEP, mesh=None, boxes=_KEEP, symmetry=None,
                   f_max=None, u_min=None, modes_count=_KEEP):
    """A variant of a one-panel shaft case (the reference fin) by ``dataclasses.replace``.

    Parameters
    ----------
    case : asekit.case.Case
        The case to vary (one panel).
    model : {"FN1", "FN2"}, optional
        ``support.model``: FN1 (shaft spring to ground, no rigid mode) or FN2.
    radius : float or None, optional
        ``support.radius`` (m): the distributed shaft of that radius; None the single node.
    mesh : (int, int), optional
        ``panel[0].n_chord, n_span``: the FE mesh (elements).
    boxes : (int, int) or None, optional
        ``aero.boxes[0]``: the doublet-lattice boxes (chordwise, spanwise); None automatic.
    symmetry : {"none", "wall"}, optional
        ``aero.symmetry``: "wall" puts a reflection plane at the root.
    f_max : float, optional
        ``modes.f_max`` (Hz): the elastic modes kept.
    u_min : float, optional
        ``aero.u_min`` (m/s) of the mesh rules and the automatic reduced frequencies.
    modes_count : int or None, optional
        ``modes.count``: the first that many elastic modes instead of all below f_max.

    Returns
    -------
    asekit.case.Case
        The varied case (frozen; not re-checked by the schema: the pipeline reports what it
        cannot build).
    """
    r = dataclasses.replace
    support, panels, aero, modes = case.support, case.panels, case.aero, case.modes
    if model is not None:
        support = r(support, model=model)
    if radius is not _KEEP:
        support = r(support, radius=radius)
    if mesh is not None:
        panels = (r(panels[0], n_chord=mesh[0], n_span=mesh[1]),) + tuple(panels[1:])
    if boxes is not _KEEP:
        aero = r(aero, boxes=None if boxes is None else (tuple(boxes),))
    if symmetry is not None:
        aero = r(aero, symmetry=symmetry)
    if u_min is not None:
        aero = r(aero, u_min=u_min)
    if f_max is not None:
        modes = r(modes, f_max=f_max)
    if modes_count is not _KEEP:
        modes = r(modes, count=modes_count)
    return r(case, support=support, panels=panels, aero=aero, modes=modes)


# ---------------------------------------------------------------------------------------------
# fixtures
# ---------------------------------------------------------------------------------------------
@pytest.fixture(scope="session")
def fin_case():
    """The reference fin's :class:`~asekit.case.Case` (``data/cases/nalci2013_fin.toml``)."""
    from asekit.case import load_case
    from asekit.util.paths import FIN_FILE
    return load_case(FIN_FILE)


@pytest.fixture(scope="session")
def fin_variant(fin_case):
    """``fin_variant(**changes) -> Case``: the reference fin varied, see :func:`fin_variant_of`
    (e.g. ``fin_variant(model="FN1")``, ``fin_variant(radius=0.005, mesh=(12, 14))``,
    ``fin_variant(boxes=(8, 6), symmetry="wall")``)."""
    def variant(**changes):
        return fin_variant_of(fin_case, **changes)
    return variant


@pytest.fixture(scope="session")
def modal_of():
    """``modal_of(case) -> ModalModel``: the pipeline's modal model of a case, as a read-only
    copy (the pipeline's memo keeps its own)."""
    from asekit.case import pipeline

    def modal(case):
        return read_only_model(pipeline.modal_model(case))
    return modal


@pytest.fixture(scope="session")
def fin_modal(fin_case, modal_of):
    """The fin's FN2 modal model (rigid pitch + elastic modes below 1000 Hz, 6 x 7 mesh,
    single-node shaft), read-only."""
    return modal_of(fin_case)


@pytest.fixture(scope="session")
def fin_fn1_modal(fin_variant, modal_of):
    """The fin's FN1 modal model (shaft spring to ground, no rigid mode), read-only."""
    return modal_of(fin_variant(model="FN1"))


@pytest.fixture(scope="session")
def boxes_of(fin_variant):
    """``boxes_of(n_chord=None, n_span=None) -> BoxMesh``: the fin's doublet-lattice boxes,
    automatic from the mesh rules (14 x 10 for the fin) or ``n_chord x n_span``."""
    from asekit.case import pipeline

    def boxes(n_chord=None, n_span=None):
        if (n_chord is None) != (n_span is None):
            raise ValueError("boxes_of: give both n_chord and n_span or neither")
        return pipeline.box_mesh(fin_variant(boxes=None if n_chord is None
                                             else (n_chord, n_span)))
    return boxes


@pytest.fixture(scope="session")
def fin_box_mesh(fin_case):
    """The fin's doublet-lattice boxes (mesh rules: 14 chordwise x 10 spanwise)."""
    from asekit.case import pipeline
    return pipeline.box_mesh(fin_case)


@pytest.fixture(scope="session")
def fin_gafs(fin_case):
    """The fin's GAF database (Mach 0.4, 0.5, 0.6, 0.75 x 15 k; the shipped
    ``data/gaf_fin.npz`` or the user cache), read-only."""
    from asekit.case import pipeline
    return read_only_database(pipeline.gaf_database(fin_case, progress=False))


@dataclasses.dataclass(frozen=True)
class AseSetup:
    """The fin's aeroservoelastic model at one flight condition and what it was built from:
    ``case``, ``model`` (:class:`asekit.ase.loop.AeroservoelasticModel`), ``modal`` (ModalModel),
    ``rfa`` (Roger fit at ``mach``), ``mach``, ``altitude`` (m), ``density`` (kg/m^3),
    ``velocity`` (m/s, M a)."""

    case: object
    model: object
    modal: object
    rfa: object
    mach: float
    altitude: float
    density: float
    velocity: float


def ase_setup(case, modal, db, mach: float, altitude: float, n_lags: int = 4) -> AseSetup:
    """The Ch. 5 model of a shaft case at (mach, altitude) built as :func:`asekit.case.pipeline.ase`
    builds it, without its step simulations: a Roger fit with ``n_lags`` lags of the GAFs at
    ``mach`` (interpolated between the database's Machs), the 1976 standard atmosphere,
    U = M a, the fin-root pitch and the four corner outputs, the case's actuator."""
    from asekit.aeroelastic.statespace import fin_outputs
    from asekit.ase.loop import build_model
    from asekit.atmosphere import standard_atmosphere
    from asekit.case import pipeline
    from asekit.rfa import roger_fit

    g = db.at(mach, interpolate=True)
    k, q = g.k, g.Q
    rfa = roger_fit(k, q, db.b_ref, n_lags=n_lags, mach=mach)
    atm = standard_atmosphere(altitude)
    rho, U = float(atm.density), mach * float(atm.speed_of_sound)
    corners = pipeline.corner_points(case)
    rows = fin_outputs(modal, np.array(list(corners.values())), names=list(corners),
                       shaft_point=case.support.axis_point)
    actuator = pipeline.actuator_setup(case)[0]
    return AseSetup(case, build_model(modal, rfa, rho, U, rows, actuator=actuator, mach=mach),
                    modal, rfa, float(mach), float(altitude), rho, U)


@pytest.fixture(scope="session")
def fin_ase(fin_case, fin_modal, fin_gafs):
    """The fin's aeroservoelastic model at Mach 0.5, sea level (the case's
    ``[actuator.condition]``), see :func:`ase_setup`."""
    a = fin_case.actuator
    return ase_setup(fin_case, fin_modal, fin_gafs, a.mach, a.altitude)


@pytest.fixture(scope="session")
def thesis_table():
    """The thesis's reported values, ``data/thesis.toml`` as read by tomllib: ``{key: {"value":
    ..., "unit": ..., "source": ...}}`` (the reference numbers physics tests compare with)."""
    import tomllib

    from asekit.util.paths import THESIS_FILE
    with open(THESIS_FILE, "rb") as fh:
        return tomllib.load(fh)


@pytest.fixture
def session_gaf_cache(tmp_path_factory, monkeypatch):
    """Rebuilt GAF databases go to one session temporary folder, never the user's cache (the
    fin's database is shipped in data/ and only read). Use it per module with
    ``pytestmark = pytest.mark.usefixtures("session_gaf_cache")``."""
    monkeypatch.setenv("ASEKIT_CACHE_DIR", str(tmp_path_factory.getbasetemp() / "gaf-cache"))


# ---------------------------------------------------------------------------------------------
# active flutter suppression on the fin (tests/ase/test_afs.py, tests/ase/test_sensors.py)
# ---------------------------------------------------------------------------------------------
@pytest.fixture(scope="session")
def afs_family(fin_ase):
    """The fin's :class:`asekit.ase.afs.SpeedFamily` at :func:`fin_ase`'s condition, with the
    tip trailing-edge deflection (x 0.156 m, y 0.15 m) as its one output."""
    from asekit.aeroelastic.statespace import fin_outputs
    from asekit.ase import afs
    rows = fin_outputs(fin_ase.modal, np.array([[0.156, 0.15]]), names=["tip_te"],
                       shaft_point=fin_ase.case.support.axis_point)
    return afs.SpeedFamily(fin_ase.modal, fin_ase.rfa, fin_ase.density, rows,
                           fin_ase.model.actuator, fin_ase.mach)


@pytest.fixture(scope="session")
def afs_open_loop(afs_family):
    """The open-loop (actuator-locked) stability boundary of :func:`afs_family` on
    ``small_cases.AFS_GRID`` (tol 1e-3 m/s)."""
    from small_cases import AFS_GRID

    from asekit.ase import afs
    return afs.stability_boundary(lambda u: afs.locked_matrix(afs_family, u), AFS_GRID, tol=1e-3)
