"""Nastran bulk data (BDF) in and out, through pyNastran.

Import (:func:`read_bdf`): a flat plate-wing deck becomes a :class:`~asekit.case.Case` of the
case pipeline, its structure built with asekit's own finite elements (MITC4,
:mod:`asekit.structure.plate`) -- not Nastran's matrices -- so that a user can compare the two
codes: ``case.structure`` (:class:`~asekit.case.imported.ImportedModel`) holds the mesh, K, M,
the deck's own supports (SPC / GRID PS / RBE2 / CELAS, applied as they are) and the CAERO1
boxes; ``case.aero`` / ``case.flight`` / ``case.modes`` hold MKAERO1, FLUTTER + FLFACT and
EIGRL. Everything else is the pipeline's::

    case = bdf.read_bdf("data/benchmarks/ha145e/ha145e.bdf", units="in-lbf-s")
    pipeline.modal_model(case); pipeline.gaf_database(case); pipeline.flutter(case)

(asekit's own doublet lattice, :mod:`asekit.aero.dlm`, and p-k). :func:`read_deck` gives the
deck's record (:class:`BdfModel`, with the Nastran ids) and :func:`deck_case` makes it a case;
one reader per card (``_read_grids``, ``_read_pshell``, ``_read_celas``, ... each with the
card's field table). Export (:func:`write_case_bdf`): a case -- declarative or imported -- as
a deck that pyNastran reads and Nastran runs (SOL 103 or SOL 145 case control), its support
written by kind (:data:`SUPPORT_CARDS`), its control surfaces as CAERO1 + CORD2R + AELIST +
AESURF (:func:`_control_surface_cards`).

Reader API (shared with :mod:`asekit.io.bdf_beam`)
--------------------------------------------------
The aerodynamic and solution readers are public so that the stick-model reader uses the same
code: :func:`need_pynastran`, :class:`Deck` (one import's units and notes),
:func:`read_aero_card` (AERO / AEROS), :func:`check_caero1` and :func:`deck_boxes` (CAERO1),
:func:`aero_axes` and :func:`deck_boxes_aero` (boxes in a rotated ACSID, stick decks),
:func:`read_mkaero1`, :func:`read_flutter` (FLUTTER + FLFACT), :func:`case_value` (case
control) and :func:`solve_request` (one FLUTTER card with its own method).

Supported cards and what asekit makes of them
---------------------------------------------
GRID (basic or CORD2R/CORD1R... any coordinate system pyNastran resolves; ``PS`` permanent
constraints), CQUAD4 (corner thicknesses T1-T4; material angle THETA or MCID) with PSHELL
(MID1 = MID2, 12I/T^3, NSM), MAT1, MAT8, CONM2 (mass, offset ignored in-plane, I11 and I22),
SPC / SPC1, CELAS1 (PELAS) / CELAS2 springs to ground or between grids, RBE2 (a rigid region,
e.g. the shaft), CAERO1 with PAERO1 (NSPAN/NCHORD or AEFACT LSPAN/LCHORD divisions),
SPLINE1 / SPLINE4 with SET1 / AELIST (checked: every box must be splined), AERO / AEROS (REFC,
RHOREF, SYMXZ), AESURF with its AELIST and hinge CORD2R (a rigid control surface of the case,
:func:`_read_aesurf`; AESURFS and AELINK kept, :func:`_read_aelinks`), MKAERO1, FLFACT,
FLUTTER (K, KE, PK, PKNL: :func:`deck_flutter` runs each
card with its own method), EIGR / EIGRL (number of modes or the frequency range), TABDMP1 (G or CRIT modal damping), PARAM WTMASS. CTRIA3 is modelled as a
degenerated MITC4 (its third node repeated: a collapsed quadrilateral, Bathe, *Finite Element
Procedures*, 1996, Ch. 5), stiffer than the quadrilateral on coarse meshes but convergent
(tests/io/test_bdf.py: NAFEMS FV16). Solids, beams, bars, rods and other shells are refused with
the list of what is missing. Every other card (e.g. ASET1, PARAM POST, plot cards) is
listed in one :class:`UnsupportedCardWarning` (name, count, first id) and otherwise ignored.
PARAM COUPMASS is read as Nastran reads it: > 0 the consistent plate mass, else (and by
default) the lumped mass, translational only (:func:`lumped_translational_mass`); the export
writes PARAM COUPMASS 1 for asekit's own (consistent) plate.

What asekit models: the out-of-plane bending of a flat plate in the plane z = z0 (degrees of
freedom T3, R1, R2 of each GRID = asekit's w, theta_x, theta_y; the in-plane DOFs 1, 2, 6 are
uncoupled from bending for a flat plate and are dropped). Differences from Nastran a user should
expect: asekit's plate is Reissner-Mindlin with consistent translational *and* rotary inertia
under PARAM COUPMASS 1 (Nastran's CQUAD4 mass has no rotary inertia; PSHELL MID3 blank makes Nastran's plate
Kirchhoff); ASET1 (Guyan reduction) is ignored, so asekit solves the full model; asekit
interpolates the modes onto the boxes with its finite-element shape functions, not with the
deck's SPLINE1/SPLINE4 surface spline.

Checks (issue 22): every pyNastran error is a :class:`BdfError` naming the card, its id and
field; duplicate ids are errors (:data:`ID_SPACES`); values outside the physical ranges
:data:`RANGES` (checked in SI) and broken MAT1 rules are refused with the card and field; a
structure with rigid-body modes its SPC / GRID PS / CELAS do not hold is refused (declared
free-free by SUPORT: warned); GRIDs and plate pieces that touch nothing are warned about
(:class:`BdfWarning`).

Units: a BDF has no units. ``units`` names the deck's consistent system and every quantity is
converted to SI on import: ``"SI"`` (m, kg, s, N), ``"mm-t-s"`` (mm, tonne, s, N) and
``"in-lbf-s"`` (in, lbf s^2/in, s, lbf; PARAM WTMASS converts the deck's mass input to it).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from asekit.aero.boxes import BoxMesh
from asekit.aero.methods import check_mach
from asekit.case import pipeline as pl
from asekit.case.imported import IMPORTED_SUPPORT, ImportedModel
from asekit.case.schema import AeroSpec, Case, FlightSpec, ModesSpec, SupportSpec
from asekit.geometry import Material, OrthotropicMaterial
from asekit.structure.assembly import SupportedSystem, element_dofs, pitch_inertia
from asekit.structure.mesh import PlateMesh
from asekit.structure.modes import MIN_OUT_OF_PLANE
from asekit.structure.plate import DOF_PER_NODE, consistent_mass, mitc4_stiffness, shape_functions
from asekit.structure.supports import (
    PLANFORM_EDGES,
    partial_support_nodes,
    planform_edge_supports,
)

#: length, mass and time of one deck unit in SI (m, kg, s).
UNITS = {"SI": (1.0, 1.0, 1.0), "mm-t-s": (1e-3, 1e3, 1.0),
         "in-lbf-s": (0.0254, 4.4482216152605 / 0.0254, 1.0)}

#: Cards asekit reads (see the module docstring).
SUPPORTED_CARDS = ("GRID", "CORD2R", "CORD1R", "CORD2C", "CORD2S", "CQUAD4", "CTRIA3", "PSHELL",
                   "MAT1",
                   "MAT8", "CONM2", "SPC", "SPC1", "CELAS1", "CELAS2", "PELAS", "RBE2",
                   "CAERO1", "PAERO1", "AEFACT", "SPLINE1", "SPLINE4", "SET1", "AELIST", "AERO",
                   "AESURF", "AESURFS", "AELINK",
                   "AEROS", "MKAERO1", "FLFACT", "FLUTTER", "EIGR", "EIGRL", "TABDMP1",
                   "PARAM", "ENDDATA")
#: Element cards asekit cannot represent: a deck holding one of them is refused.
REFUSED_CARDS = ("CTRIA6", "CTRIAR", "CQUAD8", "CQUADR", "CQUAD", "CSHEAR", "CTETRA",
                 "CPENTA", "CHEXA", "CPYRAM", "CBAR", "CBEAM", "CBEAM3", "CROD", "CONROD",
                 "CTUBE", "CBEND", "CBUSH", "CBUSH1D", "CGAP", "CELAS3", "CELAS4", "CDAMP1",
                 "CDAMP2", "CVISC", "CMASS1", "CMASS2", "CMASS3", "CMASS4", "CONM1", "RBE3",
                 "RBAR", "RBAR1", "RROD", "MPC", "CAERO2", "CAERO3", "CAERO4", "CAERO5",
                 "PCOMP", "PCOMPG")
#: PARAMs asekit applies.
_USED_PARAMS = ("WTMASS", "COUPMASS")


class UnsupportedCardWarning(UserWarning):
    """Cards of a BDF that asekit read but does not represent (listed once per import)."""


class BdfError(ValueError):
    """A BDF that asekit cannot represent; the message lists what is missing."""


def need_pynastran():
    """pyNastran's ``BDF`` class, the deck parser of every reader here (public reader API,
    shared by :mod:`asekit.io.bdf` and :mod:`asekit.io.bdf_beam`).

    Returns
    -------
    type
        ``pyNastran.bdf.bdf.BDF``.

    Raises
    ------
    ImportError
        pyNastran is not installed (one line naming the package to install).

    Examples
    --------
    >>> need_pynastran().__name__                               # doctest: +SKIP
    'BDF'
    """
    try:
        from pyNastran.bdf.bdf import BDF
    except ImportError as exc:                                    # pragma: no cover
        raise ImportError("asekit.io.bdf needs pyNastran: pip install pyNastran "
                          "(see environment.txt)") from exc
    return BDF


# ---------------------------------------------------------------------------------------------
# the imported model
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FlutterRequest:
    """A FLUTTER card resolved to SI, as Nastran reads it: ``method`` (K, KE, PK, PKNL),
    ``densities`` (kg/m^3, FLFACT DENS x RHOREF), ``machs``, ``velocities`` (m/s, absolute
    values; PK / PKNL) or ``reduced_frequencies`` (K / KE, FLFACT RFREQ), ``print_vectors``
    (one flag per velocity: negative in the FLFACT, Nastran prints the eigenvectors there),
    ``imeth`` ('L' linear or 'S' surface interpolation of Q in k), ``nvalue`` (number of
    roots printed, None: all) and ``eps`` (k convergence of PK / PKNL). K, KE and PK loop over
    every density x Mach (x velocity or k); PKNL's equal-length lists are matched point by
    point (point i = (densities[i], machs[i], velocities[i]))."""

    sid: int
    method: str
    densities: tuple[float, ...]
    machs: tuple[float, ...]
    velocities: tuple[float, ...]
    reduced_frequencies: tuple[float, ...] = ()
    print_vectors: tuple[bool, ...] = ()
    imeth: str = "L"
    nvalue: int | None = None
    eps: float = 1e-3

    def points(self) -> list[tuple[float, float]]:
        """The (density, Mach) pairs a K / KE / PK request loops over (Mach outer, density
        inner)."""
        return [(d, m) for m in self.machs for d in self.densities]


@dataclass(frozen=True)
class BdfModel:
    """A read plate-wing deck, the record :func:`read_deck` gives (SI): what the case of
    :func:`deck_case` is made of, plus the Nastran ids the export writes back (the case's
    ``structure.deck``). Analyse the case, not this record.

    Attributes
    ----------
    mesh : the plate mesh over all GRIDs (nodes that no element uses carry only springs,
        masses or rigid links); node_ids : (n_nodes,) the GRID id of each node.
    K, M : global sparse stiffness and mass (3 DOFs per node: w, theta_x, theta_y), springs
        (CELAS) in K and point masses (CONM2) and NSM in M.
    system : the supported system (SPC, GRID PS and RBE2 eliminated) for the eigen-analysis.
    boxes : the doublet-lattice boxes of the CAERO1 cards (None without aero); box_ids the
        Nastran box ids; b_ref : reference semichord REFC / 2 (m); rho_ref (kg/m^3);
        symmetric : SYMXZ = 1 (a wall at y = 0).
    machs, reduced_frequencies : the MKAERO1 grid (all pairs); flutter : the FLUTTER requests.
    n_modes, f_max_hz : from EIGR / EIGRL (None when absent), eigen_card : that card and its
        id ('EIGRL 10'; '' without one), named by errors about the number of modes; damping_g : (frequency Hz,
        g) table from TABDMP1 (CRIT converted to g = 2 zeta) or None.
    materials : {(pid, material angle rad): material}; element_pids, element_angles :
        (n_elem,) property id and material 1-axis angle (rad from +x) of each element;
        springs : (dof a, dof b or -1 for ground, k SI) in global DOF numbers; masses :
        (node index, mass kg, offset (3,) m, (I11, I21, I22) kg m^2); fixed : the constrained
        global DOFs; rigid : (independent node index, component string, dependent node
        indices) per RBE2; ignored : the (card, count, first id) left out; notes; path : the
        file read; units : its unit system (a key of :data:`UNITS`).
    control_surfaces : the AESURF cards (:class:`DeckControlSurface`); aelinks : the AELINK
        cards as (dependent label, ((independent label, coefficient), ...)), kept, not applied.
    coupled_mass : PARAM COUPMASS > 0 (the consistent plate mass); False: Nastran's default
        lumped mass (:func:`lumped_translational_mass`).
    """

    mesh: PlateMesh
    node_ids: np.ndarray
    K: sp.csr_matrix
    M: sp.csr_matrix
    system: SupportedSystem
    boxes: BoxMesh | None = None
    box_ids: np.ndarray | None = None
    b_ref: float | None = None
    rho_ref: float | None = None
    symmetric: bool = False
    machs: tuple[float, ...] = ()
    reduced_frequencies: tuple[float, ...] = ()
    flutter: tuple[FlutterRequest, ...] = ()
    n_modes: int | None = None
    f_max_hz: float | None = None
    damping_g: tuple[tuple[float, float], ...] | None = None
    eigen_card: str = ""
    materials: dict = field(default_factory=dict)
    element_pids: np.ndarray | None = None
    element_angles: np.ndarray | None = None
    springs: tuple = ()
    masses: tuple = ()
    fixed: tuple = ()
    rigid: tuple = ()
    ignored: tuple[tuple[str, int, object], ...] = ()
    control_surfaces: tuple = ()
    aelinks: tuple = ()
    notes: tuple[str, ...] = ()
    path: str = ""
    units: str = "SI"
    coupled_mass: bool = True

    def node_index(self, grid_id: int) -> int:
        """Mesh node index of GRID ``grid_id``."""
        hit = np.flatnonzero(self.node_ids == int(grid_id))
        if not hit.size:
            raise ValueError(f"grid_id {grid_id} is not a GRID of the deck")
        return int(hit[0])


def _first_id(model, card: str):
    ids = model._type_to_id_map.get(card) if hasattr(model, "_type_to_id_map") else None
    if ids:
        try:
            return min(ids)
        except TypeError:
            return ids[0]
    return None


def _card_report(model) -> tuple[list, list]:
    """(refused, ignored) lists of (card, count, first id)."""
    refused, ignored = [], []
    for card, n in sorted(model.card_count.items()):
        if card in REFUSED_CARDS:
            refused.append((card, n, _first_id(model, card)))
        elif card == "PARAM":
            ignored += [(f"PARAM {name}", 1, None) for name in sorted(model.params)
                        if name not in _USED_PARAMS]
        elif card not in SUPPORTED_CARDS:
            ignored.append((card, n, _first_id(model, card)))
    return refused, ignored


def _fmt(cards) -> str:
    return ", ".join(f"{c} x{n}" + ("" if i is None else f" (first id {i})") for c, n, i in cards)


def _plane(xyz: np.ndarray, tol: float) -> float:
    z = xyz[:, 2]
    if np.ptp(z) > tol:
        raise BdfError(f"the plate elements are not flat in a plane z = const (z spans "
                       f"{z.min():.6g} to {z.max():.6g} in basic coordinates): asekit models a "
                       f"flat plate in the x-y plane")
    return float(z.mean())


def _components(c) -> list[int]:
    """asekit DOF indices (0 w, 1 theta_x, 2 theta_y) of a Nastran component string."""
    return ["345".index(ch) for ch in str(c if c is not None else "") if ch in "345"]


def _scatter(mesh: PlateMesh, Ke: np.ndarray, n: int) -> sp.csr_matrix:
    dofs = element_dofs(mesh)
    rows = np.repeat(dofs, 12, axis=1).ravel()
    cols = np.tile(dofs, (1, 12)).ravel()
    A = sp.csr_matrix((Ke.ravel(), (rows, cols)), shape=(n, n))
    return (0.5 * (A + A.T)).tocsr()


# ---------------------------------------------------------------------------------------------
# one reader per card (the field tables are those of the MSC Nastran Quick Reference Guide)
# ---------------------------------------------------------------------------------------------
@dataclass
class Deck:
    """The working state of one import (public reader API: the card readers
    :func:`read_aero_card`, :func:`check_caero1`, :func:`read_mkaero1`, :func:`read_flutter`
    take it).

    Attributes
    ----------
    model : pyNastran ``BDF``, cross-referenced.
    name : str, the deck's file name (in messages).
    L, Mu, T : float, one deck unit of length (m), mass (kg) and time (s) (:data:`UNITS`).
    wtmass : float, PARAM WTMASS.
    nids, index, xyz, nodes : the GRIDs (ids, id -> row, basic coordinates in deck units,
        in-plane SI coordinates); None / empty until the plate reader sets them.
    z0 : float, the plate's plane (deck units).
    notes, missing : lists of what was read and how, and of what is missing.
    """

    model: object
    name: str
    L: float
    Mu: float
    T: float
    wtmass: float = 1.0
    nids: np.ndarray | None = None
    index: dict = field(default_factory=dict)
    xyz: np.ndarray | None = None
    nodes: np.ndarray | None = None
    z0: float = 0.0
    notes: list = field(default_factory=list)
    missing: list = field(default_factory=list)

    @property
    def n_dof(self) -> int:
        return DOF_PER_NODE * len(self.nids)

    def dof(self, nid, comp: int) -> int:
        """Global DOF of GRID ``nid``, asekit component ``comp`` (0 w, 1 theta_x, 2 theta_y)."""
        return DOF_PER_NODE * self.index[int(nid)] + comp


#: Cards whose ids share one name space (Nastran: an element id is unique over all elements,
#: CONM2 and rigid elements included); a second card with an id already given is an error
#: unless it repeats the first exactly (an identical repeat is read once, with a note).
#: SPC / SPC1 (sets of several cards) and MKAERO1 (no id) are not listed.
ID_SPACES = {"GRID": "GRID", "CQUAD4": "element", "CTRIA3": "element", "CELAS1": "element",
             "CELAS2": "element", "CONM2": "element", "RBE2": "element",
             "PSHELL": "property", "PELAS": "property", "MAT1": "material", "MAT8": "material",
             "CORD2R": "coordinate system", "CORD1R": "coordinate system",
             "CORD2C": "coordinate system", "CORD2S": "coordinate system",
             "CAERO1": "CAERO", "PAERO1": "PAERO", "AEFACT": "AEFACT", "SPLINE1": "spline",
             "SPLINE4": "spline", "SET1": "SET1", "AELIST": "AELIST", "FLFACT": "FLFACT",
             "FLUTTER": "FLUTTER", "EIGR": "method", "EIGRL": "method", "TABDMP1": "TABDMP1",
             "AERO": "AERO", "AEROS": "AEROS", "PARAM": "PARAM", "SUPORT": None}


class BdfWarning(UserWarning):
    """A deck asekit reads but whose model looks unintended (e.g. grids that touch nothing)."""


def _number(v):
    """A Nastran field as a float (``1.5``, ``1.-7``, ``2+3``) or None (blank, not a number)."""
    if v is None:
        return None
    if isinstance(v, (int, float)):
        return float(v)
    s = str(v).strip().upper().replace("D", "E")
    try:
        return float(s)
    except ValueError:
        pass
    for i in range(len(s) - 1, 0, -1):
        if s[i] in "+-" and s[i - 1] not in "E+-":
            try:
                return float(s[:i] + "E" + s[i:])
            except ValueError:
                return None
    return None


def _norm_fields(fields) -> tuple:
    """The fields of a card compared for a repeat: numbers as floats, text upper-case, the
    trailing blanks dropped."""
    out = []
    for v in fields:
        x = _number(v)
        out.append(x if x is not None else (None if v is None or str(v).strip() == ""
                                            else str(v).strip().upper()))
    while out and out[-1] is None:
        out.pop()
    return tuple(out)


def _first_line(exc: BaseException) -> str:
    """The first non-empty line of an exception's message (pyNastran's are multi-line)."""
    text = str(exc.args[0]) if isinstance(exc, KeyError) and exc.args else str(exc)
    lines = [ln.strip() for ln in text.strip("'\" \n").splitlines() if ln.strip()]
    return (lines[0] if lines else type(exc).__name__)[:300]


@dataclass
class _CardTrace:
    """The cards pyNastran parses, seen one by one through ``BDF.add_card``: each card's
    normalised fields by (id space, id), for the duplicate check, and the number of identical
    repeats; each MAT1 is checked on its fields as given (:func:`_check_mat1_fields`)."""

    name: str
    seen: dict = field(default_factory=dict)
    repeats: int = 0

    def record(self, card: str, fields: list) -> bool:
        """Record a card; True for an exact repeat of a card already read (to be dropped);
        BdfError for a second card with the same id and other fields."""
        space = ID_SPACES.get(card, None)
        if card not in ID_SPACES or space is None or len(fields) < 2:
            return False
        norm = (card, _norm_fields(fields))
        key = "-" if card in ("AERO", "AEROS") else (norm[1][1] if len(norm[1]) > 1 else None)
        old = self.seen.get((space, key))
        if old is None:
            self.seen[(space, key)] = norm
            if card == "MAT1":
                _check_mat1_fields(norm[1])
            return False
        if old == norm:
            self.repeats += 1
            return True
        what = card if card in ("AERO", "AEROS") else f"{card} {_fmt_id(key)}"
        raise BdfError(f"{what}: a second card with the {space} id of "
                       f"{old[0]} {_fmt_id(key)} and other fields: duplicate ids are errors "
                       f"(give each card its own id)")


def _fmt_id(key) -> str:
    return f"{key:g}" if isinstance(key, float) else str(key)


def _traced_add_card(model, trace: _CardTrace):
    """``model.add_card`` that records each card in ``trace`` and turns pyNastran's errors
    into a :class:`BdfError` naming the card and its id (pyNastran's message, with the field,
    after it)."""
    orig = model.add_card

    def add_card(card_lines, card_name, comment="", ifile=None, is_list=True, has_none=True):
        name = str(card_name).upper()
        count = model.card_count.get(name)
        try:
            card_obj, _ = model.create_card_object(card_lines, name, is_list=is_list,
                                                   has_none=has_none)
            fields = list(card_obj.card)
            if count is None:                     # the card is counted once, by orig
                model.card_count.pop(name, None)
            else:
                model.card_count[name] = count
        except Exception as exc:
            raise BdfError(f"{name} card unreadable: {_first_line(exc)}") from None
        ident = f"{name} {fields[1]}" if len(fields) > 1 and fields[1] is not None else name
        _check_thru(trace.name, name, fields)
        if trace.record(name, fields):
            return card_obj                       # an exact repeat: read once
        try:
            return orig(card_lines, card_name, comment=comment, ifile=ifile, is_list=is_list,
                        has_none=has_none)
        except BdfError:
            raise
        except Exception as exc:
            raise BdfError(f"{ident}{_include_of(model, ifile, trace.name)}: "
                           f"{_first_line(exc)}") from None
    return add_card


def _include_of(model, ifile, main: str) -> str:
    """`` (in NAME)`` when card ``ifile`` of pyNastran comes from an INCLUDE file."""
    try:
        name = Path(model.active_filenames[ifile]).name
    except (AttributeError, IndexError, TypeError):
        return ""
    return "" if name == main else f" (in {name})"


#: The most ids a "THRU" range of one card may hold (pyNastran expands every range).
MAX_THRU_IDS = 10**6


def _check_thru(name: str, card: str, fields: list) -> None:
    """A ``id1 THRU id2`` range of more than :data:`MAX_THRU_IDS` ids is refused before
    pyNastran expands it (a typo such as 24000000 for 24 would take minutes and gigabytes)."""
    for j in range(1, len(fields) - 1):
        if str(fields[j]).strip().upper() == "THRU":
            lo, hi = _number(fields[j - 1]), _number(fields[j + 1])
            if lo is not None and hi is not None and hi - lo > MAX_THRU_IDS:
                raise BdfError(f"{card} {fields[1]}: {fields[j - 1]} THRU "
                               f"{fields[j + 1]} (fields {j}-{j + 2}) holds {hi - lo + 1:.0f} "
                               f"ids, more than {MAX_THRU_IDS}")


def _check_includes(path: Path, text: str) -> None:
    """Every one-line ``INCLUDE 'file'`` of the deck names a file (relative to the deck's
    folder), checked before pyNastran (which would leave a pyNastran_crash.bdf behind)."""
    for n, line in enumerate(text.splitlines(), 1):
        head = line.split("$")[0].strip()
        if not head.upper().startswith("INCLUDE") or head.count("'") != 2:
            continue
        name = head.split("'")[1]
        if not (path.parent / name).expanduser().is_file():
            raise BdfError(f"line {n}: INCLUDE '{name}': no such file (in {path.parent})")


def _open_deck(path: Path, BDF):
    """The pyNastran model of ``path`` (cross-referenced; a file without BEGIN BULK is read as
    bulk data only) and its :class:`_CardTrace`. Every pyNastran error is a
    :class:`BdfError`: a card's error names the card, its id and (pyNastran's words) the
    field; a reference to a missing card names the card that refers; otherwise the file."""
    model = BDF(debug=None)
    try:
        text = path.read_text(errors="replace")
    except OSError as exc:
        raise BdfError(f"{path}: cannot read the deck ({exc.strerror or exc})") from None
    punch = "BEGIN BULK" not in text.upper()
    _check_includes(path, text)
    trace = _CardTrace(path.name)
    model.add_card = _traced_add_card(model, trace)
    try:
        model.read_bdf(str(path), punch=punch, xref=False, validate=False)
        _validate_cards(model, path.name)
        model.validate()                          # the rest of pyNastran's checks
    except BdfError:
        raise
    except Exception as exc:
        raise BdfError(f"pyNastran cannot read the deck "
                       f"({type(exc).__name__}: {_first_line(exc)})") from None
    try:
        model.cross_reference()
    except Exception as exc:
        raise BdfError(f"a card refers to one the deck does not hold: "
                       f"{_xref_message(exc)}") from None
    return model, trace


#: The pyNastran tables whose cards :func:`_validate_cards` checks one by one.
_VALIDATED = ("nodes", "coords", "elements", "properties", "rigid_elements", "masses",
              "materials", "caeros", "paeros", "splines", "aefacts", "sets", "aelists",
              "flfacts", "flutters", "methods", "tables_sdamping", "mkaeros", "spcs")


def _validate_cards(model, name: str) -> None:
    """pyNastran's own card checks (``card.validate()``), card by card, so that a failure
    names the card and its id."""
    for attr in _VALIDATED:
        table = getattr(model, attr, None) or {}
        cards = table.values() if isinstance(table, dict) else table
        for c in [x for v in cards for x in (v if isinstance(v, list) else [v])]:
            try:
                c.validate()
            except Exception as exc:
                ident = next((getattr(c, a) for a in ("eid", "nid", "pid", "mid", "sid", "cid",
                                                      "tid", "conid") if hasattr(c, a)), "")
                raise BdfError(f"{getattr(c, 'type', attr)} {ident}: "
                               f"{_first_line(exc)}".replace("  ", " ")) from None


def _xref_message(exc) -> str:
    """pyNastran's cross-reference error in one line (its long id lists cut)."""
    text = str(exc.args[0]) if isinstance(exc, KeyError) and exc.args else str(exc)
    lines = [ln.strip() for ln in text.strip("'\" \n").splitlines() if ln.strip()]
    hits = [ln for ln in lines if "required by" in ln or "not found" in ln]
    msg = hits[0] if hits else (lines[0] if lines else type(exc).__name__)
    msg = msg.split("Error: ", 1)[1] if msg.startswith(("KeyError: ", "CrossReferenceError: ")) \
        else msg
    for cut in (". Allowed", "; allowed", "\\n"):
        msg = msg.split(cut)[0]
    return msg.strip("'\" ")[:300]


# ---------------------------------------------------------------------------------------------
# physical ranges (SI) of the fields asekit reads
# ---------------------------------------------------------------------------------------------
#: The range (SI, low, high, whether low is allowed) each kind of field must lie in: wide
#: plausibility bounds (any aircraft or wind-tunnel model lies well inside), so that a typo
#: of a few orders of magnitude or 1e30 is refused with its card and field instead of giving
#: a structure of another scale and "no flutter".
RANGES = {
    "coordinate": (-1.0e4, 1.0e4, True, "m"),
    "length": (0.0, 1.0e4, False, "m"),
    "thickness": (0.0, 10.0, False, "m"),
    "modulus": (1.0e3, 1.0e13, True, "Pa"),
    "density": (0.0, 1.0e5, True, "kg/m^3"),
    "areal mass": (0.0, 1.0e5, True, "kg/m^2"),
    "mass": (0.0, 1.0e7, True, "kg"),
    "inertia": (0.0, 1.0e9, True, "kg m^2"),
    "spring": (0.0, 1.0e20, True, "N/m or N m/rad"),
    "fluid density": (0.0, 2.0e3, False, "kg/m^3"),
    "velocity": (0.0, 1.0e4, False, "m/s"),
    "reduced frequency": (0.0, 100.0, False, ""),
    "damping": (0.0, 1.0, True, ""),
    "frequency": (0.0, 1.0e6, True, "Hz"),
    "factor": (0.0, 1.0e30, False, ""),
}


def _si_factor(deck, kind: str) -> float:
    """SI value of one deck unit of a field of ``kind`` (WTMASS on structural masses)."""
    L, Mu, T, w = deck.L, deck.Mu, deck.T, deck.wtmass
    return {"coordinate": L, "length": L, "thickness": L, "modulus": Mu / (L * T * T),
            "density": w * Mu / L**3, "areal mass": w * Mu / L**2, "mass": w * Mu,
            "inertia": w * Mu * L * L, "fluid density": Mu / L**3, "velocity": L / T,
            "frequency": 1.0 / T}.get(kind, 1.0)


def _check_range(deck, what: str, value, kind: str, si: float | None = None) -> float:
    """``value`` (deck units; ``si`` its SI value if already converted) of the field ``what``
    (card, id and field) checked against :data:`RANGES`; returns the SI value."""
    lo, hi, lo_ok, unit = RANGES[kind]
    v = float(value)
    s = v * _si_factor(deck, kind) if si is None else float(si)
    if not (math.isfinite(s) and (s > lo or (lo_ok and s == lo)) and s <= hi):
        shown = f"{v:g}" + ("" if si is None and _si_factor(deck, kind) == 1.0
                            else f" (= {s:g} {unit})")
        raise BdfError(f"{what} = {shown} is outside the physical range "
                       f"{lo:g} {'<=' if lo_ok else '<'} {kind} <= {hi:g} {unit}".rstrip())
    return s


def _check_mat1_fields(f: tuple) -> None:
    """The MAT1 rules on the fields as given (MSC Nastran QRG, MAT1): two of E, G, NU
    determine the third (G = E / (2 (1 + NU))); E > 0, G > 0 and -1 < NU <= 0.5, given or
    derived. asekit needs two of them (Nastran's "E alone: G = NU = 0" has no shear)."""
    mid = _fmt_id(f[1])
    E, G, nu = (f[i] if len(f) > i else None for i in (2, 3, 4))
    if any(isinstance(v, str) for v in (E, G, nu)):
        return                                   # pyNastran names the bad field
    given = [n for n, v in zip(("E", "G", "NU"), (E, G, nu)) if v is not None]
    if len(given) < 2:
        raise BdfError(f"MAT1 {mid}: {' and '.join(given) or 'none of E, G, NU'} given: "
                       f"asekit needs two of E, G, NU (the third is G = E / (2 (1 + NU)))")
    for n, v in (("E", E), ("G", G)):
        if v is not None and not v > 0:
            raise BdfError(f"MAT1 {mid}: {n} = {v:g} must be > 0")
    derived = nu is None
    nu = E / (2.0 * G) - 1.0 if derived else nu
    if not -1.0 < nu <= 0.5:
        how = f" (from E = {E:g} and G = {G:g}: NU = E / (2 G) - 1)" if derived else ""
        raise BdfError(f"MAT1 {mid}: NU = {nu:g}{how} is outside -1 < NU <= 0.5")


def _check_grid_ranges(deck) -> None:
    """GRID X1-X3 (basic) within :data:`RANGES` ``coordinate``."""
    bad = np.flatnonzero(~np.all(np.abs(deck.xyz * deck.L) <= RANGES["coordinate"][1], axis=1))
    if bad.size:
        i = int(bad[0])
        j = int(np.argmax(~(np.abs(deck.xyz[i] * deck.L) <= RANGES["coordinate"][1])))
        _check_range(deck, f"GRID {deck.nids[i]} X{j + 1} (basic)", deck.xyz[i, j],
                     "coordinate")


def _read_param_wtmass(model, name: str = "") -> float:
    """PARAM WTMASS: the factor from the deck's mass input to its mass unit (default 1; > 0).

    +-------+--------+--------+
    |   1   |   2    |   3    |
    +=======+========+========+
    | PARAM | WTMASS | value  |
    +-------+--------+--------+
    """
    wt = model.params.get("WTMASS")
    if wt is None:
        return 1.0
    v = _number(wt.values[0] if wt.values else None)
    if v is None or not (math.isfinite(v) and 0.0 < v < 1.0e30):
        raise BdfError(f"PARAM WTMASS = {wt.values[0] if wt.values else None} must be "
                       f"a number > 0 (the deck's mass input x WTMASS = its mass unit)")
    return v


def _shell_elements(model, name: str) -> list:
    quads = [e for e in model.elements.values() if e.type in ("CQUAD4", "CTRIA3")]
    if not quads:
        raise BdfError(f"{name}: no CQUAD4 or CTRIA3 element: nothing asekit can model")
    return quads


def _read_grids(deck: Deck, quads, tol: float | None) -> None:
    """GRID: every grid in basic coordinates (pyNastran resolves CP through CORD2R / CORD1R /
    CORD2C / CORD2S); CD must be basic (0); the plate's grids must lie in one plane z = z0.

    +------+-----+----+----+----+----+----+----+------+
    |  1   |  2  | 3  | 4  | 5  | 6  | 7  | 8  |  9   |
    +======+=====+====+====+====+====+====+====+======+
    | GRID | ID  | CP | X1 | X2 | X3 | CD | PS | SEID |
    +------+-----+----+----+----+----+----+----+------+

    PS (permanent single-point constraints) is read by :func:`_read_grid_ps`.
    """
    model = deck.model
    nids = np.array(sorted(model.nodes), dtype=np.int64)
    bad_cd = [int(n) for n in nids if model.nodes[n].cd not in (0, None)]
    if bad_cd:
        raise BdfError(f"GRIDs {bad_cd[:10]} have a displacement coordinate system CD != 0: "
                       f"asekit needs T3, R1, R2 along the basic z, x, y axes")
    xyz = np.array([model.nodes[n].get_position() for n in nids], float)
    deck.nids, deck.xyz = nids, xyz
    deck.index = {int(n): i for i, n in enumerate(nids)}
    _check_grid_ranges(deck)
    size = float(np.ptp(xyz[:, :2], axis=0).max())
    tol = 1e-6 * size if tol is None else float(tol)
    plate_nodes = sorted({n for e in quads for n in e.node_ids})
    deck.z0 = _plane(xyz[[deck.index[n] for n in plate_nodes]], tol)
    deck.nodes = xyz[:, :2] * deck.L


def _read_pshell(p, e) -> None:
    """PSHELL: checked for what asekit's plate represents (one material for membrane and
    bending, MID1 = MID2 or MID1 blank; 12I/T^3 = 1; no element offset ZOFFS).

    +--------+-------+------+--------+------+----------+------+------+---------+
    |   1    |   2   |  3   |   4    |  5   |    6     |  7   |  8   |    9    |
    +========+=======+======+========+======+==========+======+======+=========+
    | PSHELL |  PID  | MID1 |   T    | MID2 | 12I/T**3 | MID3 | TS/T |   NSM   |
    +--------+-------+------+--------+------+----------+------+------+---------+
    |        |  Z1   |  Z2  |  MID4  |      |          |      |      |         |
    +--------+-------+------+--------+------+----------+------+------+---------+

    NSM (non-structural mass per area) is applied by :func:`_plate_matrices`.
    """
    if p.type != "PSHELL":
        raise BdfError(f"{e.type} {e.eid}: property {p.type} {e.pid} is not supported "
                       f"(PSHELL only)")
    if p.mid2 is None:
        raise BdfError(f"PSHELL {p.pid}: MID2 is blank (no bending stiffness): asekit "
                       f"models plate bending")
    if p.mid1 is not None and p.mid1 != p.mid2:
        raise BdfError(f"PSHELL {p.pid}: MID1 = {p.mid1} differs from MID2 = {p.mid2}: "
                       f"asekit's plate takes one material for bending")
    if abs(float(p.twelveIt3 or 1.0) - 1.0) > 1e-9:
        raise BdfError(f"PSHELL {p.pid}: 12I/T^3 = {p.twelveIt3} is not supported (1.0)")
    if (e.zoffset or 0.0) != 0.0:
        raise BdfError(f"{e.type} {e.eid}: ZOFFS = {e.zoffset} is not supported")


def _check_shell_ranges(deck: Deck, quads, th, props) -> None:
    """PSHELL T (> 0) and NSM, and each element's corner thicknesses (deck units): all >= 0,
    the largest > 0 (an element of zero thickness has no stiffness), within :data:`RANGES`."""
    for p in props.values():
        if p.t is not None:
            _check_range(deck, f"PSHELL {p.pid} T", p.t, "thickness")
        _check_range(deck, f"PSHELL {p.pid} NSM", p.nsm or 0.0, "areal mass")
    bad = np.flatnonzero(~((th >= 0).all(axis=1) & (th.max(axis=1) > 0)
                           & (th.max(axis=1) * deck.L <= RANGES["thickness"][1])))
    if bad.size:
        e = quads[int(bad[0])]
        raise BdfError(f"{e.type} {e.eid}: corner thicknesses T1-T4 = "
                       f"{[float(v) for v in th[bad[0]]]} (with PSHELL {e.pid} T for blanks): "
                       f"each must be >= 0, the largest > 0 and <= "
                       f"{RANGES['thickness'][1] / deck.L:g} (10 m)")


def _check_element_shapes(deck: Deck, quads, conn) -> None:
    """Every element's Jacobian positive inside it (after :func:`_orient`): det J of the
    bilinear map is affine in r and s, so it is > 0 everywhere inside iff it is >= 0 at the
    four corners and > 0 at the centre (a CTRIA3, G3 repeated, has det J = 0 at that corner).
    A degenerate (collinear, coincident grids) or non-convex element is refused by id."""
    xy = deck.nodes[conn]
    tol = 1e-12 * max(float(np.ptp(deck.nodes, axis=0).max()), 1e-300) ** 2

    def det(r, s):
        _, dNr, dNs = shape_functions(r, s)
        J = np.stack([dNr @ xy, dNs @ xy], axis=1)
        return J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
    corners = np.min([det(r, s) for r, s in ((-1, -1), (1, -1), (1, 1), (-1, 1))], axis=0)
    bad = np.flatnonzero(~((corners >= -tol) & (det(0.0, 0.0) > tol)))
    if bad.size:
        e = quads[int(bad[0])]
        raise BdfError(f"{e.type} {e.eid} (grids {list(e.node_ids)}) is degenerate "
                       f"or not convex in the plate's plane (Jacobian <= 0): its grids must "
                       f"make a convex polygon of non-zero area")


def _shell_thickness(e, p, tri: bool) -> list[float]:
    """Corner thicknesses (deck units) of a CQUAD4 (T1-T4) or CTRIA3 (T1-T3, T3 repeated for
    the degenerated MITC4): blank or negative -> PSHELL T; TFLAG = 1 -> multiples of T.

    +--------+-------+-------+----+----+----+----+------------+-------+
    |   1    |   2   |   3   | 4  | 5  | 6  | 7  |     8      |   9   |
    +========+=======+=======+====+====+====+====+============+=======+
    | CQUAD4 |  EID  |  PID  | G1 | G2 | G3 | G4 | THETA/MCID | ZOFFS |
    +--------+-------+-------+----+----+----+----+------------+-------+
    |        |       | TFLAG | T1 | T2 | T3 | T4 |            |       |
    +--------+-------+-------+----+----+----+----+------------+-------+

    +--------+-------+-------+----+----+----+------------+-------+
    |   1    |   2   |   3   | 4  | 5  | 6  |     7      |   8   |
    +========+=======+=======+====+====+====+============+=======+
    | CTRIA3 |  EID  |  PID  | G1 | G2 | G3 | THETA/MCID | ZOFFS |
    +--------+-------+-------+----+----+----+------------+-------+
    |        |       | TFLAG | T1 | T2 | T3 |            |       |
    +--------+-------+-------+----+----+----+------------+-------+
    """
    t = [e.T1, e.T2, e.T3, e.T3] if tri else [e.T1, e.T2, e.T3, e.T4]
    if p.t is None and (getattr(e, "tflag", 0) == 1 or any(v is None or v < 0 for v in t)):
        raise BdfError(f"{e.type} {e.eid}: a corner thickness is blank and PSHELL {p.pid} T "
                       f"is blank too: give T")
    if getattr(e, "tflag", 0) == 1:
        t = [(v if v is not None else 1.0) * p.t for v in t]
    return [p.t if v is None or v < 0 else v for v in t]


def _element_angle(elem, xyz_of, g1, g2, model) -> float:
    """Material 1-axis angle from +x (rad) of a CQUAD4 / CTRIA3: THETA (deg) from the G1-G2
    edge, or the projection of the MCID system's x axis."""
    tm = elem.theta_mcid
    d = xyz_of(g2) - xyz_of(g1)
    edge = math.atan2(d[1], d[0])
    if isinstance(tm, int):
        ax = np.asarray(model.coords[tm].i, float)
        return math.atan2(ax[1], ax[0])
    return edge + math.radians(float(tm or 0.0))


def _orient(deck: Deck, conn, th, is_tri) -> None:
    """Renumber (in place) the elements numbered clockwise seen from +z: a quadrilateral
    reversed, a triangle G1 G3 G2 (G2 repeated)."""
    xy = deck.nodes[conn]
    area2 = ((xy[:, 2, 0] - xy[:, 0, 0]) * (xy[:, 3, 1] - xy[:, 1, 1])
             - (xy[:, 3, 0] - xy[:, 1, 0]) * (xy[:, 2, 1] - xy[:, 0, 1]))
    flip = area2 < 0
    fq, ft = flip & ~is_tri, flip & is_tri
    conn[fq] = conn[fq][:, ::-1]
    th[fq] = th[fq][:, ::-1]
    conn[ft] = conn[ft][:, [0, 2, 1, 1]]
    th[ft] = th[ft][:, [0, 2, 1, 1]]
    if flip.any():
        deck.notes.append(f"{int(flip.sum())} elements numbered clockwise seen from +z were "
                          f"renumbered (same element)")


def _read_shells(deck: Deck, quads):
    """CQUAD4 / CTRIA3 (fields in :func:`_shell_thickness`) with their PSHELL: connectivity
    (a CTRIA3 as a degenerated MITC4, G1 G2 G3 G3), corner thicknesses (m), material angles
    (rad) and property ids; returns (conn, th, angles, pids, props)."""
    is_tri = np.array([e.type == "CTRIA3" for e in quads])
    conn = np.array([[deck.index[n] for n in (list(e.node_ids) + [e.node_ids[2]])[:4]]
                     for e in quads], dtype=np.int64)
    th = np.zeros((len(quads), 4))
    angles = np.zeros(len(quads))
    props = {}
    for j, e in enumerate(quads):
        p = deck.model.properties[e.pid]
        _read_pshell(p, e)
        props[e.pid] = p
        th[j] = _shell_thickness(e, p, bool(is_tri[j]))
        angles[j] = _element_angle(e, lambda g: deck.xyz[deck.index[g]], e.node_ids[0],
                                   e.node_ids[1], deck.model)
    _check_shell_ranges(deck, quads, th, props)
    _orient(deck, conn, th, is_tri)
    _check_element_shapes(deck, quads, conn)
    if is_tri.any():
        deck.notes.append(f"{int(is_tri.sum())} CTRIA3 modelled as degenerated MITC4 (G3 "
                          f"repeated; Bathe, Finite Element Procedures, 1996, Ch. 5: collapsed "
                          f"quadrilaterals; less accurate than the quadrilateral)")
    if any(p.mid3 is None for p in props.values()):
        deck.notes.append("PSHELL MID3 blank (Nastran: no transverse shear flexibility, "
                          "Kirchhoff plate); asekit's plate is Reissner-Mindlin with G from the "
                          "material -- negligible for a thin plate")
    return conn, th * deck.L, angles, np.array([e.pid for e in quads]), props


def _read_mat1(mat, deck: Deck, pid: int) -> Material:
    """MAT1 in SI (stress F / L^2, density m / L^3, x WTMASS): two of E, G, NU (all three only
    if consistent).

    +------+-----+---+---+----+-----+---+------+----+
    |  1   |  2  | 3 | 4 | 5  |  6  | 7 |  8   | 9  |
    +======+=====+===+===+====+=====+===+======+====+
    | MAT1 | MID | E | G | NU | RHO | A | TREF | GE |
    +------+-----+---+---+----+-----+---+------+----+
    """
    _check_mat1_fields((mat.type, mat.mid, mat.e, mat.g, mat.nu))   # after pyNastran's fill
    E, G, nu = mat.e, mat.g, mat.nu
    if abs(G - E / (2 * (1 + nu))) > 1e-3 * G:
        raise BdfError(f"MAT1 {mat.mid}: E, G and NU all given and G = {G:g} differs from "
                       f"E / (2 (1 + NU)) = {E / (2 * (1 + nu)):g}: asekit's isotropic "
                       f"material takes E and NU (give two of the three)")
    what = f"MAT1 {mat.mid} (PSHELL {pid})"
    E_si = _check_range(deck, f"{what} E", E, "modulus")
    _check_range(deck, f"{what} G", G, "modulus")
    return Material(E_si, nu,
                    _check_range(deck, f"{what} RHO", mat.rho or 0.0, "density"),
                    name=f"MAT1 {mat.mid}")


def _read_mat8(mat, deck: Deck, angle: float) -> OrthotropicMaterial:
    """MAT8 in SI at the element's material angle (rad); G1Z / G2Z blank -> G12.

    +------+-----+-----+------+------+-----+-----+-----+-----+
    |  1   |  2  |  3  |  4   |  5   |  6  |  7  |  8  |  9  |
    +======+=====+=====+======+======+=====+=====+=====+=====+
    | MAT8 | MID | E1  |  E2  | NU12 | G12 | G1Z | G2Z | RHO |
    +------+-----+-----+------+------+-----+-----+-----+-----+
    """
    what = f"MAT8 {mat.mid}"
    g1z = mat.g1z if mat.g1z else mat.g12
    g2z = mat.g2z if mat.g2z else mat.g12
    mod = {n: _check_range(deck, f"{what} {n}", v, "modulus")
           for n, v in (("E1", mat.e11), ("E2", mat.e22), ("G12", mat.g12), ("G1Z", g1z),
                        ("G2Z", g2z))}
    nu12 = float(mat.nu12 or 0.0)
    if not abs(nu12) < math.sqrt(mod["E1"] / mod["E2"]):
        raise BdfError(f"{what}: NU12 = {nu12:g} is outside |NU12| < sqrt(E1 / E2) = "
                       f"{math.sqrt(mod['E1'] / mod['E2']):g} (a positive definite lamina)")
    return OrthotropicMaterial(mod["E1"], mod["E2"], mod["G12"], nu12,
                               _check_range(deck, f"{what} RHO", mat.rho or 0.0, "density"),
                               mod["G1Z"], mod["G2Z"], angle, name=f"MAT8 {mat.mid}")


def _material(deck: Deck, mat, angle: float, pid: int):
    """asekit material of a MAT1 / MAT8 (SI)."""
    if mat.type == "MAT1":
        return _read_mat1(mat, deck, pid)
    if mat.type == "MAT8":
        return _read_mat8(mat, deck, angle)
    raise BdfError(f"PSHELL {pid}: material {mat.type} {mat.mid} is not supported "
                   f"(MAT1 or MAT8)")


def _material_groups(deck: Deck, pids, props, angles) -> dict:
    """{(pid, material angle rad, 0 for MAT1): element indices}."""
    keys = {}
    for j, pid in enumerate(pids):
        mat = deck.model.materials[props[pid].mid2]
        ang = round(float(angles[j]), 9) if mat.type == "MAT8" else 0.0
        keys.setdefault((int(pid), ang), []).append(j)
    return keys


def _nsm_mass(sub: PlateMesh, nsm: float) -> np.ndarray:
    """Element mass matrices of a non-structural mass ``nsm`` (kg/m^2): translational only
    (Nastran's NSM), the consistent plate mass of unit density rescaled from rho h to nsm."""
    me = consistent_mass(sub, Material(1.0, 0.3, 1.0))
    h = sub.corner_thickness.mean(axis=1)
    for r in (1, 2):
        me[:, r::3, :] = 0.0
        me[:, :, r::3] = 0.0
    return me * (nsm / h)[:, None, None]


def _read_param_coupmass(model) -> bool:
    """PARAM COUPMASS: True (coupled, i.e. consistent, mass) if its value is > 0; Nastran's
    default (absent, or <= 0) is the lumped mass (MSC Nastran Quick Reference Guide, PARAM
    COUPMASS: "-1 (default) ... lumped mass").

    +-------+----------+--------+
    |   1   |    2     |   3    |
    +=======+==========+========+
    | PARAM | COUPMASS | value  |
    +-------+----------+--------+
    """
    cm = model.params.get("COUPMASS")
    if cm is None:
        return False
    v = _number(cm.values[0] if cm.values else None)
    if v is None or not math.isfinite(v):
        raise BdfError(f"PARAM COUPMASS = {cm.values[0] if cm.values else None} must be an "
                       f"integer (> 0 coupled mass, <= 0 lumped mass)")
    return v > 0


def lumped_translational_mass(me: np.ndarray) -> np.ndarray:
    """Nastran's lumped plate mass from consistent element mass matrices: each corner's
    translational mass is the row sum of the consistent w-w block (int N_i rho h dA, the
    quarter of the element's mass on a parallelogram), placed on the diagonal; no rotary
    inertia (MSC Nastran's CQUAD4 lumped mass, PARAM COUPMASS -1, the default).

    Parameters
    ----------
    me : ndarray (n_elem, 12, 12)
        Consistent element mass matrices, DOFs (w, theta_x, theta_y) per corner (kg, kg m,
        kg m^2).

    Returns
    -------
    ndarray (n_elem, 12, 12)
        Diagonal lumped mass matrices: the element's translational mass kept exactly.

    Examples
    --------
    >>> import numpy as np
    >>> me = np.zeros((1, 12, 12)); me[0, 0::3, 0::3] = [[4, 2, 1, 2], [2, 4, 2, 1],
    ...                                                  [1, 2, 4, 2], [2, 1, 2, 4]]
    >>> np.diag(lumped_translational_mass(me)[0])[0::3].tolist()
    [9.0, 9.0, 9.0, 9.0]
    """
    out = np.zeros_like(me)
    idx = np.arange(0, me.shape[1], 3)
    out[:, idx, idx] = me[:, idx[:, None], idx[None, :]].sum(axis=2)
    return out


def _plate_matrices(deck: Deck, conn, th, pids, props, angles, thickness_rule):
    """Global K and M (SI) of the plate elements, grouped by property and material angle:
    MITC4 stiffness and consistent mass (:mod:`asekit.structure.plate`) plus the PSHELL NSM,
    lumped (:func:`lumped_translational_mass`) unless PARAM COUPMASS > 0, as Nastran.
    Returns (K, M, materials {(pid, angle): material}, groups, mesh)."""
    nodes, n = deck.nodes, deck.n_dof
    coupled = _read_param_coupmass(deck.model)
    K = sp.csr_matrix((n, n))
    M = sp.csr_matrix((n, n))
    span = max(float(np.ptp(nodes[:, 1])), 1e-12)
    keys = _material_groups(deck, pids, props, angles)
    materials = {}
    for (pid, ang), idx in keys.items():
        p = props[pid]
        material = _material(deck, deck.model.materials[p.mid2], ang, pid)
        materials[(pid, ang)] = material
        idx = np.asarray(idx)
        sub = PlateMesh(nodes=nodes, elements=conn[idx], thickness_root=1.0, thickness_tip=1.0,
                        y_root=float(nodes[:, 1].min()), span=span, corner_thickness=th[idx])
        K = K + _scatter(sub, mitc4_stiffness(sub, material, thickness_rule), n)
        me = consistent_mass(sub, material, thickness_rule)
        nsm = float(p.nsm or 0.0) * deck.wtmass * deck.Mu / deck.L**2
        if nsm:
            me = me + _nsm_mass(sub, nsm)
        M = M + _scatter(sub, me if coupled else lumped_translational_mass(me), n)
    mesh = PlateMesh(nodes=nodes, elements=conn, thickness_root=float(th.max()),
                     thickness_tip=float(th.max()), y_root=float(nodes[:, 1].min()), span=span,
                     corner_thickness=th)
    return K, M, materials, keys, mesh


def _celas_dofs(deck: Deck, e):
    """(dof a, dof b) of a CELAS1 / CELAS2 (None: ground or an in-plane component) and
    whether any end is on an in-plane component."""
    dofs, dropped = [], False
    for nid, c in zip(e.node_ids, (e.c1, e.c2)):
        comp = [] if nid in (None, 0) or c in (None, 0) else _components(c)
        dropped |= nid not in (None, 0) and c not in (None, 0) and not comp
        dofs.append(deck.dof(nid, comp[0]) if comp else None)
    rot = [c in (4, 5) for c in (e.c1, e.c2)]
    if rot[0] != rot[1] and all(d is not None for d in dofs):
        raise BdfError(f"CELAS {e.eid} couples a translation and a rotation: not supported")
    return dofs, any(rot), dropped


def _read_celas(deck: Deck):
    """CELAS1 (with PELAS K) and CELAS2 springs to ground or between two grids, in SI (force
    per length, or moment per radian on R1 / R2); springs on in-plane components are dropped.

    +--------+-----+-----+----+----+----+----+
    |   1    |  2  |  3  | 4  | 5  | 6  | 7  |
    +========+=====+=====+====+====+====+====+
    | CELAS1 | EID | PID | G1 | C1 | G2 | C2 |
    +--------+-----+-----+----+----+----+----+
    | CELAS2 | EID |  K  | G1 | C1 | G2 | C2 |
    +--------+-----+-----+----+----+----+----+
    | PELAS  | PID |  K  | GE | S  |    |    |
    +--------+-----+-----+----+----+----+----+

    Returns (springs: (dof a, dof b or -1 for ground, k), global spring stiffness K_s).
    """
    n = deck.n_dof
    Kx = sp.lil_matrix((n, n))
    springs, dropped = [], []
    for e in deck.model.elements.values():
        if e.type not in ("CELAS1", "CELAS2"):
            continue
        k = float(e.k if e.type == "CELAS2" else deck.model.properties[e.pid].k)
        (a, b), rot, lost = _celas_dofs(deck, e)
        if lost:
            dropped.append(e.eid)
        k_deck = k
        k *= deck.Mu * deck.L**2 / deck.T**2 if rot else deck.Mu / deck.T**2
        _check_range(deck, f"{e.type} {e.eid} K" if e.type == "CELAS2" else
                     f"PELAS {e.pid} K (CELAS1 {e.eid})", k_deck, "spring", si=k)
        if a is None:
            a, b = b, None
        if a is None:
            continue
        springs.append((int(a), -1 if b is None else int(b), float(k)))
        Kx[a, a] += k
        if b is not None:
            Kx[b, b] += k
            Kx[a, b] -= k
            Kx[b, a] -= k
    if dropped:
        more = "..." if len(dropped) > 5 else ""
        deck.notes.append(f"CELAS {dropped[:5]}{more} on in-plane DOFs (1, 2, 6) ignored: "
                          f"uncoupled from bending")
    return tuple(springs), Kx.tocsr()


def _read_conm2(deck: Deck):
    """CONM2 point masses in SI (x WTMASS) with their offset X (rigid: w_m = w + theta_x dy -
    theta_y dx) and inertias I11, I21, I22 (about the offset point); CID basic only.

    +-------+-----+-----+-----+-----+-----+-----+-----+-----+
    |   1   |  2  |  3  |  4  |  5  |  6  |  7  |  8  |  9  |
    +=======+=====+=====+=====+=====+=====+=====+=====+=====+
    | CONM2 | EID |  G  | CID |  M  | X1  | X2  | X3  |     |
    +-------+-----+-----+-----+-----+-----+-----+-----+-----+
    |       | I11 | I21 | I22 | I31 | I32 | I33 |     |     |
    +-------+-----+-----+-----+-----+-----+-----+-----+-----+

    Returns (masses: (node index, mass, offset (3,) m, (I11, I21, I22)), global mass M_m).
    """
    n = deck.n_dof
    Mx = sp.lil_matrix((n, n))
    masses = []
    for m in deck.model.masses.values():
        if m.type != "CONM2":
            continue
        if m.cid not in (0, -1, None):
            raise BdfError(f"CONM2 {m.eid}: CID = {m.cid} is not supported (basic only)")
        i = deck.index[m.nid]
        mass, X, I = _conm2_values(deck, m)
        masses.append((i, mass, X.copy(), (float(I[0]), float(I[1]), float(I[2]))))
        d = DOF_PER_NODE * i
        r = np.array([1.0, X[1], -X[0]])
        Mx[d:d + 3, d:d + 3] += mass * np.outer(r, r)
        Mx[d + 1, d + 1] += I[0] + mass * X[2] ** 2
        Mx[d + 2, d + 2] += I[2] + mass * X[2] ** 2
        Mx[d + 1, d + 2] -= I[1]
        Mx[d + 2, d + 1] -= I[1]
    return tuple(masses), Mx.tocsr()


def _conm2_values(deck: Deck, m):
    """(mass kg, offset (3,) m, (I11, I21, I22, ...) kg m^2) of a CONM2, checked: mass and
    offsets within :data:`RANGES`, I11, I22 >= 0 and I21^2 <= I11 I22."""
    what = f"CONM2 {m.eid}"
    mass = _check_range(deck, f"{what} M", float(m.mass or 0.0), "mass")
    X = np.asarray(m.X if m.X is not None else np.zeros(3), float)
    for j, x in enumerate(X):
        _check_range(deck, f"{what} X{j + 1}", x, "coordinate")
    I = np.asarray(m.I, float) * deck.wtmass * deck.Mu * deck.L**2
    for j, n in ((0, "I11"), (2, "I22")):
        _check_range(deck, f"{what} {n}", I[j], "inertia", si=I[j])
    if not I[1] ** 2 <= I[0] * I[2] * (1 + 1e-12):
        raise BdfError(f"{what}: I21^2 > I11 I22 (I11, I21, I22 = "
                       f"{list(map(float, np.asarray(m.I)[:3]))}): not a positive inertia")
    return mass, X * deck.L, I


def _read_grid_ps(deck: Deck) -> set:
    """GRID PS (permanent single-point constraints, field 8 of GRID, :func:`_read_grids`):
    the constrained global DOFs (components 3, 4, 5; 1, 2, 6 are in-plane)."""
    return {deck.dof(nid, c) for nid, g in deck.model.nodes.items() for c in _components(g.ps)}


def _spc_set_ids(deck: Deck) -> list:
    """The SPC sets applied: the case control's SPC = n, else all (with a note if several)."""
    model = deck.model
    ids = sorted(model.spcs)
    cc = case_value(model, "SPC")
    if cc is not None and cc in model.spcs:
        return [cc]
    adds = (getattr(model, "spcadds", {}) or {}).get(cc) if cc is not None else None
    if adds:
        adds = adds if isinstance(adds, list) else [adds]
        return [s for a in adds for s in getattr(a, "spc_ids", a.sets) if s in model.spcs]
    if cc is not None:
        deck.missing.append(f"the case control's SPC = {cc} is not a set of the deck "
                            f"(SPC sets: {ids or 'none'})")
        return []
    if len(ids) > 1:
        deck.notes.append(f"several SPC sets {ids} and no SPC = in the case control: all "
                          f"applied")
    return ids


def _read_spc_card(deck: Deck, sid: int, c) -> set:
    """The DOFs an SPC1 or SPC card fixes (zero enforced displacement only).

    +------+-----+----+----+------+----+----+----+
    |  1   |  2  | 3  | 4  |  5   | 6  | 7  | 8  |
    +======+=====+====+====+======+====+====+====+
    | SPC1 | SID | C  | G1 |  G2  | G3 | G4 | G5 |
    +------+-----+----+----+------+----+----+----+
    | SPC  | SID | G1 | C1 |  D1  | G2 | C2 | D2 |
    +------+-----+----+----+------+----+----+----+
    """
    if any(nid in (None, 0) for nid in c.node_ids):
        raise BdfError(f"{c.type} {sid}: a grid id is 0 or blank "
                       f"(grids {list(c.node_ids)[:10]}): each G must be a GRID id > 0")
    if c.type == "SPC1":
        return {deck.dof(nid, k) for nid in c.node_ids for k in _components(c.components)}
    if c.type != "SPC":
        raise BdfError(f"{c.type} {sid} is not supported (SPC, SPC1)")
    out = set()
    for nid, comp, val in zip(c.node_ids, c.components, c.enforced):
        if val:
            raise BdfError(f"SPC {sid}: enforced displacement {val} is not supported")
        out |= {deck.dof(nid, k) for k in _components(comp)}
    return out


def _read_spcs(deck: Deck) -> set:
    """Every DOF fixed by GRID PS and the applied SPC / SPC1 sets."""
    fixed = _read_grid_ps(deck)
    for sid in _spc_set_ids(deck):
        for c in deck.model.spcs[sid]:
            fixed |= _read_spc_card(deck, sid, c)
    return fixed


def _read_rbe2(deck: Deck, fixed: set):
    """RBE2 rigid links: the dependent grids' components CM (3, 4, 5) follow the independent
    grid GN rigidly (w_j = w_i + theta_x,i dy - theta_y,i dx). No chains, no dependent DOF
    that is also constrained.

    +------+-----+-----+-----+------+-------+-----+-----+-----+
    |  1   |  2  |  3  |  4  |  5   |   6   |  7  |  8  |  9  |
    +======+=====+=====+=====+======+=======+=====+=====+=====+
    | RBE2 | EID | GN  | CM  | GM1  |  GM2  | GM3 | GM4 | GM5 |
    +------+-----+-----+-----+------+-------+-----+-----+-----+

    Returns (dep {dependent DOF: {independent DOF: coefficient}}, rigid: (independent node,
    component string, dependent nodes) per RBE2).
    """
    dep, rigid = {}, []
    for r in deck.model.rigid_elements.values():
        if r.type != "RBE2":
            raise BdfError(f"{r.type} {r.eid} is not supported (RBE2 only)")
        gi = deck.index[r.gn]
        comps = _components(r.cm)
        rigid.append((gi, "".join(str(k + 3) for k in comps),
                      tuple(deck.index[g] for g in r.Gmi_node_ids)))
        for gm in r.Gmi_node_ids:
            j = deck.index[gm]
            dx, dy = deck.nodes[j] - deck.nodes[gi]
            rows = {0: {0: 1.0, 1: dy, 2: -dx}, 1: {1: 1.0}, 2: {2: 1.0}}
            for k in comps:
                dep[DOF_PER_NODE * j + k] = {DOF_PER_NODE * gi + a: v
                                             for a, v in rows[k].items() if v != 0.0}
    for d, comb in dep.items():
        if any(c in dep for c in comb):
            raise BdfError("RBE2 chains (a dependent grid of one RBE2 as the independent grid "
                           "of another) are not supported")
        if d in fixed:
            raise BdfError(f"grid {deck.nids[d // 3]} is both constrained (SPC) and an RBE2 "
                           f"dependent grid (Nastran: a fatal error)")
    return dep, tuple(rigid)


def _reduction(n: int, fixed: set, dep: dict, K, M) -> sp.csr_matrix:
    """The support reduction u = T q: the fixed and RBE2-dependent DOFs eliminated, and the
    DOFs without stiffness and mass (grids only in-plane, unattached) removed as well."""
    free = [d for d in range(n) if d not in fixed and d not in dep]
    col = {d: i for i, d in enumerate(free)}
    rows, cols, vals = list(free), list(range(len(free))), [1.0] * len(free)
    for d, comb in dep.items():
        for c, v in comb.items():
            if c in col:
                rows.append(d), cols.append(col[c]), vals.append(v)
    Tm = sp.csr_matrix((vals, (rows, cols)), shape=(n, len(free)))
    Kr = (Tm.T @ K @ Tm).tocsr()
    Mr = (Tm.T @ M @ Tm).tocsr()
    empty = (np.abs(Kr).sum(axis=1).A1 == 0) & (np.abs(Mr).sum(axis=1).A1 == 0)
    return Tm[:, np.flatnonzero(~empty)].tocsr() if empty.any() else Tm


def _read_eigen_method(model, deck: Deck):
    """EIGRL (or EIGR) of the case control's METHOD (else the first): (ND number of modes or
    None, V2 / F2 upper frequency Hz or None).

    +-------+-----+----+----+----+-------+-------+-----+
    |   1   |  2  | 3  | 4  | 5  |   6   |   7   |  8  |
    +=======+=====+====+====+====+=======+=======+=====+
    | EIGRL | SID | V1 | V2 | ND | MSGLVL| MAXSET|SHFSC|
    +-------+-----+----+----+----+-------+-------+-----+
    | EIGR  | SID |METH| F1 | F2 |  NE   |  ND   |     |
    +-------+-----+----+----+----+-------+-------+-----+
    """
    methods = model.methods
    if not methods:
        return None, None
    meth = case_value(model, "METHOD")
    mth = methods.get(meth) if meth in methods else methods[min(methods)]
    nd = getattr(mth, "nd", None)
    v2 = getattr(mth, "v2", None) if mth.type == "EIGRL" else getattr(mth, "f2", None)
    if nd is not None and not 1 <= nd <= 100000:
        raise BdfError(f"{mth.type} {mth.sid} ND = {nd} must be an integer "
                       f"1 <= ND <= 100000 (the number of modes)")
    if v2 is not None:
        _check_range(deck, f"{mth.type} {mth.sid} {'V2' if mth.type == 'EIGRL' else 'F2'}",
                     v2, "frequency")
    return (int(nd) if nd else None), (float(v2) / deck.T if v2 else None)


def _eigen_card(model) -> str:
    """'EIGRL 10' / 'EIGR 10': the card :func:`_read_eigen_method` reads, '' without one."""
    methods = model.methods
    if not methods:
        return ""
    meth = case_value(model, "METHOD")
    mth = methods.get(meth) if meth in methods else methods[min(methods)]
    return f"{mth.type} {mth.sid}"


def _read_tabdmp1(model, deck: Deck):
    """TABDMP1 (the first): modal damping vs frequency as ((f Hz, g), ...); TYPE G as given,
    CRIT (fraction of critical) as g = 2 zeta.

    +---------+-----+------+----+----+----+----+----+----+
    |    1    |  2  |  3   | 4  | 5  | 6  | 7  | 8  | 9  |
    +=========+=====+======+====+====+====+====+====+====+
    | TABDMP1 | TID | TYPE |    |    |    |    |    |    |
    +---------+-----+------+----+----+----+----+----+----+
    |         | f1  |  g1  | f2 | g2 | f3 | g3 |... |ENDT|
    +---------+-----+------+----+----+----+----+----+----+
    """
    tables = getattr(model, "tables_sdamping", None)
    if not tables:
        return None
    tab = tables[min(tables)]
    if tab.Type not in ("G", "CRIT"):
        raise BdfError(f"TABDMP1 {tab.tid}: TYPE {tab.Type} is not supported (G, CRIT)")
    for j, (f, v) in enumerate(zip(tab.x, tab.y)):
        _check_range(deck, f"TABDMP1 {tab.tid} f{j + 1}", f, "frequency")
        _check_range(deck, f"TABDMP1 {tab.tid} {tab.Type.lower()}{j + 1}", v, "damping")
    g = np.asarray(tab.y, float) * (2.0 if tab.Type == "CRIT" else 1.0)
    return tuple((float(f) / deck.T, float(v)) for f, v in zip(tab.x, g))


def _check_acsid(model, card: str, aero, rotated: bool = False) -> None:
    """AERO / AEROS ACSID: the aerodynamic system's x axis is the flow direction (MSC QRG,
    AERO). It must be rectangular (CORD1R / CORD2R). A plate deck's CAERO1 boxes take the flow
    along basic +X and the normal along basic Z, so there (``rotated`` False) an ACSID whose
    axes are not basic's (e.g. flow along -X) is refused, not misread; a stick deck builds its
    boxes in the ACSID's axes (:func:`aero_axes`, ``rotated`` True)."""
    acsid = int(getattr(aero, "acsid", 0) or 0)
    if acsid == 0:
        return
    coord = model.coords.get(acsid)
    if coord is None or coord.type not in ("CORD1R", "CORD2R"):
        kind = "undefined" if coord is None else coord.type
        raise BdfError(f"{card} ACSID = {acsid}: a {kind} system; the aerodynamic system must "
                       f"be rectangular (CORD1R / CORD2R)")
    axes = np.asarray(coord.beta(), float)
    if not rotated and not np.allclose(axes, np.eye(3), atol=1e-9):
        raise BdfError(f"{card} ACSID = {acsid}: its x axis (the flow) is "
                       f"{tuple(np.round(axes[0], 6).tolist())} and z axis "
                       f"{tuple(np.round(axes[2], 6).tolist())} in basic; asekit takes the flow "
                       f"along basic +X and z up in a plate (CQUAD4) deck (ACSID 0 or a system "
                       f"with basic's axes; a CBAR stick deck may rotate it)")


def aero_axes(model) -> np.ndarray:
    """The axes of AERO / AEROS ACSID in basic (rows: the flow direction x, y, the normal z).

    MSC Nastran Quick Reference Guide, AERO / AEROS field ACSID: the aerodynamic coordinate
    system, whose x axis is the flow; CAERO1 chords X12, X43 lie along it. A point of basic
    coordinates p has aerodynamic (rotated, same origin) coordinates R p, R this matrix.

    Parameters
    ----------
    model : pyNastran ``BDF``, cross-referenced.

    Returns
    -------
    R : (3, 3) orthonormal, identity for ACSID 0 or no AERO / AEROS card.

    Examples
    --------
    >>> from types import SimpleNamespace as NS
    >>> aero_axes(NS(aero=NS(acsid=0), aeros=None)).tolist()[0]
    [1.0, 0.0, 0.0]
    """
    aero = model.aero or model.aeros
    acsid = int(getattr(aero, "acsid", 0) or 0) if aero is not None else 0
    if acsid == 0:
        return np.eye(3)
    _check_acsid(model, "AERO" if model.aero is not None else "AEROS", aero, rotated=True)
    return np.asarray(model.coords[acsid].beta(), float)


def read_aero_card(deck: Deck, rotated_acsid: bool = False):
    """AERO / AEROS: the reference semichord, reference density and symmetry (public reader
    API); SYMXY (ground effect) and a non-rectangular ACSID refused, and an ACSID whose axes
    are not basic's unless ``rotated_acsid`` (the caller then builds its boxes in
    :func:`aero_axes`).

    Parameters
    ----------
    deck : :class:`Deck`
    rotated_acsid : bool, accept a rectangular ACSID whose axes are not basic's.

    Returns
    -------
    b_ref : float, REFC / 2 (m).
    rho_ref : float or None, AERO RHOREF (kg/m^3); None for AEROS.
    symmetric : bool, SYMXZ = 1.

    Raises
    ------
    BdfError
        No AERO / AEROS, SYMXY != 0, a rotated ACSID, or a field out of :data:`RANGES`.

    Card fields (MSC Quick Reference Guide)::

        +-------+-------+-------+--------+--------+-------+-------+-------+
        |   1   |   2   |   3   |   4    |   5    |   6   |   7   |   8   |
        +=======+=======+=======+========+========+=======+=======+=======+
        | AERO  | ACSID | VELO  |  REFC  | RHOREF | SYMXZ | SYMXY |       |
        +-------+-------+-------+--------+--------+-------+-------+-------+
        | AEROS | ACSID | RCSID |  REFC  |  REFB  | REFS  | SYMXZ | SYMXY |
        +-------+-------+-------+--------+--------+-------+-------+-------+
    """
    model = deck.model
    aero = model.aero or model.aeros
    if aero is None:
        raise BdfError("CAERO1 without AERO / AEROS: the reference chord is unknown")
    if int(getattr(aero, "sym_xy", 0) or 0) != 0:
        raise BdfError("SYMXY (ground effect) is not supported")
    card = "AERO" if model.aero is not None else "AEROS"
    _check_acsid(model, card, aero, rotated_acsid)
    rho_ref = (_check_range(deck, "AERO RHOREF", model.aero.rho_ref, "fluid density")
               if model.aero is not None else None)
    refc = _check_range(deck, f"{card} REFC", aero.cref, "length")
    return 0.5 * refc, rho_ref, int(aero.sym_xz or 0) == 1


def read_mkaero1(model, deck=None):
    """MKAERO1: the Mach numbers and reduced frequencies of the GAF database (all pairs of
    all cards; subsonic only, asekit's doublet lattice). Public reader API.

    Parameters
    ----------
    model : pyNastran ``BDF`` (its ``mkaeros``).
    deck : :class:`Deck` or None, when given each k is checked against :data:`RANGES`.

    Returns
    -------
    machs, ks : tuples of the sorted distinct Mach numbers and reduced frequencies (b_ref).

    Raises
    ------
    BdfError
        MKAERO2, a Mach outside the doublet lattice's range, or k out of range.

    Examples
    --------
    >>> from types import SimpleNamespace as NS
    >>> mk = NS(type="MKAERO1", machs=[0.5, 0.0], reduced_freqs=[0.1, 0.01])
    >>> read_mkaero1(NS(mkaeros=[mk]))
    ((0.0, 0.5), (0.01, 0.1))

    +---------+----+----+----+----+----+----+----+----+
    |    1    | 2  | 3  | 4  | 5  | 6  | 7  | 8  | 9  |
    +=========+====+====+====+====+====+====+====+====+
    | MKAERO1 | m1 | m2 | m3 | m4 | m5 | m6 | m7 | m8 |
    +---------+----+----+----+----+----+----+----+----+
    |         | k1 | k2 | k3 | k4 | k5 | k6 | k7 | k8 |
    +---------+----+----+----+----+----+----+----+----+
    """
    pairs = []
    for mk in model.mkaeros:
        if mk.type != "MKAERO1":
            raise BdfError(f"{mk.type} is not supported (MKAERO1)")
        pairs += [(float(m), float(k)) for m in mk.machs for k in mk.reduced_freqs]
    for k in sorted({p[1] for p in pairs}):
        if deck is not None:
            _check_range(deck, "MKAERO1 k", k, "reduced frequency")
    machs = tuple(sorted({p[0] for p in pairs}))
    for m in machs:                 # the deck's CAERO1 boxes are run with the doublet lattice
        try:
            check_mach(m, "dlm", "MKAERO1 Mach")
        except ValueError as exc:
            raise BdfError(str(exc)) from None
    return machs, tuple(sorted({p[1] for p in pairs}))


def _read_aero(deck: Deck) -> dict:
    """The aerodynamic part (CAERO1 boxes, splines checked, AERO, MKAERO1, FLUTTER): the
    keyword arguments of :class:`BdfModel` it sets (empty without CAERO1)."""
    model = deck.model
    if not model.caeros:
        if model.flutters:
            raise BdfError("FLUTTER without CAERO1 boxes")
        return {}
    for c in model.caeros.values():
        check_caero1(deck, c)
    boxes, box_ids = deck_boxes(model, deck.L, deck.z0 * deck.L)
    _check_splines(model, box_ids, deck.notes)
    b_ref, rho_ref, symmetric = read_aero_card(deck)
    machs, ks = read_mkaero1(model, deck)
    flut = [read_flutter(model, f, rho_ref, deck)
            for f in model.flutters.values()]
    fm = case_value(model, "FMETHOD")
    flut.sort(key=lambda r: r.sid != fm)          # the case control's FMETHOD first
    return {"boxes": boxes, "box_ids": box_ids, "b_ref": b_ref, "rho_ref": rho_ref,
            "symmetric": symmetric, "machs": machs, "reduced_frequencies": ks,
            "flutter": tuple(flut)}


def case_value(model, key: str):
    """The integer value of a case-control entry in the first subcase (public reader API).

    Parameters
    ----------
    model : pyNastran ``BDF`` (its ``case_control_deck``).
    key : str, e.g. ``"SPC"``, ``"METHOD"``, ``"FMETHOD"``.

    Returns
    -------
    int or None
        The value in subcase 1 (or the global subcase 0); None without a case control, without
        the entry, or when its value is not an integer.

    Examples
    --------
    >>> from types import SimpleNamespace as NS
    >>> case_value(NS(case_control_deck=None), "SPC") is None
    True
    """
    cc = getattr(model, "case_control_deck", None)
    if cc is None:
        return None
    for sc in [cc.subcases.get(1), cc.subcases.get(0)]:
        if sc is not None and sc.has_parameter(key):
            try:
                return int(sc.get_parameter(key)[0])
            except (TypeError, ValueError, KeyError):
                return None
    return None


def _divisions(caero, n, aefact, name):
    """Box division fractions 0..1 of a CAERO1 side: N uniform boxes, or an AEFACT list.

    +--------+-----+----+----+----+----+----+----+----+
    |   1    |  2  | 3  | 4  | 5  | 6  | 7  | 8  | 9  |
    +========+=====+====+====+====+====+====+====+====+
    | AEFACT | SID | D1 | D2 | D3 | D4 | D5 | D6 | D7 |
    +--------+-----+----+----+----+----+----+----+----+
    """
    if n:
        return np.linspace(0.0, 1.0, int(n) + 1)
    if aefact is None:
        raise BdfError(f"CAERO1 {caero.eid}: neither N{name} nor L{name} given")
    f = np.asarray(aefact.fractions, float)
    if f[0] != 0.0 or f[-1] != 1.0 or np.any(np.diff(f) <= 0):
        raise BdfError(f"AEFACT {aefact.sid} (CAERO1 {caero.eid} L{name}): fractions must "
                       f"rise from 0 to 1")
    return f


def _caero1_boxes(c, L, axes=None):
    """One CAERO1 (with PAERO1) as box corners (n, 4, 3) m and Nastran box ids, ordered
    spanwise from the root (the box ids run chordwise first from P1). With ``axes`` (the
    ACSID's, :func:`aero_axes`) the corners are in the aerodynamic system's axes (x the flow,
    chords along it); without, in basic (chords along basic x).

    +--------+-----+-----+----+-------+--------+--------+--------+------+
    |   1    |  2  |  3  | 4  |   5   |   6    |   7    |   8    |  9   |
    +========+=====+=====+====+=======+========+========+========+======+
    | CAERO1 | EID | PID | CP | NSPAN | NCHORD | LSPAN  | LCHORD | IGID |
    +--------+-----+-----+----+-------+--------+--------+--------+------+
    |        | X1  | Y1  | Z1 |  X12  |   X4   |   Y4   |   Z4   | X43  |
    +--------+-----+-----+----+-------+--------+--------+--------+------+
    """
    p1, _, _, p4 = (np.asarray(p, float) for p in c.get_points())
    if axes is not None:
        p1, p4 = axes @ p1, axes @ p4
    eta = _divisions(c, c.nspan, c.lspan_ref if c.lspan else None, "SPAN")
    xi = _divisions(c, c.nchord, c.lchord_ref if c.lchord else None, "CHORD")
    flip = p4[1] < p1[1]
    r, t = (p4, p1) if flip else (p1, p4)
    cr, ct = (c.x43, c.x12) if flip else (c.x12, c.x43)
    e = (1 - eta[::-1]) if flip else eta
    le = r[None, :] + e[:, None] * (t - r)[None, :]
    ch = cr + e * (ct - cr)
    grid = le[:, None, :] + xi[None, :, None] * ch[:, None, None] * np.array([1.0, 0, 0])
    ns, nc = len(eta) - 1, len(xi) - 1
    box = np.stack([grid[:-1, :-1], grid[:-1, 1:], grid[1:, 1:], grid[1:, :-1]],
                   axis=2).reshape(-1, 4, 3)
    bid = c.eid + np.arange(ns * nc).reshape(ns, nc)
    return box * L, (bid[::-1] if flip else bid).ravel(), ns, nc


#: The most boxes one CAERO1 may have (the doublet-lattice matrix of n boxes holds n^2
#: complex numbers per Mach and k: 10000 boxes are 1.6 GB).
MAX_BOXES_PER_CAERO1 = 10000


def check_caero1(deck: Deck, c) -> None:
    """Check one CAERO1 card before any box is built (public reader API): corners P1, P4 and
    chords X12, X43 within :data:`RANGES` (chords >= 0, one of them > 0), NSPAN x NCHORD <=
    :data:`MAX_BOXES_PER_CAERO1`. Other CAERO types pass (:func:`deck_boxes` refuses them).

    Parameters
    ----------
    deck : :class:`Deck`
    c : a pyNastran CAERO card.

    Raises
    ------
    BdfError
        Naming the card, its id and the field.
    """
    if c.type != "CAERO1":
        return
    for name, p in (("P1", c.p1), ("P4", c.p4)):
        for j, x in enumerate(np.asarray(p, float)):
            _check_range(deck, f"CAERO1 {c.eid} {name} X{j + 1}", x, "coordinate")
    for name, x in (("X12", c.x12), ("X43", c.x43)):
        if x != 0.0:
            _check_range(deck, f"CAERO1 {c.eid} {name}", x, "length")
    if not (c.x12 > 0 or c.x43 > 0):
        raise BdfError(f"CAERO1 {c.eid}: both chords X12 and X43 are zero")
    ns = c.nspan or (len(c.lspan_ref.fractions) - 1 if c.lspan else 1)
    nc = c.nchord or (len(c.lchord_ref.fractions) - 1 if c.lchord else 1)
    if ns * nc > MAX_BOXES_PER_CAERO1:
        raise BdfError(f"CAERO1 {c.eid}: NSPAN x NCHORD = {ns} x {nc} = "
                       f"{ns * nc} boxes, more than {MAX_BOXES_PER_CAERO1} (the doublet-lattice "
                       f"matrix would need {16 * (ns * nc) ** 2 / 2**30:.3g} GiB per Mach and k)")


def deck_boxes(model, L, z0):
    """Every CAERO1 of a deck as one :class:`BoxMesh` (public reader API).

    Parameters
    ----------
    model : pyNastran ``BDF``, cross-referenced (CAERO1 with PAERO1, AEFACT).
    L : float, one deck length unit in m.
    z0 : float, the structure's plane (m); every surface must lie in it (no dihedral).

    Returns
    -------
    mesh : :class:`BoxMesh`, in the structure's plane (z = 0 in asekit), spanwise from the
        root, one surface per CAERO1 in id order.
    box_ids : (n_boxes,) int, the Nastran box ids (EID + chordwise-first index).

    Raises
    ------
    BdfError
        A CAERO type other than CAERO1, or a surface off the plane.
    """
    def in_plane(cid, p1, p4):
        if abs(p1[2] - p4[2]) > 1e-9 * max(1.0, abs(p4[1] - p1[1])) \
                or abs(p1[2] * L - z0) > 1e-6 * max(1.0, abs(z0)):
            raise BdfError(f"CAERO1 {cid}: the surface must lie in the structure's plane "
                           f"z = {z0 / L:g} (no dihedral)")

    mesh, ids = _caero1_mesh(model, L, None, in_plane)
    c = mesh.corners.copy()
    c[:, :, 2] = 0.0                                 # the structural plane is z = 0 in asekit
    return replace(mesh, corners=c), ids


def _caero1_mesh(model, L, axes, check):
    """Every CAERO1 of a deck, in id order, as one :class:`BoxMesh` and its Nastran box ids:
    the corners in ``axes`` (:func:`_caero1_boxes`), ``check(cid, p1, p4)`` (P1 and P4 in
    those axes) raising :class:`BdfError` for a surface the caller cannot represent."""
    R = np.eye(3) if axes is None else axes
    corners, strip, surface, ids, names = [], [], [], [], []
    s0 = 0
    for i, cid in enumerate(sorted(model.caeros)):
        c = model.caeros[cid]
        if c.type != "CAERO1":
            raise BdfError(f"{c.type} {cid} is not supported (CAERO1)")
        p1, _, _, p4 = (R @ np.asarray(p, float) for p in c.get_points())
        check(cid, p1, p4)
        box, bid, ns, nc = _caero1_boxes(c, L, axes)
        corners.append(box)
        strip.append(s0 + np.repeat(np.arange(ns), nc))
        surface.append(np.full(ns * nc, i))
        ids.append(bid)
        names.append(f"CAERO1 {cid}")
        s0 += ns
    return BoxMesh(np.concatenate(corners), np.concatenate(strip), np.concatenate(surface),
                   tuple(names)), np.concatenate(ids)


def deck_boxes_aero(model, L):
    """Every CAERO1 of a deck as one :class:`BoxMesh` in the axes of AERO / AEROS ACSID
    (public reader API; the stick-deck path, whose beam splines carry the surfaces' heights).

    The doublet lattice (Albano and Rodden 1969; nonplanar, Rodden, Giesing and Kalman 1971)
    is solved in the aerodynamic system (MSC Nastran Aeroelastic Analysis User's Guide, Sec.
    2.2: x the flow, CAERO1 chords along x): the corners are R p, R = :func:`aero_axes`, so a
    deck whose ACSID points the flow along basic -X gives the same boxes as the same deck
    rotated to basic axes. Surfaces may lie in different planes z = const of that system (a
    tail above the wing), not across them.

    Parameters
    ----------
    model : pyNastran ``BDF``, cross-referenced (CAERO1 with PAERO1, AEFACT, ACSID).
    L : float, one deck length unit in m.

    Returns
    -------
    mesh : :class:`BoxMesh` (aerodynamic axes, m), one surface per CAERO1 in id order.
    box_ids : (n_boxes,) int, the Nastran box ids.
    axes : (3, 3), R.

    Raises
    ------
    BdfError
        A CAERO type other than CAERO1, or a CAERO1 not in a plane z = const of ACSID
        (dihedral in the aerodynamic system).
    """
    R = aero_axes(model)
    acsid = int(getattr(model.aero or model.aeros, "acsid", 0) or 0)

    def flat(cid, p1, p4):
        if abs(p1[2] - p4[2]) > 1e-9 * max(1.0, abs(p4[1] - p1[1])):
            raise BdfError(f"CAERO1 {cid}: P1 and P4 are not in one x-y plane of the "
                           f"aerodynamic system (AERO ACSID = {acsid}): dihedral is not "
                           f"supported")

    mesh, ids = _caero1_mesh(model, L, R, flat)
    return mesh, ids, R


def _splined_boxes(model, s) -> set:
    """Box ids a SPLINE1 (BOX1-BOX2) or SPLINE4 (AELIST) interpolates.

    +---------+-----+-------+------+------+------+-----+------+-------+
    |    1    |  2  |   3   |  4   |  5   |  6   |  7  |  8   |   9   |
    +=========+=====+=======+======+======+======+=====+======+=======+
    | SPLINE1 | EID | CAERO | BOX1 | BOX2 | SETG | DZ  | METH | USAGE |
    +---------+-----+-------+------+------+------+-----+------+-------+
    | SPLINE4 | EID | CAERO |AELIST|      | SETG | DZ  | METH | USAGE |
    +---------+-----+-------+------+------+------+-----+------+-------+
    """
    if s.type == "SPLINE1":
        return set(range(int(s.box1), int(s.box2) + 1))
    if s.type == "SPLINE4":
        return {int(b) for b in model.aelists[s.aelist].elements}
    raise BdfError(f"{s.type} {s.eid} is not supported (SPLINE1, SPLINE4)")


def _check_splines(model, box_ids, notes):
    splined = set()
    for s in model.splines.values():
        splined |= _splined_boxes(model, s)
    missing = [int(b) for b in box_ids if int(b) not in splined]
    if missing:
        raise BdfError(f"boxes {missing[:10]}{'...' if len(missing) > 10 else ''} are not "
                       f"on any SPLINE1 / SPLINE4: Nastran would leave them rigid; asekit "
                       f"splines every box with the plate's shape functions")
    if model.splines:
        notes.append("SPLINE1 / SPLINE4 checked (every box splined); asekit interpolates the "
                     "modes with its finite-element shape functions, not the surface spline")


# ---------------------------------------------------------------------------------------------
# control surfaces: AESURF, AELIST, AESURFS, AELINK and the hinge's CORD2R (issue 25)
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class DeckControlSurface:
    """An AESURF read and mapped onto its CAERO1 (SI, angles in rad): ``label``, ``aesurf_id``,
    ``cid`` (CID1, the hinge system), ``aelist_id`` (ALID1), ``caero_id`` and ``caero_index``
    (its position among the CAERO1 cards, sorted by id), ``hinge_chord_fraction`` (inboard,
    outboard) and ``span_fraction`` (root to tip) of that panel, ``hinge_point`` and
    ``hinge_axis`` (the CORD2R's origin and unit y axis, basic, m), ``eff``, ``ldw``, the
    hinge-moment reference chord ``crefc`` (m) and area ``crefs`` (m^2), the deflection limits
    ``pllim`` / ``pulim`` (rad), the hinge-moment limits ``hmllim`` / ``hmulim`` (N m, None
    when blank) and the AESURFS grid lists (``aesurfs``: (SET1 of LIST1, SET1 of LIST2) or
    None)."""

    label: str
    aesurf_id: int
    cid: int
    aelist_id: int
    caero_id: int
    caero_index: int
    hinge_chord_fraction: tuple[float, float]
    span_fraction: tuple[float, float]
    hinge_point: tuple[float, float, float]
    hinge_axis: tuple[float, float, float]
    eff: float = 1.0
    ldw: str = "LDW"
    crefc: float = 1.0
    crefs: float = 1.0
    pllim: float = -0.5 * math.pi
    pulim: float = 0.5 * math.pi
    hmllim: float | None = None
    hmulim: float | None = None
    aesurfs: tuple[int, int] | None = None


#: Relative tolerance (of the panel's chord) of the hinge line against the AELIST boxes' edge.
HINGE_TOL = 1e-6


def _caero1_of_boxes(model, a, ids: list[int]):
    """(CAERO1 card, its index among the sorted CAERO1 ids) holding every box of ``ids``."""
    for i, cid in enumerate(sorted(model.caeros)):
        c = model.caeros[cid]
        n = len(_caero1_boxes(c, 1.0)[1])
        if all(cid <= b < cid + n for b in ids):
            return c, i
    raise BdfError(f"AESURF {a.aesurf_id} ALID1 = {a.aelist_id1}: the AELIST boxes {ids[:6]}"
                   f"{'...' if len(ids) > 6 else ''} are not all boxes of one CAERO1")


def _aelist_region(a, c, ids: list[int]):
    """(span box range i0..i1 from P1, first chordwise box j0, NSPAN, NCHORD) of an AELIST
    that is a chordwise-rectangular region reaching the trailing edge of CAERO1 ``c``."""
    _, _, ns, nc = _caero1_boxes(c, 1.0)
    ij = {divmod(b - c.eid, nc) for b in ids}
    rows = sorted({i for i, _ in ij})
    j0 = min(j for _, j in ij)
    want = {(i, j) for i in range(rows[0], rows[-1] + 1) for j in range(j0, nc)}
    if ij != want or j0 == 0:
        raise BdfError(f"AESURF {a.aesurf_id} ALID1 = {a.aelist_id1}: AELIST {a.aelist_id1} must list a "
                       f"rectangular block of CAERO1 {c.eid}'s boxes, whole spanwise strips "
                       f"from one chordwise box to the trailing edge (not the leading-edge "
                       f"box): asekit's control surface is the panel aft of a hinge line")
    return rows[0], rows[-1], j0, ns, nc


def _hinge_axis(deck: Deck, a, c, pts) -> tuple[np.ndarray, np.ndarray]:
    """The hinge system CID1's origin (deck units) and unit y axis (basic), checked to run
    along the boxes' front edge through ``pts`` (its two ends, deck units) root to tip."""
    model = deck.model
    if int(a.cid1) not in model.coords or model.coords[int(a.cid1)].type != "CORD2R":
        raise BdfError(f"AESURF {a.aesurf_id} CID1 = {a.cid1}: no CORD2R {a.cid1} (the hinge "
                       f"system, its y axis the hinge line, MSC Nastran QRG AESURF)")
    cs = model.coords[int(a.cid1)]
    o = np.asarray(cs.origin, float)
    y = np.asarray(cs.j, float)
    y = y / np.linalg.norm(y)
    chord = max(float(c.x12), float(c.x43))
    off = [np.linalg.norm(np.cross(p - o, y)) for p in pts]
    if max(off) > HINGE_TOL * chord or np.dot(pts[1] - pts[0], y) <= 0:
        raise BdfError(f"AESURF {a.aesurf_id} CID1 = {a.cid1}: the y axis of CORD2R {a.cid1} "
                       f"(origin {o.tolist()}, y {np.round(y, 6).tolist()}) is not the front "
                       f"edge of the AELIST {a.aelist_id1} boxes from root to tip (off by "
                       f"{max(off):.3g} deck units): asekit's hinge is that edge, pointing "
                       f"outboard")
    return o, y


def _aesurfs_of(model, label: str):
    """(LIST1, LIST2) SET1 ids of the AESURFS with label ``label``, or None."""
    for s in getattr(model, "aesurfs", {}).values():
        if s.label == label:
            return int(s.list1), int(s.list2)
    return None


def _read_aesurf(deck: Deck, a) -> DeckControlSurface:
    """AESURF (with its AELIST of boxes and the CORD2R of its hinge) as a control surface of
    one CAERO1 (MSC Nastran Quick Reference Guide, AESURF: the hinge line is the y axis of
    CIDi, a positive deflection a right-handed rotation about it: trailing edge down for a y
    axis pointing outboard, asekit's sense, :mod:`asekit.aero.control_surface`).

    +--------+--------+--------+--------+--------+--------+--------+--------+--------+
    |   1    |   2    |   3    |   4    |   5    |   6    |   7    |   8    |   9    |
    +========+========+========+========+========+========+========+========+========+
    | AESURF |   ID   | LABEL  |  CID1  | ALID1  |  CID2  | ALID2  |  EFF   |  LDW   |
    +--------+--------+--------+--------+--------+--------+--------+--------+--------+
    |        | CREFC  | CREFS  | PLLIM  | PULIM  | HMLLIM | HMULIM | TQLLIM | TQULIM |
    +--------+--------+--------+--------+--------+--------+--------+--------+--------+
    | AELIST |  SID   |   E1   |   E2   |   E3   |  ...   |        |        |        |
    +--------+--------+--------+--------+--------+--------+--------+--------+--------+
    """
    model = deck.model
    if a.cid2 is not None or a.aelist_id2 is not None:
        raise BdfError(f"AESURF {a.aesurf_id} CID2 / ALID2: a second component is not supported "
                       f"(one hinge line per surface; give each component its own AESURF)")
    if a.tqllim is not None or a.tqulim is not None:
        deck.notes.append(f"AESURF {a.aesurf_id} TQLLIM / TQULIM (deflection-dependent hinge-"
                          f"moment limits) read and ignored")
    if int(a.aelist_id1) not in model.aelists:
        raise BdfError(f"AESURF {a.aesurf_id} ALID1 = {a.aelist_id1}: no AELIST {a.aelist_id1}")
    ids = sorted(int(b) for b in model.aelists[int(a.aelist_id1)].elements)
    c, index = _caero1_of_boxes(model, a, ids)
    i0, i1, j0, ns, nc = _aelist_region(a, c, ids)
    p1, _, _, p4 = (np.asarray(p, float) for p in c.get_points())
    eta = _divisions(c, c.nspan, c.lspan_ref if c.lspan else None, "SPAN")
    xi = float(_divisions(c, c.nchord, c.lchord_ref if c.lchord else None, "CHORD")[j0])
    e0, e1 = float(eta[i0]), float(eta[i1 + 1])
    pts = [p1 + e * (p4 - p1) + np.array([xi * (c.x12 + e * (c.x43 - c.x12)), 0.0, 0.0])
           for e in (e0, e1)]
    if p4[1] < p1[1]:                       # spanwise from the root (least y), as deck_boxes
        e0, e1, pts = 1.0 - e1, 1.0 - e0, pts[::-1]
    o, y = _hinge_axis(deck, a, c, pts)
    L = deck.L
    hm = [None if v is None else float(v) * deck.Mu * L ** 2 / deck.T ** 2
          for v in (a.hmllim, a.hmulim)]
    return DeckControlSurface(
        str(a.label), int(a.aesurf_id), int(a.cid1), int(a.aelist_id1), int(c.eid), index, (xi, xi),
        (e0, e1), tuple(float(v) for v in o * L), tuple(float(v) for v in y),
        float(a.eff), str(a.ldw), float(a.crefc) * L, float(a.crefs) * L ** 2,
        float(a.pllim), float(a.pulim), hm[0], hm[1], _aesurfs_of(model, str(a.label)))


def _read_aelinks(model, surfaces, notes) -> tuple:
    """AELINK: (label of the dependent, ((independent label, coefficient), ...)) kept and
    reported; one surface geared to one other becomes the case's ``linked_to`` /
    ``gear_ratio`` (:func:`_gears`), any other link is not applied (each surface deflects on
    its own).

    +--------+-------+--------+-------+-------+-------+-------+-------+-------+
    |   1    |   2   |   3    |   4   |   5   |   6   |   7   |   8   |   9   |
    +========+=======+========+=======+=======+=======+=======+=======+=======+
    | AELINK |  ID   | LABLD  | LABL1 |  C1   | LABL2 |  C2   | LABL3 |  C3   |
    +--------+-------+--------+-------+-------+-------+-------+-------+-------+
    """
    labels = {s.label for s in surfaces}
    out = []
    for links in getattr(model, "aelinks", {}).values():
        for k in links:
            named = [k.label] + list(k.independent_labels)
            missing = [n for n in named if n not in labels]
            if missing:
                raise BdfError(f"AELINK {k.aelink_id}: LABEL {missing[0]} is not an AESURF "
                               f"label {sorted(labels)}")
            out.append((str(k.label), tuple((str(n), float(v)) for n, v in
                                            zip(k.independent_labels,
                                                k.linking_coefficients))))
    gears = _gears(out)
    kept = [(d, ind) for d, ind in out if d not in gears]
    if gears:
        notes.append("AELINK applied: " + "; ".join(
            f"{d} geared to {g['linked_to']} (gear ratio {g['gear_ratio']:g})"
            for d, g in gears.items()) + " (control_surface[].linked_to / gear_ratio)")
    if kept:
        notes.append("AELINK read and kept, not applied (asekit gears one surface to one "
                     "other, |C1| <= 10, no chains): asekit reports each of these AESURF as its "
                     "own control surface (" + "; ".join(
                         f"{d} = " + " + ".join(f"{v:g} {n}" for n, v in ind)
                         for d, ind in kept) + ")")
    return tuple(out)


def _read_control_surfaces(deck: Deck) -> dict:
    """Every AESURF (:func:`_read_aesurf`) and AELINK: the keyword arguments of
    :class:`BdfModel` they set."""
    model = deck.model
    found = [_read_aesurf(deck, model.aesurf[k]) for k in sorted(model.aesurf)]
    for s in getattr(model, "aesurfs", {}).values():
        if s.label not in {f.label for f in found}:
            raise BdfError(f"AESURFS {s.aesid} LABEL = {s.label}: no AESURF of that label")
    links = _read_aelinks(model, found, deck.notes)
    if found:
        warnings.warn(f"{deck.name}: AESURF {', '.join(f.label for f in found)}: AESURF gives no "
                      f"hinge stiffness, so the surfaces float free on their hinges (hinge "
                      f"stiffness 0) in the flutter with the hinge degrees of freedom; set "
                      f"case.control_surfaces[i].hinge_stiffness for a spring or actuator",
                      BdfWarning, stacklevel=4)
    return {"control_surfaces": tuple(found), "aelinks": links} if found else {}


def _flfact(model, f, v, name: str) -> tuple[int, np.ndarray]:
    sid = v if isinstance(v, (int, np.integer)) else getattr(v, "sid", v)
    if int(sid) not in model.flfacts:
        raise BdfError(f"FLUTTER {f.sid} {name} = {sid}: no FLFACT {sid}")
    vals = np.asarray(model.flfacts[int(sid)].factors, float)
    if vals.size < 1:
        raise BdfError(f"FLUTTER {f.sid} {name}: FLFACT {sid} lists no value")
    return int(sid), vals


def _flutter_options(f) -> tuple[str, int | None, float]:
    """IMETH, NVALUE and EPS of a FLUTTER card, checked."""
    imeth = str(getattr(f, "imethod", "L") or "L").upper()
    if imeth not in ("L", "S"):
        raise BdfError(f"FLUTTER {f.sid} IMETH = {imeth!r} must be 'L' (linear) or 'S' "
                       f"(surface)")
    nvalue = getattr(f, "nvalue", None)
    if nvalue is not None and (not isinstance(nvalue, (int, np.integer)) or nvalue < 1):
        raise BdfError(f"FLUTTER {f.sid} NVALUE = {nvalue!r} must be an integer >= 1")
    eps = getattr(f, "epsilon", None)
    eps = 1e-3 if eps is None else float(eps)
    if not (math.isfinite(eps) and eps > 0):
        raise BdfError(f"FLUTTER {f.sid} EPS = {eps!r} must be > 0 (default 1.0E-3)")
    return imeth, (int(nvalue) if nvalue is not None else None), eps


def _check_pknl(f, ids, lists) -> None:
    n = [len(v) for v in lists]
    if len(set(n)) != 1:
        parts = ", ".join(f"{name} = FLFACT {sid} has {k}" for name, sid, k in
                          zip(("DENS", "MACH", "RFREQ"), ids, n))
        raise BdfError(f"FLUTTER {f.sid} PKNL: {parts} values; PKNL needs equal lengths "
                       f"(one flight point per index)")


def read_flutter(model, f, rho_ref, deck) -> FlutterRequest:
    """A FLUTTER request with its FLFACT lists in SI (densities x RHOREF, |velocities|), as
    MSC Nastran reads it (Quick Reference Guide, FLUTTER and FLFACT). Public reader API.

    Parameters
    ----------
    model : pyNastran ``BDF`` (its FLFACT cards).
    f : the pyNastran FLUTTER card.
    rho_ref : float or None, AERO RHOREF (kg/m^3) (:func:`read_aero_card`).
    deck : :class:`Deck` (units and ranges).

    Returns
    -------
    FlutterRequest

    Raises
    ------
    BdfError
        Naming FLUTTER SID and the field (METHOD, DENS, MACH, RFREQ, IMETH, NVALUE, EPS).

    Card fields (MSC Quick Reference Guide)::

        +---------+-----+--------+------+------+-------+-------+-------+------+
        |    1    |  2  |   3    |  4   |  5   |   6   |   7   |   8   |  9   |
        +=========+=====+========+======+======+=======+=======+=======+======+
        | FLUTTER | SID | METHOD | DENS | MACH | RFREQ | IMETH | NVALUE| EPS  |
        +---------+-----+--------+------+------+-------+-------+-------+------+
        | FLFACT  | SID |   F1   |  F2  |  F3  |  F4   |  F5   |  F6   |  F7  |
        +---------+-----+--------+------+------+-------+-------+-------+------+

    METHOD K / KE: RFREQ lists reduced frequencies k > 0; PK / PKNL: velocities (negative:
    print the eigenvectors at |V|). PKNL: DENS, MACH and VEL lists of equal length, one flight
    point per index. DENS are density ratios (x AERO RHOREF).
    """
    method = str(f.method).upper()
    if method not in ("K", "KE", "PK", "PKNL"):
        raise BdfError(f"FLUTTER {f.sid} METHOD = {method} must be K, KE, PK or PKNL")
    if rho_ref is None:
        raise BdfError(f"FLUTTER {f.sid} needs AERO (RHOREF)")
    imeth, nvalue, eps = _flutter_options(f)
    ids, raw = zip(*(_flfact(model, f, v, name) for v, name in (
        (f.density, "DENS"), (f.mach, "MACH"), (f.reduced_freq_velocity, "RFREQ"))))
    for j, x in enumerate(raw[0]):
        _check_range(deck, f"FLFACT {ids[0]} (FLUTTER {f.sid} DENS) F{j + 1}", x,
                     "fluid density", si=x * rho_ref)
    dens = raw[0] * rho_ref
    if method == "PKNL":
        _check_pknl(f, ids, raw)
    common = dict(sid=int(f.sid), method=method, densities=tuple(map(float, dens)),
                  machs=tuple(map(float, raw[1])), imeth=imeth, nvalue=nvalue, eps=eps)
    if method in ("K", "KE"):
        bad = [j for j, k in enumerate(raw[2]) if not (math.isfinite(k) and k > 0)]
        if bad:
            raise BdfError(f"FLFACT {ids[2]} (FLUTTER {f.sid} RFREQ) F{bad[0] + 1} = "
                           f"{raw[2][bad[0]]:g}: reduced frequencies of the {method} method "
                           f"must be > 0")
        return FlutterRequest(velocities=(), reduced_frequencies=tuple(map(float, raw[2])),
                              **common)
    vel = raw[2] * deck.L / deck.T
    for j, x in enumerate(raw[2]):
        _check_range(deck, f"FLFACT {ids[2]} (FLUTTER {f.sid} RFREQ) F{j + 1}", x,
                     "velocity", si=abs(x) * deck.L / deck.T)
    return FlutterRequest(velocities=tuple(map(float, np.abs(vel))),
                          print_vectors=tuple(bool(x < 0) for x in raw[2]), **common)


# ---------------------------------------------------------------------------------------------
# what holds the structure: connectivity and rigid-body modes
# ---------------------------------------------------------------------------------------------
def _components_of(n: int, links) -> np.ndarray:
    """Connected components (a label per node) of ``n`` nodes joined by ``links`` (node index
    arrays, each joining all its nodes)."""
    parent = np.arange(n)

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i
    for group in links:
        r0 = root(int(group[0]))
        for j in group[1:]:
            r = root(int(j))
            if r != r0:
                parent[r] = r0
    return np.array([root(i) for i in range(n)])


def _check_connectivity(deck: Deck, conn, quads, springs, masses, rigid) -> np.ndarray:
    """Warn (:class:`BdfWarning`) about GRIDs that no element, spring, mass or rigid link uses
    (ignored) and about plate elements in pieces that share no grid, rigid link or spring with
    the largest piece; returns the component label of each node (elements and RBE2 joined)."""
    n = len(deck.nids)
    links = [np.unique(c) for c in conn] + [np.array([gi, *dep]) for gi, _, dep in rigid]
    comp = _components_of(n, links)
    used = np.zeros(n, bool)
    used[np.unique(conn)] = True
    for gi, _, dep in rigid:
        used[[gi, *dep]] = True
    for a, b, _ in springs:
        used[[a // DOF_PER_NODE] + ([b // DOF_PER_NODE] if b >= 0 else [])] = True
    used[[m[0] for m in masses]] = True
    idle = deck.nids[~used]
    if idle.size:
        off = [int(g) for g in idle if abs(deck.xyz[deck.index[int(g)], 2] - deck.z0)
               > 1e-6 * max(float(np.ptp(deck.xyz[:, :2])), 1.0)]
        warnings.warn(f"{deck.name}: GRIDs {idle[:10].tolist()}{'...' if idle.size > 10 else ''}"
                      f" touch no element, spring, mass or rigid link: ignored"
                      + (f" (off the plate's plane: {off[:10]})" if off else ""),
                      BdfWarning, stacklevel=4)
    joined = _components_of(n, links + [np.array([a // 3, b // 3]) for a, b, _ in springs
                                        if b >= 0])
    pieces = joined[conn[:, 0]]
    labels, counts = np.unique(pieces, return_counts=True)
    if labels.size > 1:
        loose = [int(quads[j].eid) for j in np.flatnonzero(pieces != labels[np.argmax(counts)])]
        warnings.warn(f"{deck.name}: the plate is in {labels.size} pieces that share no grid, "
                      f"spring or rigid link: elements {loose[:10]}"
                      f"{'...' if len(loose) > 10 else ''} do not touch the largest piece",
                      BdfWarning, stacklevel=4)
    return comp


def _rigid_vectors(deck: Deck, comp: np.ndarray):
    """The rigid out-of-plane motions of each component with a label >= 0 (3 per component:
    w = 1; w = y - y_c, theta_x = 1; w = -(x - x_c), theta_y = 1, lengths in units of the
    model's size, so that every column has entries of order 1), as an (n_dof, 3 n_comp)
    array, and the component of each column."""
    labels = np.unique(comp[comp >= 0])
    R = np.zeros((deck.n_dof, 3 * labels.size))
    ell = max(float(np.ptp(deck.nodes, axis=0).max()), 1e-300)
    for k, lab in enumerate(labels):
        idx = np.flatnonzero(comp == lab)
        xy = deck.nodes[idx]
        c = xy.mean(axis=0)
        d = DOF_PER_NODE * idx
        R[d, 3 * k] = 1.0
        R[d, 3 * k + 1], R[d + 1, 3 * k + 1] = (xy[:, 1] - c[1]) / ell, 1.0 / ell
        R[d, 3 * k + 2], R[d + 2, 3 * k + 2] = -(xy[:, 0] - c[0]) / ell, 1.0 / ell
    return R, np.repeat(labels, 3)


def _unrestrained(R, fixed: set, Ks, K) -> np.ndarray:
    """Basis (columns) of the combinations c of the rigid motions R that every constraint
    allows (R c = 0 on the fixed DOFs; an RBE2 moves rigidly anyway) and that no spring
    resists (c^T R^T K_s R c = 0; plate elements carry no strain energy in a rigid motion)."""
    rows = R[sorted(fixed)] if fixed else np.zeros((0, R.shape[1]))
    rows = rows[np.abs(rows).max(axis=1) > 0] if rows.size else rows
    rows = rows / np.abs(rows).max(axis=1, keepdims=True) if rows.size else rows
    tau = max(float(np.abs(K.diagonal()).max()), 1e-300)
    w, V = np.linalg.eigh(0.5 * (R.T @ (Ks @ R) + (R.T @ (Ks @ R)).T) / tau)
    A = np.vstack([rows, np.sqrt(np.clip(w, 0.0, None))[:, None] * V.T])
    if not A.size:
        return np.eye(R.shape[1])
    _, s, Vt = np.linalg.svd(A, full_matrices=True)
    s = np.concatenate([s, np.zeros(R.shape[1] - s.size)])
    return Vt[s <= 1e-6].T


def _free_rigid_modes(deck: Deck, comp, fixed: set, Ks, K, M):
    """The rigid-body modes the supports leave: the unrestrained rigid motions
    (:func:`_unrestrained`) that carry mass, split as the mode selection of the pipeline
    does (:data:`asekit.structure.modes.MIN_OUT_OF_PLANE`): those with an out-of-plane (w)
    kinetic-energy share of at least that reach the analysis as 0 Hz modes; the others (the
    fictitious pitch inertia of an FN2 export: a grounded grid's R2 inertia) are dropped by
    it. Returns (modes kept, modes dropped, component with the largest share of the first
    kept one or None)."""
    node_mass = np.abs(M).sum(axis=1).A1.reshape(-1, DOF_PER_NODE).sum(axis=1)
    labels, inv = np.unique(comp, return_inverse=True)
    heavy = np.bincount(inv, weights=node_mass) > 0
    comp = np.where(heavy[inv], comp, -1)           # a massless piece has no mode
    R, col_comp = _rigid_vectors(deck, comp)
    N = _unrestrained(R, fixed, Ks, K)
    if not N.shape[1]:
        return 0, 0, None
    U = R @ N
    MU = M @ U
    b, Vb = np.linalg.eigh(0.5 * (U.T @ MU + MU.T @ U))
    massive = b > 1e-10 * max(float(b.max()), 1e-300)
    if not massive.any():
        return 0, 0, None
    W = Vb[:, massive] / np.sqrt(b[massive])          # M-orthonormal unrestrained motions
    Aw = (U @ W)[0::DOF_PER_NODE].T @ (MU @ W)[0::DOF_PER_NODE]
    share, S = np.linalg.eigh(0.5 * (Aw + Aw.T))
    kept = share >= MIN_OUT_OF_PLANE
    if not kept.any():
        return 0, int(massive.sum()), None
    first = N @ (W @ S[:, np.flatnonzero(kept)[-1]])
    return int(kept.sum()), int((~kept).sum()), int(col_comp[np.argmax(np.abs(first))])


def _suport_dofs(model) -> int:
    """The number of out-of-plane DOFs (components 3, 4, 5) SUPORT / SUPORT1 declare free."""
    cards = list(getattr(model, "suport", []) or []) + list(
        (getattr(model, "suport1", {}) or {}).values())
    return sum(len(_components(c)) for s in cards for c in getattr(s, "Cs", []))


def _holding_words(deck: Deck, fixed: set, springs) -> str:
    """What the deck holds the structure with (for the rigid-body error)."""
    parts = [f"SPC / SPC1 / GRID PS fix {len(fixed)} out-of-plane DOFs" if fixed else
             "no SPC / SPC1 set applies and no GRID PS holds a T3, R1 or R2 DOF"]
    grounded = sum(1 for _, b, _ in springs if b < 0)
    parts.append(f"{grounded} CELAS to ground" if grounded else "no CELAS to ground")
    parts += deck.missing
    return "; ".join(parts)


def _check_rigid_modes(deck: Deck, comp, fixed, springs, Ks, K, M) -> None:
    """Refuse a structure with rigid-body modes (zero strain energy, some mass) the deck does
    not explain; with as many SUPORT DOFs as modes (a free-free model declared) warn."""
    n, dropped, where = _free_rigid_modes(deck, comp, fixed, Ks, K, M)
    if dropped:
        deck.notes.append(f"{dropped} zero-frequency mode{'s' * (dropped > 1)} with less than "
                          f"{MIN_OUT_OF_PLANE:.0%} of its kinetic energy out of plane (e.g. an "
                          f"FN2 fictitious pitch inertia): left out by the mode selection")
    if not n:
        return
    idx = np.flatnonzero(comp == where)
    grids = [int(g) for g in deck.nids[idx][:8]]
    piece = ("the whole plate" if idx.size == len(deck.nids)
             else f"the piece of GRIDs {grids}{'...' if idx.size > 8 else ''}")
    n_sup = _suport_dofs(deck.model)
    if n_sup and n <= n_sup:
        warnings.warn(f"{deck.name}: {n} rigid-body modes (free-free, SUPORT on {n_sup} "
                      f"DOFs): asekit keeps them as 0 Hz modes among the elastic ones",
                      BdfWarning, stacklevel=4)
        return
    raise BdfError(f"the structure has {n} rigid-body mode{'s' * (n > 1)} (zero "
                   f"strain energy; {piece} moves freely): {_holding_words(deck, fixed, springs)}"
                   f"{f'; SUPORT declares {n_sup}' if n_sup else ''}: add the SPC / SPC1 of "
                   f"its supports (and SPC = n in the case control) or GRID PS")


def _angles(keys, n):
    out = np.zeros(n)
    for (pid, ang), idx in keys.items():
        out[np.asarray(idx)] = ang
    return out


# ---------------------------------------------------------------------------------------------
# the import
# ---------------------------------------------------------------------------------------------
def _check_cards(model, name: str) -> list:
    """Refuse the decks holding a card asekit cannot represent; the ignored cards."""
    refused, ignored = _card_report(model)
    if refused:
        raise BdfError(f"{name}: asekit cannot represent these cards: {_fmt(refused)}. "
                       f"It models a flat plate of CQUAD4 / CTRIA3 elements (PSHELL, "
                       f"MAT1/MAT8) with CONM2, CELAS1/2, RBE2 and SPC supports (CTRIA3 as a "
                       f"degenerated MITC4).")
    return ignored


def read_deck(path, units: str = "SI", tol: float | None = None,
              thickness_rule: str = "gauss") -> BdfModel:
    """Read a flat plate-wing BDF with pyNastran into a :class:`BdfModel` (the deck's record:
    asekit's matrices and Nastran's ids); :func:`read_bdf` makes it a case.

    Parameters
    ----------
    path : str or Path
        The deck (executive and case control optional).
    units : str
        The deck's unit system, a key of :data:`UNITS` (``"SI"``, ``"mm-t-s"``,
        ``"in-lbf-s"``); everything is converted to SI.
    tol : float, optional
        Flatness tolerance in deck length units (default 1e-6 x the model size).
    thickness_rule : str
        ``"gauss"`` (default: the corner thicknesses T1-T4 interpolated bilinearly to every
        integration point) or ``"centroid"`` (each element at its mean corner thickness).

    Returns
    -------
    BdfModel
        Raises :class:`BdfError` (a ValueError, one line) for a deck asekit cannot represent
        (refused cards listed) or that is wrong: any error of pyNastran's (the card, its id
        and the field in pyNastran's words; a reference to a missing card names the card
        that refers), a second card with an id already given (:data:`ID_SPACES`; an exact
        repeat is read once), a value outside :data:`RANGES` (card, id, field, value in
        deck and SI units), the MAT1 rules broken, a degenerate element, or rigid-body
        modes that no SPC / SPC1 / GRID PS / CELAS holds (the missing support named; with
        as many SUPORT DOFs it is a :class:`BdfWarning`). Warns :class:`BdfWarning` for
        GRIDs that touch nothing and for plate pieces that touch nothing else, and
        :class:`UnsupportedCardWarning` once, listing every card read but not represented
        (name, count, first id).
    """
    if units not in UNITS:
        raise ValueError(f"units must be one of {sorted(UNITS)}, got {units!r}")
    BDF = need_pynastran()
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"BDF not found: {path}")
    if not path.is_file():
        raise BdfError(f"{path}: not a file (give the deck's .bdf file)")
    model, trace = _open_deck(path, BDF)
    ignored = _check_cards(model, path.name)
    deck = Deck(model, path.name, *UNITS[units], wtmass=_read_param_wtmass(model, path.name))
    if trace.repeats:
        deck.notes.append(f"{trace.repeats} cards repeated exactly (same id, same fields): "
                          f"each read once")
    quads = _shell_elements(model, path.name)
    _read_grids(deck, quads, tol)
    conn, th, angles, pids, props = _read_shells(deck, quads)
    K, M, materials, keys, mesh = _plate_matrices(deck, conn, th, pids, props, angles,
                                                  thickness_rule)
    springs, Ks = _read_celas(deck)
    masses, Mm = _read_conm2(deck)
    K, M = (K + Ks).tocsr(), (M + Mm).tocsr()
    fixed = _read_spcs(deck)
    dep, rigid = _read_rbe2(deck, fixed)
    Tm = _reduction(deck.n_dof, fixed, dep, K, M)
    comp = _check_connectivity(deck, conn, quads, springs, masses, rigid)
    _check_rigid_modes(deck, comp, fixed, springs, Ks, K, M)
    system = SupportedSystem(K=(Tm.T @ K @ Tm).tocsr(), M=(Tm.T @ M @ Tm).tocsr(), T=Tm,
                             shaft_index=None, ground_index=None, fictitious_inertia=0.0,
                             shaft_nodes=np.array([], dtype=np.int64), mesh=mesh,
                             label=f"BDF {path.name}: {len(quads)} CQUAD4, {len(deck.nids)} "
                                   f"GRID")
    n_modes, f_max = _read_eigen_method(model, deck)
    aero = _read_aero(deck)
    if aero:
        aero.update(_read_control_surfaces(deck))
    elif deck.model.aesurf:
        raise BdfError("AESURF without CAERO1 boxes")
    if ignored:
        warnings.warn(f"{path.name}: cards read but not represented by asekit: "
                      f"{_fmt(ignored)}", UnsupportedCardWarning, stacklevel=2)
    return BdfModel(mesh=mesh, node_ids=deck.nids, K=K, M=M, system=system, **aero,
                    n_modes=n_modes, f_max_hz=f_max, damping_g=_read_tabdmp1(model, deck),
                    eigen_card=_eigen_card(model),
                    materials=materials, element_pids=pids.copy(),
                    element_angles=_angles(keys, len(quads)), springs=springs, masses=masses,
                    fixed=tuple(sorted(fixed)), rigid=rigid, ignored=tuple(ignored),
                    notes=tuple(deck.notes), path=str(path), units=units,
                    coupled_mass=_read_param_coupmass(model))


# ---------------------------------------------------------------------------------------------
# the deck as a case of the pipeline
# ---------------------------------------------------------------------------------------------
def _clamped_root(bdf: BdfModel) -> bool:
    """Whether the fixed DOFs are exactly T3, R1, R2 of every plate node on the root station
    (least y) and nothing else holds the structure."""
    used = np.unique(bdf.mesh.elements)
    y = bdf.mesh.nodes[used, 1]
    root = used[np.abs(y - y.min()) <= 1e-9 * max(float(np.ptp(y)), 1.0)]
    want = {DOF_PER_NODE * int(i) + c for i in root for c in range(DOF_PER_NODE)}
    return set(bdf.fixed) == want and not bdf.rigid and not bdf.springs


def _support_words(bdf: BdfModel) -> str:
    """What holds the deck's structure, in words (its own cards, applied as they are)."""
    parts = []
    if bdf.fixed:
        grids = len({d // DOF_PER_NODE for d in bdf.fixed})
        parts.append(f"SPC / GRID PS on {len(bdf.fixed)} DOFs of {grids} grids"
                     + (" (a clamped root)" if _clamped_root(bdf) else ""))
    if bdf.rigid:
        parts.append(f"{len(bdf.rigid)} RBE2")
    grounded = sum(1 for _, b, _ in bdf.springs if b < 0)
    if grounded:
        parts.append(f"{grounded} CELAS to ground")
    return ", ".join(parts) if parts else "nothing (free-free)"


def _flight_of(bdf: BdfModel) -> FlightSpec | None:
    """The flight conditions of the deck's first PK / PKNL FLUTTER request (the case control's
    FMETHOD first): its densities and its velocities (ascending, duplicates dropped)."""
    swept = [r for r in bdf.flutter if r.velocities]        # PK / PKNL (K, KE sweep k)
    if not swept:
        return None
    req = swept[0]
    return FlightSpec(velocities=tuple(sorted(set(req.velocities))),
                      densities=tuple(dict.fromkeys(req.densities)))


def _aero_of(bdf: BdfModel) -> AeroSpec | None:
    """The aerodynamics of the deck: the first FLUTTER request's Mach numbers (on the MKAERO1
    grid; without FLUTTER the MKAERO1 Mach numbers), the MKAERO1 reduced frequencies,
    REFC / 2, SYMXZ as a wall at y = 0; asekit's doublet lattice (quartic kernel)."""
    if bdf.boxes is None:
        return None
    machs = bdf.machs
    for req in bdf.flutter:
        off = [m for m in req.machs if not any(abs(m - g) <= 1e-9 for g in bdf.machs)]
        if off:
            raise BdfError(f"FLUTTER {req.sid} MACH: Mach {off[0]} is not on the MKAERO1 grid "
                           f"{list(bdf.machs)}")
    if bdf.flutter:
        machs = tuple(sorted(set(bdf.flutter[0].machs)))
    return AeroSpec(machs=machs, reference_semichord=bdf.b_ref,
                    reduced_frequencies=bdf.reduced_frequencies,
                    symmetry="wall" if bdf.symmetric else "none")


def _modes_of(bdf: BdfModel) -> ModesSpec:
    """EIGRL / EIGR as the case's modes: the first ND (below V2 if given), else all below V2
    (default 1000 Hz)."""
    if bdf.n_modes:
        return ModesSpec(count=bdf.n_modes, f_max=bdf.f_max_hz or 1e300, keep_rigid=False)
    return ModesSpec(count=None, f_max=bdf.f_max_hz or 1000.0, keep_rigid=False)


def _surface_geometry(boxes: BoxMesh, i: int):
    """(root LE, root chord, tip LE, tip chord, NCHORD, NSPAN, chord fractions, span fractions)
    of surface ``i`` of a structured box mesh (root to tip, LE box first in each strip)."""
    c = boxes.corners[boxes.surface == i]
    st = boxes.strip[boxes.surface == i]
    nc = int(np.sum(st == st[0]))
    ns = c.shape[0] // nc
    g = c.reshape(ns, nc, 4, 3)
    r_le, r_c = g[0, 0, 0], g[0, -1, 1, 0] - g[0, 0, 0, 0]
    t_le, t_c = g[-1, 0, 3], g[-1, -1, 2, 0] - g[-1, 0, 3, 0]
    xi = np.concatenate([[0.0], (g[0, :, 1, 0] - r_le[0]) / r_c])
    eta = np.concatenate([[0.0], (g[:, 0, 3, 1] - r_le[1]) / (t_le[1] - r_le[1])])
    return r_le, float(r_c), t_le, float(t_c), nc, ns, xi, eta


def _deck_panels(bdf: BdfModel) -> tuple:
    """The CAERO1 panels as :class:`~asekit.aero.boxes.TrapezoidSurface` (their box counts),
    for the control surfaces' hinged boxes (:func:`asekit.case.pipeline.control_surface_mesh`);
    () without AESURF."""
    from asekit.aero.boxes import TrapezoidSurface
    if not bdf.control_surfaces:
        return ()
    out = []
    for i, name in enumerate(bdf.boxes.surface_names):
        r_le, r_c, t_le, t_c, nc, ns, _, _ = _surface_geometry(bdf.boxes, i)
        out.append(TrapezoidSurface(tuple(r_le), r_c, tuple(t_le), t_c, nc, ns, name))
    return tuple(out)


def _control_specs(bdf: BdfModel) -> tuple:
    """The AESURF cards as ``[[control_surface]]`` specs: rigid, on a free hinge (AESURF gives
    no hinge stiffness: 0 N m/rad)."""
    from asekit.case.schema import ControlSurfaceSpec
    gears = _gears(bdf.aelinks)
    return tuple(ControlSurfaceSpec(s.label, s.caero_index, s.hinge_chord_fraction,
                                    s.span_fraction, "rigid", 0.0, 0.0,
                                    **gears.get(s.label, {}))
                 for s in bdf.control_surfaces)


def _gears(aelinks) -> dict:
    """The AELINKs a case can hold (``linked_to`` / ``gear_ratio``, issue 25): one surface
    geared to one other, |C1| <= 10, the master itself not geared; {label: keywords}."""
    one = {d: ind[0] for d, ind in aelinks if len(ind) == 1 and ind[0][0] != d
           and abs(ind[0][1]) <= 10.0}
    return {d: {"linked_to": m, "gear_ratio": c} for d, (m, c) in one.items() if m not in one}


def deck_case(bdf: BdfModel, name: str | None = None) -> Case:
    """A read deck as a :class:`~asekit.case.Case` of the pipeline.

    The case's ``structure`` (:class:`~asekit.case.imported.ImportedModel`) holds the mesh,
    K, M, the deck's own supports (the SPC / GRID PS / RBE2 reduction; CELAS in K: applied as
    they are, ``support.kind = "imported"``), the CAERO1 boxes and the TABDMP1 table; EIGRL /
    EIGR give ``modes``; AERO, MKAERO1 and the first FLUTTER request (FMETHOD's) give
    ``aero`` (its Mach numbers, the MKAERO1 k, REFC / 2, SYMXZ) and ``flight`` (its FLFACT
    densities x RHOREF and velocities); None without CAERO1 / FLUTTER. A PKNL request's
    matched (density, Mach, velocity) triples become the full grid density x Mach over all
    velocities (a superset) for the pipeline's p-k. The AESURF cards become
    ``control_surfaces`` (rigid, hinge stiffness 0: AESURF gives none), their CAERO1 panels
    ``structure.panels``. Every FLUTTER request, each with its own
    method (K, KE, PK, PKNL at its matched points), is run by :func:`deck_flutter`.

    Parameters
    ----------
    bdf : BdfModel
        From :func:`read_deck`.
    name : str, optional
        The case name (default the file's stem).

    Returns
    -------
    Case
        ``pipeline.modal_model(case)``, ``gaf_database(case)``, ``flutter(case)`` and the
        report work on it; the export :func:`case_bdf` writes it back with the deck's ids.
    """
    stem = Path(bdf.path).stem if bdf.path else "bdf"
    structure = ImportedModel(mesh=bdf.mesh, K=bdf.K, M=bdf.M, T=bdf.system.T, boxes=bdf.boxes,
                              damping_g=bdf.damping_g, support=_support_words(bdf),
                              label=bdf.system.label, deck=bdf,
                              panels=_deck_panels(bdf))
    return Case(name=name or stem, panels=(), thickness=None, material=None,
                support=SupportSpec(kind=IMPORTED_SUPPORT), aero=_aero_of(bdf),
                flight=_flight_of(bdf), modes=_modes_of(bdf),
                control_surfaces=_control_specs(bdf),
                reference=f"Nastran deck {Path(bdf.path).name if bdf.path else ''} "
                          f"(units {bdf.units}, converted to SI)",
                source=bdf.path or "", structure=structure)


def read_bdf(path, units: str = "SI", tol: float | None = None,
             thickness_rule: str = "gauss", name: str | None = None) -> Case:
    """Read a flat plate-wing BDF into a :class:`~asekit.case.Case` of the pipeline
    (:func:`read_deck`, then :func:`deck_case`).

    Parameters
    ----------
    path, units, tol, thickness_rule : see :func:`read_deck`.
    name : str, optional
        The case name (default the file's stem).

    Returns
    -------
    Case
        With ``case.structure.deck`` the :class:`BdfModel` record.

    Examples
    --------
    The HA145E wing (needs pyNastran; tests/io/test_bdf.py runs it):

    >>> from asekit.io import bdf                                 # doctest: +SKIP
    >>> from asekit.case import pipeline                          # doctest: +SKIP
    >>> case = bdf.read_bdf("data/benchmarks/ha145e/ha145e.bdf",
    ...                     units="in-lbf-s")                     # doctest: +SKIP
    >>> round(pipeline.flutter(case).results[0].flutter.speed / 0.0254)   # doctest: +SKIP
    6066
    """
    return deck_case(read_deck(path, units, tol, thickness_rule), name=name)


# ---------------------------------------------------------------------------------------------
# the deck's FLUTTER cards, each with its own method (MSC Nastran's K, KE, PK, PKNL)
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class DeckFlutter:
    """One FLUTTER card solved as Nastran would: ``request`` the card, ``results`` one
    :class:`~asekit.aeroelastic.nastran.NastranFlutterResult` per density x Mach loop (PKNL:
    one, over its matched points), ``crossings`` every g = 0 crossing (and root unstable at
    the first point) of them, sorted by speed."""

    request: FlutterRequest
    results: tuple
    crossings: tuple


def _signed(req: FlutterRequest) -> np.ndarray:
    v = np.asarray(req.velocities, float)
    return np.where(np.asarray(req.print_vectors, bool), -v, v) if req.print_vectors else v


def solve_request(req: FlutterRequest, modal, db) -> DeckFlutter:
    """Run one FLUTTER request with its own method (public reader API).

    Parameters
    ----------
    req : :class:`FlutterRequest` (:func:`read_flutter`).
    modal : the elastic modal model (:class:`~asekit.aeroelastic.statespace.ModalArrays`).
    db : the GAF tables by Mach (``db.at(mach)`` a
        :class:`~asekit.aero.gaf.TabulatedGaf`).

    Returns
    -------
    DeckFlutter
        The request, one :mod:`asekit.aeroelastic.nastran` result per (density, Mach) point
        (one matched-point result for PKNL) and the crossings.
    """
    from asekit.aeroelastic import nastran as N

    def gaf(mach):
        return N.elastic_part(modal, db.at(mach))

    if req.method == "PKNL":
        m = gaf(req.machs[0])[0]
        results = [N.pknl_method(m, lambda mach: gaf(mach)[1], req.densities, req.machs,
                                 _signed(req), eps=req.eps, interpolation=req.imeth)]
    else:
        results = []
        for rho, mach in req.points():
            m, g = gaf(mach)
            if req.method == "PK":
                results.append(N.pk_method(m, g, rho, _signed(req), eps=req.eps,
                                           interpolation=req.imeth, mach=mach))
            else:
                results.append(N.k_method(m, g, rho, req.reduced_frequencies,
                                          vectors=req.method == "K", interpolation=req.imeth,
                                          mach=mach))
    found = sorted((c for r in results for c in N.crossings(r)), key=lambda c: c.speed)
    return DeckFlutter(req, tuple(results), tuple(found))


def deck_flutter(case: Case, db=None) -> list[DeckFlutter]:
    """Every FLUTTER card of a deck's case (:func:`read_bdf`) with its own method, densities,
    Machs and velocities or reduced frequencies (:mod:`asekit.aeroelastic.nastran`; asekit's
    modes of the deck's structure and asekit's doublet lattice, rigid modes held).

    Parameters
    ----------
    case : Case
        From :func:`read_bdf` (``case.structure.deck`` holds the FLUTTER requests).
    db : GafDatabase, optional
        GAFs at every Mach of the cards (default: :func:`asekit.case.pipeline.gaf_database`
        of the case with the Machs of every card).

    Returns
    -------
    list of DeckFlutter, in the deck's order (the case control's FMETHOD first).
    """
    bdf = getattr(case.structure, "deck", None)
    if bdf is None or not bdf.flutter:
        return []
    from dataclasses import replace
    modal = pl.modal_model(case)
    if db is None:
        machs = tuple(sorted({m for r in bdf.flutter for m in r.machs}))
        db = pl.gaf_database(replace(case, aero=replace(case.aero, machs=machs)),
                             progress=False)
    return [solve_request(req, modal, db) for req in bdf.flutter]


def flutter_rows(solved: list[DeckFlutter]) -> list[dict]:
    """The JSON rows of :func:`deck_flutter`: one per crossing (or root unstable at the first
    point), a card without any gives one row with ``speed_ms`` None. Keys: method, sid, mach,
    density (kg/m^3), speed_ms, frequency_hz, mode (1-based elastic mode),
    unstable_at_first_point, altitude_m (None: a deck gives densities)."""
    rows = []
    for d in solved:
        r = d.request
        for c in d.crossings:
            rows.append({"method": r.method, "sid": r.sid, "mach": c.mach,
                         "density": c.density, "altitude_m": None, "speed_ms": c.speed,
                         "frequency_hz": 0.0 if c.kind == "divergence" else c.frequency_hz,
                         "mode": c.mode + 1, "kind": c.kind,
                         "unstable_at_first_point": c.unstable_at_first_point,
                         "speed_upper_bound_ms": c.speed if c.unstable_at_first_point
                         else None})
        if not d.crossings:
            rows.append({"method": r.method, "sid": r.sid, "mach": r.machs[0],
                         "density": r.densities[0], "altitude_m": None, "speed_ms": None,
                         "frequency_hz": None, "mode": None, "kind": None,
                         "unstable_at_first_point": False, "speed_upper_bound_ms": None})
    return rows


def format_flutter_summary(solved: list[DeckFlutter]) -> str:
    """Nastran's FLUTTER SUMMARY of every card (V in m/s, g, f Hz per mode, the card's NVALUE
    modes), :func:`asekit.aeroelastic.nastran.flutter_summary`."""
    from asekit.aeroelastic.nastran import flutter_summary
    blocks = []
    for d in solved:
        for res in d.results:
            blocks.append(f"FLUTTER {d.request.sid} ({d.request.method})\n"
                          + flutter_summary(res, d.request.nvalue, "m/s"))
    return "\n\n".join(blocks)


# ---------------------------------------------------------------------------------------------
# export of a case
# ---------------------------------------------------------------------------------------------
def _mkaero_cards(bdf, machs, ks):
    for i in range(0, len(machs), 8):
        for j in range(0, len(ks), 8):
            bdf.add_mkaero1(list(machs[i:i + 8]), list(ks[j:j + 8]))


def _material_card(model, mid: int, mat) -> None:
    """MAT1 (isotropic) or MAT8 (orthotropic; its angle goes on the elements' THETA)."""
    if isinstance(mat, Material):
        model.add_mat1(mid, mat.youngs_modulus, None, mat.poisson_ratio, rho=mat.density)
    else:
        model.add_mat8(mid, mat.e1, mat.e2, mat.nu12, g12=mat.g12, g1z=mat.g13, g2z=mat.g23,
                       rho=mat.density)


def _plate_cards(model, case) -> tuple[list[int], int]:
    """GRID (PS 126) per node, MAT1 / MAT8 + PSHELL, CQUAD4 with T1-T4 from the case's
    thickness law; returns (GRID id per mesh node, next element id)."""
    mesh = pl.structural_mesh(case)
    for i, (x, y) in enumerate(mesh.nodes):
        model.add_grid(i + 1, [float(x), float(y), 0.0], ps="126")
    xy = mesh.nodes[mesh.elements]
    # corner thicknesses from the case's law (evaluated at the nodes)
    cth = mesh.thickness_xy(xy[:, :, 0].ravel(), xy[:, :, 1].ravel()).reshape(-1, 4)
    mat = case.material
    _material_card(model, 1, mat)
    ang_mat = 0.0 if isinstance(mat, Material) else mat.fibre_angle
    model.add_pshell(1, mid1=1, t=float(np.max(cth)), mid2=1, mid3=1)
    for e, conn in enumerate(mesh.elements):
        d = xy[e, 1] - xy[e, 0]
        theta = math.degrees(ang_mat - math.atan2(d[1], d[0]))
        model.add_cquad4(e + 1, 1, [int(c) + 1 for c in conn], theta_mcid=float(theta),
                         T1=float(cth[e, 0]), T2=float(cth[e, 1]), T3=float(cth[e, 2]),
                         T4=float(cth[e, 3]))
    return list(range(1, mesh.n_nodes + 1)), mesh.n_elements + 1


def _deck_of(case) -> BdfModel:
    deck = case.structure.deck
    if not isinstance(deck, BdfModel):
        raise BdfError(f"{case.name}: the imported structure has no BDF record "
                       f"(structure.deck is {type(deck).__name__}): the export writes an "
                       f"imported model from the deck it was read from")
    return deck


def _imported_shell_cards(model, bdf: BdfModel) -> tuple[list[int], int]:
    """GRIDs (the deck's ids, PS 126), one MAT1 / MAT8 + PSHELL per property, CQUAD4 / CTRIA3
    with the corner thicknesses (MAT8 angle as THETA); returns (ids, next element id)."""
    ids = [int(g) for g in bdf.node_ids]
    for g, (x, y) in zip(ids, bdf.mesh.nodes):
        model.add_grid(g, [float(x), float(y), 0.0], ps="126")
    for (pid, _), mat in bdf.materials.items():
        if pid in model.properties:
            continue
        _material_card(model, pid, mat)
        sel = bdf.element_pids == pid
        model.add_pshell(pid, mid1=pid, t=float(bdf.mesh.corner_thickness[sel].max()),
                         mid2=pid, mid3=pid)
    xy = bdf.mesh.nodes[bdf.mesh.elements]
    th = bdf.mesh.corner_thickness
    for e, conn in enumerate(bdf.mesh.elements):
        pid, ang = int(bdf.element_pids[e]), float(bdf.element_angles[e])
        mat = bdf.materials.get((pid, ang))
        theta = 0.0
        if mat is not None and not isinstance(mat, Material):
            d = xy[e, 1] - xy[e, 0]
            theta = math.degrees(ang - math.atan2(d[1], d[0]))
        t = [float(v) for v in th[e]]
        if conn[2] == conn[3]:
            model.add_ctria3(e + 1, pid, [ids[c] for c in conn[:3]], theta_mcid=float(theta),
                             T1=t[0], T2=t[1], T3=t[2])
        else:
            model.add_cquad4(e + 1, pid, [ids[c] for c in conn], theta_mcid=float(theta),
                             T1=t[0], T2=t[1], T3=t[2], T4=t[3])
    return ids, bdf.mesh.n_elements + 1


def _imported_support_cards(model, bdf: BdfModel, ids, eid: int) -> int:
    """The deck's own masses and supports as read: CONM2, CELAS2, RBE2, SPC1 (SPC set 1)."""
    for i, m, X, I in bdf.masses:
        model.add_conm2(eid, ids[i], float(m), X=[float(v) for v in X],
                        I=[I[0], I[1], I[2], 0.0, 0.0, 0.0])
        eid += 1
    for a, b, k in bdf.springs:
        nb = 0 if b < 0 else ids[b // 3]
        model.add_celas2(eid, k, [ids[a // 3], nb], a % 3 + 3, 0 if b < 0 else b % 3 + 3)
        eid += 1
    for gi, cm, dep in bdf.rigid:
        model.add_rbe2(eid, ids[gi], cm, [ids[j] for j in dep])
        eid += 1
    _spc1_cards(model, ids, bdf.fixed)
    return eid


def _spc1_cards(model, ids, fixed) -> None:
    """SPC1 (set 1) per component of the fixed global DOFs (w, theta_x, theta_y -> 3, 4, 5)."""
    by_comp = {}
    for d in fixed:
        by_comp.setdefault(str(d % 3 + 3), []).append(ids[d // 3])
    for comp, nodes in sorted(by_comp.items()):
        model.add_spc1(1, comp, nodes)


def _point_mass_cards(model, case, ids, eid: int) -> int:
    """CONM2 for the case's point masses (each on a node)."""
    mesh = pl.structural_mesh(case)
    for pm in case.point_masses:
        i = mesh.node_at(pm.position, tol=1e-9 * max(float(np.ptp(mesh.nodes[:, 1])), 1.0),
                         name="point_mass position (BDF export puts a CONM2 on a node)")
        model.add_conm2(eid, ids[i], pm.mass, I=[pm.inertia[0], 0.0, pm.inertia[1], 0.0, 0.0,
                                                 0.0])
        eid += 1
    return eid


def _clamped_root_cards(model, case, ids, eid: int) -> int:
    """SPC1 345 on the root-chord nodes."""
    mesh = pl.structural_mesh(case)
    root = np.flatnonzero(np.abs(mesh.nodes[:, 1] - mesh.y_root) <= 1e-9 * mesh.span)
    model.add_spc1(1, "345", [ids[i] for i in root])
    return eid


def _edges_cards(model, case, ids, eid: int) -> int:
    """SPC1 on the DOFs the edge conditions fix (those with no column in the reduction T of
    :func:`asekit.structure.supports.planform_edge_supports`)."""
    mesh = pl.structural_mesh(case)
    K, M = pl.mass_and_stiffness(case)
    T = planform_edge_supports(mesh, K, M, **dict(case.support.edges)).T
    _spc1_cards(model, ids, np.flatnonzero(np.abs(T).sum(axis=1).A1 == 0))
    return eid


def _shaft_cards(model, case, ids, eid: int) -> int:
    """A shaft GRID held in T3 and R1 (or on a CELAS2 in R1 with ``bending_stiffness``), an
    RBE2 (CM 345) to a shaft region's nodes, the torsional spring as CELAS2 on R2 (FN1: to
    ground; FN2: to a ground GRID carrying the fictitious inertia as CONM2 I22)."""
    s, mesh = case.support, pl.structural_mesh(case)
    nn = mesh.n_nodes
    if s.radius is None:
        shaft = ids[mesh.node_at(s.axis_point, tol=1e-9 * max(mesh.span, 1.0),
                                 name="shaft axis_point")]
    else:
        shaft = nn + 1
        model.add_grid(shaft, [float(s.axis_point[0]), float(s.axis_point[1]), 0.0], ps="126")
        d = np.hypot(*(mesh.nodes - np.asarray(s.axis_point)).T)
        model.add_rbe2(eid, shaft, "345", [ids[i] for i in np.flatnonzero(d <= s.radius
                                                                           * (1 + 1e-9))])
        eid += 1
    if s.bending_stiffness is None:
        model.add_spc1(1, "34", [shaft])
    else:
        model.add_spc1(1, "3", [shaft])
        model.add_celas2(eid, s.bending_stiffness, [shaft, 0], 4, 0)
        eid += 1
    if s.model == "FN1" or not case.modes.keep_rigid:
        model.add_celas2(eid, s.torsional_stiffness, [shaft, 0], 5, 0)
        return eid + 1
    ground = nn + 2
    model.add_grid(ground, [float(s.axis_point[0]), float(s.axis_point[1]), 0.0], ps="12346")
    _, Mp = pl.mass_and_stiffness(case)
    i_f = s.fictitious_inertia_factor * pitch_inertia(mesh, Mp, s.axis_point[0])
    model.add_celas2(eid, s.torsional_stiffness, [shaft, ground], 5, 5)
    model.add_conm2(eid + 1, ground, 0.0, I=[0.0, 0.0, i_f, 0.0, 0.0, 0.0])
    return eid + 2


def _partial_cards(model, case, ids, eid: int) -> int:
    """``support.kind = "partial"`` (:func:`asekit.structure.supports.partial_support_nodes`):
    SPC1 345 on the held grids (clamped), SPC1 3 (pinned), or CELAS2 to ground on DOFs 3, 4, 5
    with k_w, k_theta_x, k_theta_y (springs; a zero stiffness writes no card)."""
    s, mesh = case.support, pl.structural_mesh(case)
    ranges = [(e, s.option(e)) for e in PLANFORM_EDGES if s.option(e) is not None]
    nodes = partial_support_nodes(mesh, s.option("points", ()), ranges)
    condition = s.option("condition", "clamped")
    if condition != "springs":
        model.add_spc1(1, "345" if condition == "clamped" else "3", [ids[i] for i in nodes])
        return eid
    for i in nodes:
        for c, k in zip((3, 4, 5), s.option("springs")):
            if k > 0.0:
                model.add_celas2(eid, float(k), [ids[i], 0], c, 0)
                eid += 1
    return eid


#: The BDF cards of each support kind of a case (``case.support.kind``).
SUPPORT_CARDS = {"clamped_root": _clamped_root_cards, "edges": _edges_cards,
                 "shaft": _shaft_cards, "partial": _partial_cards}


def _support_cards(model, case, ids, eid: int) -> int:
    if case.structure is not None:
        return _imported_support_cards(model, _deck_of(case), ids, eid)
    kind = case.support.kind
    if kind not in SUPPORT_CARDS:
        raise BdfError(f"support.kind = {kind!r} has no BDF export (known: "
                       f"{', '.join(sorted(SUPPORT_CARDS))})")
    return SUPPORT_CARDS[kind](model, case, ids, eid)


def _panel_aero_cards(model, case, nn: int) -> None:
    """One CAERO1 (PAERO1) per panel with the case's boxes, SPLINE1 on all grids."""
    boxes = pl.box_mesh(case)
    start = 100001
    model.add_paero1(1)
    for ip, p in enumerate(case.panels):
        sel = boxes.surface == ip
        nc = int(np.sum(boxes.strip[sel] == boxes.strip[sel][0]))
        ns = int(sel.sum() // nc)
        pf = p.planform
        model.add_caero1(start, 1, 1, [pf.root_le[0], pf.root_le[1], 0.0],
                         pf.root_chord, [pf.tip_le[0], pf.tip_le[1], 0.0], pf.tip_chord,
                         nspan=ns, nchord=nc)
        model.add_set1(start, list(range(1, nn + 1)))
        model.add_spline1(start, start, start, start + ns * nc - 1, start)
        start += 10 ** int(math.ceil(math.log10(ns * nc + 1)) + 1)


#: first id of the hinge systems (CORD2R), AELISTs and AESURFs the export writes
_AESURF_ID0 = 501


def _check_caero1_mesh(hm, case) -> None:
    """The hinged boxes must be one CAERO1: the same chord fractions in every strip."""
    m = hm.mesh
    nc = int(np.sum(m.strip == m.strip[0]))
    g = m.corners.reshape(-1, nc, 4, 3)
    xi = (g[:, :, 1, 0] - g[:, :1, 0, 0]) / (g[:, -1:, 1, 0] - g[:, :1, 0, 0])
    if np.ptp(xi, axis=0).max() > 1e-9:
        h = [list(c.hinge_chord_fraction) for c in case.control_surfaces]
        raise ValueError(f"control_surface[].hinge_chord_fraction {h}: the export writes one "
                         f"CAERO1 with AESURF boxes, which needs one constant hinge chord "
                         f"fraction for every surface (inboard = outboard)")


def _aesurf_labels(case) -> list[str]:
    """The surfaces' names as AESURF LABELs (capitals), each a Nastran label: 1-8 letters,
    digits or underscores, a letter first, unique."""
    out = []
    for i, c in enumerate(case.control_surfaces):
        lab = c.name.upper()
        if not (1 <= len(lab) <= 8 and lab[0].isalpha() and lab.isascii()
                and lab.replace("_", "").isalnum()) or lab in out:
            raise ValueError(f"control_surface[{i}].name {c.name!r} is not a Nastran AESURF "
                             f"LABEL for the export: 1-8 letters, digits or underscores, a "
                             f"letter first, unique without case")
        out.append(lab)
    return out


def _control_surface_cards(model, case, ids) -> None:
    """The control surfaces as Nastran's (MSC QRG AESURF): the hinged boxes
    (:func:`asekit.case.pipeline.control_surface_mesh`) as one CAERO1 (AEFACT divisions),
    and per surface a CORD2R whose y axis is the hinge line (origin at its inboard end, y
    outboard, x aft in the plane, z up: a positive deflection is trailing edge down, asekit's
    sense), an AELIST of its boxes and an AESURF (CREFC its mean chord aft of the hinge,
    CREFS its area). AESURF has no hinge stiffness, damping or balance field: those are not
    written (a re-import has a free hinge). AESURFS (the structural grids of a separately
    modelled surface) does not apply to asekit's rigid surfaces and is not written. A surface
    geared to another (``linked_to``, ``gear_ratio``) is an AELINK ALWAYS (LABLD the geared
    surface, LABL1 its master, C1 the gear ratio). Elastic surfaces are refused (the plate
    is not released along the hinge in the export)."""
    labels = _aesurf_labels(case)
    for i, c in enumerate(case.control_surfaces):
        if c.kind != "rigid":
            raise ValueError(f"control_surface[{i}].kind = {c.kind!r}: the export writes AESURF "
                             f"(a rigid surface on the plate's boxes) and does not release the "
                             f"plate along the hinge, so the deck would hold a different "
                             f"structure; export a case whose surfaces are kind = \"rigid\"")
    hm = pl.control_surface_mesh(case)
    _check_caero1_mesh(hm, case)
    eid0 = 100001
    _aero_cards(model, hm.mesh, eid0, ids)
    for i, s in enumerate(hm.surfaces):
        sid = _AESURF_ID0 + i
        p = hm.hinge_point[i]
        y = hm.hinge_axis[i]
        x = np.array([y[1], -y[0], 0.0]) / math.hypot(y[0], y[1])
        model.add_cord2r(sid, [float(v) for v in p], [float(v) for v in p + [0, 0, 1]],
                         [float(v) for v in p + x])
        model.add_aelist(sid, [eid0 + int(b) for b in np.flatnonzero(hm.on_surface[i])])
        model.add_aesurf(sid, labels[i], sid, sid, crefc=hm.mean_chord(i),
                         crefs=hm.surface_area(i))
    names = [c.name for c in case.control_surfaces]
    for i, c in enumerate(case.control_surfaces):     # a geared surface: AELINK (issue 25)
        if c.linked_to:
            model.add_aelink("ALWAYS", labels[i], [labels[names.index(c.linked_to)]],
                             [float(c.gear_ratio)])


def _flutter_cards(model, case, ids) -> None:
    """Boxes (per panel, or the imported ones with AEFACT where not uniform), AERO (REFC =
    2 b, RHOREF = 1 so the FLFACT densities are in kg/m^3), MKAERO1 over the case's Mach and
    k, FLFACT densities / Machs / velocities and FLUTTER 20 (PK)."""
    a = case.aero
    if case.control_surfaces:
        _control_surface_cards(model, case, ids)
    elif case.structure is not None:
        _aero_cards(model, pl.box_mesh(case), 100001, ids)
    else:
        _panel_aero_cards(model, case, len(ids))
    model.add_aero(None, 2.0 * a.reference_semichord, 1.0,
                   sym_xz=1 if a.symmetry == "wall" else 0)
    _mkaero_cards(model, list(a.machs), [float(k) for k in pl.reduced_frequencies(case)])
    model.add_flfact(1, [c.density for c in pl.flight_conditions(case)])
    model.add_flfact(2, list(a.machs))
    model.add_flfact(3, list(case.flight.velocities))
    model.add_flutter(20, "PK", 1, 2, 3, imethod="L")


def _damping_table(case):
    """(frequencies Hz, values, TYPE) of the case's damping as a TABDMP1, or None: the case's
    ``damping`` (constant: two points; per mode: a point at each mode), else an imported
    structure's own table (G)."""
    d = case.damping
    if d.modal_damping_ratio is None and d.structural_g is None:
        if case.structure is not None and case.structure.damping_g:
            f, g = zip(*case.structure.damping_g)
            return list(f), list(g), "G"
        return None
    ref = pl.modal_model(case)
    f = ref.frequencies_hz[ref.n_rigid:]
    kind = "G" if d.structural_g is not None else "CRIT"
    v = d.structural_g if d.structural_g is not None else d.modal_damping_ratio
    g = np.broadcast_to(np.asarray(v, float), f.shape)
    if np.ptp(g) == 0:
        return [0.0, 1.0e5], [float(g[0])] * 2, kind
    return list(map(float, f)), list(map(float, g)), kind          # a table through each mode


def _export_sol(case, sol):
    if sol is None:
        sol = 145 if case.aero is not None and case.flight is not None else 103
    if sol not in (103, 145):
        raise ValueError(f"sol must be 103 or 145, got {sol!r}")
    if sol == 145 and (case.aero is None or case.flight is None):
        raise ValueError(f"sol = 145 needs the case's aero and flight ({case.name} has "
                         f"{'no aero' if case.aero is None else 'no flight conditions'}); "
                         f"use sol = 103")
    return sol


def case_bdf(case, sol: int | None = None, n_modes: int | None = None):
    """The case as a pyNastran ``BDF`` object (SI units: m, kg, s, N).

    Structure: one GRID per node (PS = 126: the in-plane DOFs, uncoupled from bending, are
    held), one CQUAD4 per element with its corner thicknesses T1-T4 from the case's
    thickness law, PSHELL (MID1 = MID2 = MID3) and MAT1 or MAT8 (material angle THETA from the
    G1-G2 edge), CONM2 for point masses at nodes. Supports by kind (:data:`SUPPORT_CARDS`):
    SPC1 for a clamped root or for the DOFs edge conditions fix; a shaft as a shaft GRID held
    in T3 and R1 (or on a CELAS2 in R1 with ``bending_stiffness``), an RBE2 (CM 345) to the
    nodes of a shaft region, the torsional spring as CELAS2 on R2 (FN1: to ground; FN2: to a
    ground GRID carrying the fictitious inertia as CONM2 I22). A case with an imported
    structure (:func:`read_bdf`) is written with the deck's GRID ids, properties, CTRIA3 /
    CQUAD4, CONM2, CELAS2, RBE2 and SPC1 as read (in SI), its boxes with AEFACT where not
    uniform. Aerodynamics: one CAERO1 (PAERO1) per panel with the case's boxes, SPLINE1 (IPS)
    on all grids, AERO (REFC = 2 b, RHOREF = 1 so the FLFACT densities are in kg/m^3),
    MKAERO1 over the case's Mach and k, FLFACT densities / Machs / velocities and FLUTTER
    (PK); with ``control_surfaces`` the hinged boxes as one CAERO1 and per surface CORD2R +
    AELIST + AESURF (:func:`_control_surface_cards`; ValueError for a hinge whose chord
    fraction changes along the span). Case control: SOL 103 (METHOD = EIGRL) or SOL 145 (also FMETHOD); ``sol`` None:
    145 when the case has aero and flight conditions, else 103.
    """
    from pyNastran.bdf.case_control_deck import CaseControlDeck
    BDF = need_pynastran()
    sol = _export_sol(case, sol)
    model = BDF(debug=None)
    if case.structure is not None:
        ids, eid = _imported_shell_cards(model, _deck_of(case))
    else:
        ids, eid = _plate_cards(model, case)
    eid = _point_mass_cards(model, case, ids, eid)
    _support_cards(model, case, ids, eid)
    if case.structure is None or _deck_of(case).coupled_mass:
        model.add_param("COUPMASS", [1])      # asekit's plate mass is the consistent one
    nmod = n_modes if n_modes is not None else case.modes.count
    model.add_eigrl(10, v1=None if nmod else -1.0e-3,
                    v2=None if nmod else float(case.modes.f_max), nd=nmod)
    lines = [f"TITLE = {case.name} (asekit export, SI: m kg s N)", "ECHO = NONE", "SPC = 1",
             "METHOD = 10", "DISP = ALL"]
    if sol == 145:
        _flutter_cards(model, case, ids)
        lines.insert(4, "FMETHOD = 20")
    tab = _damping_table(case)
    if tab is not None:
        model.add_tabdmp1(30, np.array(tab[0]), np.array(tab[1]), Type=tab[2])
        lines.append("SDAMP = 30")
    model.sol = sol
    model.case_control_deck = CaseControlDeck(lines + ["BEGIN BULK"])
    return model


def write_case_bdf(case, path, sol: int | None = None, n_modes: int | None = None) -> Path:
    """Write :func:`case_bdf` to ``path`` in large (16-character) fields; returns the path."""
    model = case_bdf(case, sol=sol, n_modes=n_modes)
    path = Path(path)
    model.write_bdf(str(path), size=16, elements_size=8, is_double=False, enddata=True)
    return path


def _aero_cards(model, boxes: BoxMesh, eid0: int, set_nodes: list[int]):
    """CAERO1 / PAERO1 / SPLINE1 / SET1 (AEFACT when the divisions are not uniform) of each
    surface of a structured box mesh."""
    model.add_paero1(1)
    model.add_set1(eid0, set_nodes)
    start = eid0
    aef = 1
    for i in range(len(boxes.surface_names)):
        r_le, r_c, t_le, t_c, nc, ns, xi, eta = _surface_geometry(boxes, i)
        kw = {}
        if np.allclose(xi, np.linspace(0, 1, nc + 1), atol=1e-9):
            kw["nchord"] = nc
        else:
            model.add_aefact(aef, list(xi))
            kw["lchord"], aef = aef, aef + 1
        if np.allclose(eta, np.linspace(0, 1, ns + 1), atol=1e-9):
            kw["nspan"] = ns
        else:
            model.add_aefact(aef, list(eta))
            kw["lspan"], aef = aef, aef + 1
        model.add_caero1(start, 1, 1, [float(v) for v in r_le], float(r_c),
                         [float(v) for v in t_le], float(t_c), **kw)
        model.add_spline1(start, start, start, start + ns * nc - 1, eid0)
        start += 10 ** int(math.ceil(math.log10(ns * nc + 1)) + 1)


def bdf_model_deck(bdf):
    """A read deck (:class:`BdfModel`, or the case :func:`read_bdf` gives) as a pyNastran
    ``BDF`` (SI units): :func:`case_bdf` of its case."""
    return case_bdf(deck_case(bdf) if isinstance(bdf, BdfModel) else bdf)


def write_bdf_model(bdf, path) -> Path:
    """Write :func:`bdf_model_deck` to ``path`` in large fields; returns the path."""
    path = Path(path)
    bdf_model_deck(bdf).write_bdf(str(path), size=16, elements_size=8, is_double=False,
                                  enddata=True)
    return path


def read_f06_eigenvalues(path) -> np.ndarray:
    """Natural frequencies (Hz, the CYCLES column) of the first REAL EIGENVALUES table of a
    Nastran f06, keeping the modes with a non-zero generalized mass (Nastran prints 0.0 for
    the modes beyond those it normalised and recovered). Raises ValueError without a table."""
    lines = Path(path).read_text(errors="replace").splitlines()
    try:
        i = next(j for j, line in enumerate(lines) if "R E A L   E I G E N V A L U E S" in line)
    except StopIteration:
        raise ValueError(f"{path}: no REAL EIGENVALUES table") from None
    out = []
    for line in lines[i + 1:]:
        f = line.split()
        if not f or not f[0].isdigit():
            if out:
                break
            continue
        if len(f) != 7:
            break
        if float(f[5]) > 0:
            out.append(float(f[4]))
    if not out:
        raise ValueError(f"{path}: the REAL EIGENVALUES table has no mode with a mass")
    return np.array(out)
