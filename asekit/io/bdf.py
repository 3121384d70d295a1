"""Nastran bulk data (BDF) in and out, through pyNastran.

Import (:func:`read_bdf`): a flat plate-wing deck becomes an asekit model built with asekit's
own finite elements (MITC4, :mod:`asekit.structure.plate`) and its own doublet lattice
(:mod:`asekit.aero.dlm`) -- not Nastran's matrices -- so that a user can compare the two codes.
Export (:func:`write_case_bdf`): a case's structural model and boxes as a deck that pyNastran
reads and Nastran runs (SOL 103 or SOL 145 case control).

Supported cards and what asekit makes of them
---------------------------------------------
GRID (basic or CORD2R/CORD1R... any coordinate system pyNastran resolves; ``PS`` permanent
constraints), CQUAD4 (corner thicknesses T1-T4; material angle THETA or MCID) with PSHELL
(MID1 = MID2, 12I/T^3, NSM), MAT1, MAT8, CONM2 (mass, offset ignored in-plane, I11 and I22),
SPC / SPC1, CELAS1 (PELAS) / CELAS2 springs to ground or between grids, RBE2 (a rigid region,
e.g. the shaft), CAERO1 with PAERO1 (NSPAN/NCHORD or AEFACT LSPAN/LCHORD divisions),
SPLINE1 / SPLINE4 with SET1 / AELIST (checked: every box must be splined), AERO / AEROS (REFC,
RHOREF, SYMXZ), MKAERO1, FLFACT, FLUTTER (PK, PKNL), EIGR / EIGRL (number of modes or the
frequency range), TABDMP1 (G or CRIT modal damping), PARAM WTMASS. CTRIA3 is modelled as a
degenerated MITC4 (its third node repeated: a collapsed quadrilateral, Bathe, *Finite Element
Procedures*, 1996, Ch. 5), stiffer than the quadrilateral on coarse meshes but convergent
(tests/io/test_bdf.py: NAFEMS FV16). Solids, beams, bars, rods and other shells are refused with
the list of what is missing. Every other card (e.g. ASET1, PARAM COUPMASS, plot cards) is
listed in one :class:`UnsupportedCardWarning` (name, count, first id) and otherwise ignored.

What asekit models: the out-of-plane bending of a flat plate in the plane z = z0 (degrees of
freedom T3, R1, R2 of each GRID = asekit's w, theta_x, theta_y; the in-plane DOFs 1, 2, 6 are
uncoupled from bending for a flat plate and are dropped). Differences from Nastran a user should
expect: asekit's plate is Reissner-Mindlin with consistent translational *and* rotary inertia
(Nastran's CQUAD4 mass has no rotary inertia; PSHELL MID3 blank makes Nastran's plate
Kirchhoff); ASET1 (Guyan reduction) is ignored, so asekit solves the full model; asekit
interpolates the modes onto the boxes with its finite-element shape functions, not with the
deck's SPLINE1/SPLINE4 surface spline.

Units: a BDF has no units. ``units`` names the deck's consistent system and every quantity is
converted to SI on import: ``"SI"`` (m, kg, s, N), ``"mm-t-s"`` (mm, tonne, s, N) and
``"in-lbf-s"`` (in, lbf s^2/in, s, lbf; PARAM WTMASS converts the deck's mass input to it).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from asekit.aero.boxes import BoxMesh
from asekit.geometry import Material, OrthotropicMaterial
from asekit.structure.assembly import SupportedSystem, element_dofs
from asekit.structure.mesh import PlateMesh
from asekit.structure.plate import DOF_PER_NODE, consistent_mass, mitc4_stiffness

#: length, mass and time of one deck unit in SI (m, kg, s).
UNITS = {"SI": (1.0, 1.0, 1.0), "mm-t-s": (1e-3, 1e3, 1.0),
         "in-lbf-s": (0.0254, 4.4482216152605 / 0.0254, 1.0)}

#: Cards asekit reads (see the module docstring).
SUPPORTED_CARDS = ("GRID", "CORD2R", "CORD1R", "CORD2C", "CORD2S", "CQUAD4", "CTRIA3", "PSHELL",
                   "MAT1",
                   "MAT8", "CONM2", "SPC", "SPC1", "CELAS1", "CELAS2", "PELAS", "RBE2",
                   "CAERO1", "PAERO1", "AEFACT", "SPLINE1", "SPLINE4", "SET1", "AELIST", "AERO",
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
_USED_PARAMS = ("WTMASS",)


class UnsupportedCardWarning(UserWarning):
    """Cards of a BDF that asekit read but does not represent (listed once per import)."""


class BdfError(ValueError):
    """A BDF that asekit cannot represent; the message lists what is missing."""


def _need_pynastran():
    try:
        from pyNastran.bdf.bdf import BDF
    except ImportError as exc:                                    # pragma: no cover
        raise ImportError("asekit.io.bdf needs pyNastran: pip install 'asekit[nastran]' "
                          "(see environment.txt)") from exc
    return BDF


# ---------------------------------------------------------------------------------------------
# the imported model
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FlutterRequest:
    """A FLUTTER card resolved to SI: ``method`` (PK / PKNL), ``densities`` (kg/m^3),
    ``machs``, ``velocities`` (m/s, absolute values); for PK every combination of density x
    Mach is swept over the velocities, for PKNL the three lists are matched point by point."""

    sid: int
    method: str
    densities: tuple[float, ...]
    machs: tuple[float, ...]
    velocities: tuple[float, ...]


@dataclass(frozen=True)
class BdfModel:
    """A plate-wing deck as an asekit model (SI).

    mesh : the plate mesh over all GRIDs (nodes that no element uses carry only springs,
        masses or rigid links); node_ids : (n_nodes,) the GRID id of each node.
    K, M : global sparse stiffness and mass (3 DOFs per node: w, theta_x, theta_y), springs
        (CELAS) in K and point masses (CONM2) and NSM in M.
    system : the supported system (SPC, GRID PS and RBE2 eliminated) for the eigen-analysis.
    boxes : the doublet-lattice boxes of the CAERO1 cards (None without aero); box_ids the
        Nastran box ids; b_ref : reference semichord REFC / 2 (m); rho_ref (kg/m^3);
        symmetric : SYMXZ = 1 (a wall at y = 0).
    machs, reduced_frequencies : the MKAERO1 grid (all pairs); flutter : the FLUTTER requests.
    n_modes, f_max_hz : from EIGR / EIGRL (None when absent); damping_g : (frequency Hz,
        g) table from TABDMP1 (CRIT converted to g = 2 zeta) or None.
    materials : {(pid, material angle rad): material}; element_pids, element_angles :
        (n_elem,) property id and material 1-axis angle (rad from +x) of each element;
        springs : (dof a, dof b or -1 for ground, k SI) in global DOF numbers; masses :
        (node index, mass kg, offset (3,) m, (I11, I21, I22) kg m^2); fixed : the constrained
        global DOFs; rigid : (independent node index, component string, dependent node
        indices) per RBE2; ignored : the (card, count, first id) left out; notes.
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
    materials: dict = field(default_factory=dict)
    element_pids: np.ndarray | None = None
    element_angles: np.ndarray | None = None
    springs: tuple = ()
    masses: tuple = ()
    fixed: tuple = ()
    rigid: tuple = ()
    ignored: tuple[tuple[str, int, object], ...] = ()
    notes: tuple[str, ...] = ()

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
            for name in sorted(model.params):
                if name not in _USED_PARAMS:
                    ignored.append((f"PARAM {name}", 1, None))
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
    out = []
    for ch in str(c if c is not None else ""):
        if ch in "345":
            out.append("345".index(ch))
    return out


def _material(mat, wtmass: float, L: float, Mu: float, T: float, angle: float, pid: int):
    """asekit material of a MAT1 / MAT8 in SI (stress F / L^2, density m / L^3)."""
    stress = Mu / (L * T * T)                       # force / area in SI per deck unit
    dens = Mu / L**3
    if mat.type == "MAT1":
        E, G, nu = mat.e, mat.g, mat.nu
        if E is None or E <= 0:
            raise BdfError(f"MAT1 {mat.mid} (PSHELL {pid}): E must be > 0, got {E}")
        if nu is None:
            nu = E / (2 * G) - 1.0
        elif G is not None and abs(G - E / (2 * (1 + nu))) > 1e-3 * G:
            raise BdfError(f"MAT1 {mat.mid}: E, G and NU all given and G = {G:g} differs from "
                           f"E / (2 (1 + NU)) = {E / (2 * (1 + nu)):g}: asekit's isotropic "
                           f"material takes E and NU (give two of the three)")
        return Material(E * stress, nu, mat.rho * wtmass * dens, name=f"MAT1 {mat.mid}")
    if mat.type == "MAT8":
        g1z = mat.g1z if mat.g1z else mat.g12
        g2z = mat.g2z if mat.g2z else mat.g12
        return OrthotropicMaterial(mat.e11 * stress, mat.e22 * stress, mat.g12 * stress,
                                   mat.nu12, mat.rho * wtmass * dens, g1z * stress,
                                   g2z * stress, angle, name=f"MAT8 {mat.mid}")
    raise BdfError(f"PSHELL {pid}: material {mat.type} {mat.mid} is not supported "
                   f"(MAT1 or MAT8)")


def _scatter(mesh: PlateMesh, Ke: np.ndarray, n: int) -> sp.csr_matrix:
    dofs = element_dofs(mesh)
    rows = np.repeat(dofs, 12, axis=1).ravel()
    cols = np.tile(dofs, (1, 12)).ravel()
    A = sp.csr_matrix((Ke.ravel(), (rows, cols)), shape=(n, n))
    return (0.5 * (A + A.T)).tocsr()


def _element_angle(elem, xyz_of, g1, g2, model) -> float:
    """Material 1-axis angle from +x (rad) of a CQUAD4: THETA (deg) from the G1-G2 edge, or
    the projection of the MCID system's x axis."""
    tm = elem.theta_mcid
    d = xyz_of(g2) - xyz_of(g1)
    edge = math.atan2(d[1], d[0])
    if isinstance(tm, int):
        cs = model.coords[tm]
        ax = np.asarray(cs.i, float)
        return math.atan2(ax[1], ax[0])
    return edge + math.radians(float(tm or 0.0))


def read_bdf(path, units: str = "SI", tol: float | None = None,
             thickness_rule: str = "gauss") -> BdfModel:
    """Read a flat plate-wing BDF with pyNastran and build the asekit model.

    Parameters
    ----------
    path : the deck (executive and case control optional).
    units : the deck's unit system, a key of :data:`UNITS` (``"SI"``, ``"mm-t-s"``,
        ``"in-lbf-s"``); everything is converted to SI.
    tol : flatness tolerance in deck length units (default 1e-6 x the model size).
    thickness_rule : ``"gauss"`` (default: the corner thicknesses T1-T4 interpolated
        bilinearly to every integration point) or ``"centroid"`` (each element at its mean
        corner thickness, constant over the element).

    Returns
    -------
    BdfModel. Raises :class:`BdfError` (a ValueError) for a deck asekit cannot represent
    (refused cards listed); warns :class:`UnsupportedCardWarning` once, listing every card
    that was read but is not represented (name, count, first id).
    """
    if units not in UNITS:
        raise ValueError(f"units must be one of {sorted(UNITS)}, got {units!r}")
    L, Mu, T = UNITS[units]
    BDF = _need_pynastran()
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"BDF not found: {path}")
    model = BDF(debug=None)
    text = path.read_text(errors="replace").upper()
    punch = "BEGIN BULK" not in text
    model.read_bdf(str(path), punch=punch, xref=True)
    refused, ignored = _card_report(model)
    if refused:
        raise BdfError(f"{path.name}: asekit cannot represent these cards: {_fmt(refused)}. "
                       f"It models a flat plate of CQUAD4 / CTRIA3 elements (PSHELL, "
                       f"MAT1/MAT8) with CONM2, CELAS1/2, RBE2 and SPC supports (CTRIA3 as a "
                       f"degenerated MITC4).")
    notes = []
    wt = model.params.get("WTMASS")
    wtmass = float(wt.values[0]) if wt is not None else 1.0

    # ---- grids -------------------------------------------------------------------------
    quads = [e for e in model.elements.values() if e.type in ("CQUAD4", "CTRIA3")]
    if not quads:
        raise BdfError(f"{path.name}: no CQUAD4 or CTRIA3 element: nothing asekit can model")
    is_tri = np.array([e.type == "CTRIA3" for e in quads])
    nids = np.array(sorted(model.nodes), dtype=np.int64)
    bad_cd = [int(n) for n in nids if model.nodes[n].cd not in (0, None)]
    if bad_cd:
        raise BdfError(f"GRIDs {bad_cd[:10]} have a displacement coordinate system CD != 0: "
                       f"asekit needs T3, R1, R2 along the basic z, x, y axes")
    xyz = np.array([model.nodes[n].get_position() for n in nids], float)
    index = {int(n): i for i, n in enumerate(nids)}
    size = float(np.ptp(xyz[:, :2], axis=0).max())
    tol = 1e-6 * size if tol is None else float(tol)
    plate_nodes = sorted({n for e in quads for n in e.node_ids})
    z0 = _plane(xyz[[index[n] for n in plate_nodes]], tol)
    nodes = xyz[:, :2] * L

    # ---- elements, thickness, materials --------------------------------------------------
    # a CTRIA3 is a degenerated MITC4 with its third node repeated (G1 G2 G3 G3)
    conn = np.array([[index[n] for n in (list(e.node_ids) + [e.node_ids[2]])[:4]]
                     for e in quads], dtype=np.int64)
    xy = nodes[conn]
    area2 = ((xy[:, 2, 0] - xy[:, 0, 0]) * (xy[:, 3, 1] - xy[:, 1, 1])
             - (xy[:, 3, 0] - xy[:, 1, 0]) * (xy[:, 2, 1] - xy[:, 0, 1]))
    flip = area2 < 0
    th = np.zeros((len(quads), 4))
    angles = np.zeros(len(quads))
    pids = np.array([e.pid for e in quads])
    props = {}
    for j, e in enumerate(quads):
        p = model.properties[e.pid]
        if p.type != "PSHELL":
            raise BdfError(f"CQUAD4 {e.eid}: property {p.type} {e.pid} is not supported "
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
            raise BdfError(f"CQUAD4 {e.eid}: ZOFFS = {e.zoffset} is not supported")
        props[e.pid] = p
        t = [e.T1, e.T2, e.T3, e.T3] if is_tri[j] else [e.T1, e.T2, e.T3, e.T4]
        if getattr(e, "tflag", 0) == 1:
            t = [(v if v is not None else 1.0) * p.t for v in t]
        th[j] = [p.t if v is None or v < 0 else v for v in t]
        angles[j] = _element_angle(e, lambda g: xyz[index[g]], e.node_ids[0], e.node_ids[1],
                                   model)
    fq, ft = flip & ~is_tri, flip & is_tri
    conn[fq] = conn[fq][:, ::-1]
    th[fq] = th[fq][:, ::-1]
    conn[ft] = conn[ft][:, [0, 2, 1, 1]]
    th[ft] = th[ft][:, [0, 2, 1, 1]]
    if flip.any():
        notes.append(f"{int(flip.sum())} elements numbered clockwise seen from +z were "
                     f"renumbered (same element)")
    if is_tri.any():
        notes.append(f"{int(is_tri.sum())} CTRIA3 modelled as degenerated MITC4 (G3 repeated; "
                     f"Bathe, Finite Element Procedures, 1996, Ch. 5: collapsed "
                     f"quadrilaterals; less accurate than the quadrilateral)")
    th = th * L
    mids3 = {p.pid: p.mid3 for p in props.values()}
    if any(m is None for m in mids3.values()):
        notes.append("PSHELL MID3 blank (Nastran: no transverse shear flexibility, Kirchhoff "
                     "plate); asekit's plate is Reissner-Mindlin with G from the material -- "
                     "negligible for a thin plate")
    n = DOF_PER_NODE * nodes.shape[0]
    K = sp.csr_matrix((n, n))
    M = sp.csr_matrix((n, n))
    materials = {}
    span = max(float(np.ptp(nodes[:, 1])), 1e-12)
    # group elements by property and (for MAT8) material angle
    keys = {}
    for j in range(len(quads)):
        mat = props[pids[j]].mid2_ref if hasattr(props[pids[j]], "mid2_ref") else None
        mat = mat if mat is not None else model.materials[props[pids[j]].mid2]
        ang = round(float(angles[j]), 9) if mat.type == "MAT8" else 0.0
        keys.setdefault((int(pids[j]), ang), []).append(j)
    for (pid, ang), idx in keys.items():
        p = props[pid]
        mat = model.materials[p.mid2]
        material = _material(mat, wtmass, L, Mu, T, ang, pid)
        materials[(pid, ang)] = material
        idx = np.asarray(idx)
        sub = PlateMesh(nodes=nodes, elements=conn[idx], thickness_root=1.0, thickness_tip=1.0,
                        y_root=float(nodes[:, 1].min()), span=span, corner_thickness=th[idx])
        K = K + _scatter(sub, mitc4_stiffness(sub, material, thickness_rule), n)
        M = M + _scatter(sub, consistent_mass(sub, material, thickness_rule), n)
        nsm = float(p.nsm or 0.0) * wtmass * Mu / L**2
        if nsm:
            # non-structural mass per area: translational only (Nastran's NSM)
            me = consistent_mass(sub, Material(1.0, 0.3, 1.0))
            h = sub.corner_thickness.mean(axis=1)
            me[:, 1::3, :] = 0.0
            me[:, :, 1::3] = 0.0
            me[:, 2::3, :] = 0.0
            me[:, :, 2::3] = 0.0
            # consistent_mass integrates rho h: rescale to nsm per unit area
            me *= (nsm / h)[:, None, None]
            M = M + _scatter(sub, me, n)
    mesh = PlateMesh(nodes=nodes, elements=conn, thickness_root=float(th.max()),
                     thickness_tip=float(th.max()), y_root=float(nodes[:, 1].min()), span=span,
                     corner_thickness=th)

    # ---- springs and masses ---------------------------------------------------------------
    Kx = sp.lil_matrix((n, n))
    Mx = sp.lil_matrix((n, n))
    dropped_springs = []
    springs, masses, rigid = [], [], []
    for e in model.elements.values():
        if e.type not in ("CELAS1", "CELAS2"):
            continue
        k = float(e.k if e.type == "CELAS2" else model.properties[e.pid].k)
        rot = [c in (4, 5) for c in (e.c1, e.c2)]
        dofs = []
        for nid, c in zip(e.node_ids, (e.c1, e.c2)):
            if nid in (None, 0) or c in (None, 0):
                dofs.append(None)
                continue
            comp = _components(c)
            dofs.append(None if not comp else DOF_PER_NODE * index[nid] + comp[0])
            if not comp:
                dropped_springs.append(e.eid)
        scale = Mu * L * L / (T * T) if any(rot) else Mu / (T * T)
        if rot[0] != rot[1] and all(d is not None for d in dofs):
            raise BdfError(f"CELAS {e.eid} couples a translation and a rotation: not supported")
        k *= scale
        a, b = dofs
        if a is None and b is None:
            continue
        if a is None:
            a, b = b, None
        springs.append((int(a), -1 if b is None else int(b), float(k)))
        if a is not None:
            Kx[a, a] += k
        if b is not None:
            Kx[b, b] += k
        if a is not None and b is not None:
            Kx[a, b] -= k
            Kx[b, a] -= k
    if dropped_springs:
        notes.append(f"CELAS {dropped_springs[:5]}... on in-plane DOFs (1, 2, 6) ignored: "
                     f"uncoupled from bending" if len(dropped_springs) > 5 else
                     f"CELAS {dropped_springs} on in-plane DOFs (1, 2, 6) ignored: uncoupled "
                     f"from bending")
    for m in model.masses.values():
        if m.type != "CONM2":
            continue
        i = index[m.nid]
        if m.cid not in (0, -1, None):
            raise BdfError(f"CONM2 {m.eid}: CID = {m.cid} is not supported (basic only)")
        mass = float(m.mass) * wtmass * Mu
        X = np.asarray(m.X if m.X is not None else np.zeros(3), float) * L
        I = np.asarray(m.I, float) * wtmass * Mu * L * L
        masses.append((i, mass, X.copy(), (float(I[0]), float(I[1]), float(I[2]))))
        d = DOF_PER_NODE * i
        # mass at offset (dx, dy): w_m = w + theta_x dy - theta_y dx (rigid offset)
        r = np.array([1.0, X[1], -X[0]])
        Mx[d:d + 3, d:d + 3] += mass * np.outer(r, r)
        Mx[d + 1, d + 1] += I[0] + mass * X[2] ** 2
        Mx[d + 2, d + 2] += I[2] + mass * X[2] ** 2
        Mx[d + 1, d + 2] -= I[1]
        Mx[d + 2, d + 1] -= I[1]
    K = (K + Kx.tocsr()).tocsr()
    M = (M + Mx.tocsr()).tocsr()

    # ---- constraints: GRID PS, SPC/SPC1 (all sets), RBE2 -----------------------------------
    fixed = set()
    for nid, g in model.nodes.items():
        for c in _components(g.ps):
            fixed.add(DOF_PER_NODE * index[nid] + c)
    spc_ids = sorted(model.spcs)
    cc_spc = _case_value(model, "SPC")
    if cc_spc is not None and cc_spc in model.spcs:
        spc_ids = [cc_spc]
    elif len(spc_ids) > 1:
        notes.append(f"several SPC sets {spc_ids} and no SPC = in the case control: all applied")
    for sid in spc_ids:
        for c in model.spcs[sid]:
            if c.type == "SPC1":
                for nid in c.node_ids:
                    for k in _components(c.components):
                        fixed.add(DOF_PER_NODE * index[nid] + k)
            elif c.type == "SPC":
                for nid, comp, val in zip(c.node_ids, c.components, c.enforced):
                    if val:
                        raise BdfError(f"SPC {sid}: enforced displacement {val} is not "
                                       f"supported")
                    for k in _components(comp):
                        fixed.add(DOF_PER_NODE * index[nid] + k)
            else:
                raise BdfError(f"{c.type} {sid} is not supported (SPC, SPC1)")
    dep = {}
    for r in model.rigid_elements.values():
        if r.type != "RBE2":
            raise BdfError(f"{r.type} {r.eid} is not supported (RBE2 only)")
        gi = index[r.gn]
        rigid.append((gi, "".join(str(k + 3) for k in _components(r.cm)),
                      tuple(index[g] for g in r.Gmi_node_ids)))
        for gm in r.Gmi_node_ids:
            j = index[gm]
            dx, dy = nodes[j] - nodes[gi]
            rows = {0: {0: 1.0, 1: dy, 2: -dx}, 1: {1: 1.0}, 2: {2: 1.0}}
            for k in _components(r.cm):
                dep[DOF_PER_NODE * j + k] = {DOF_PER_NODE * gi + a: v
                                             for a, v in rows[k].items() if v != 0.0}
    for d, comb in dep.items():
        if any(c in dep for c in comb):
            raise BdfError("RBE2 chains (a dependent grid of one RBE2 as the independent grid "
                           "of another) are not supported")
        if d in fixed:
            raise BdfError(f"grid {nids[d // 3]} is both constrained (SPC) and an RBE2 "
                           f"dependent grid (Nastran: a fatal error)")
    free = [d for d in range(n) if d not in fixed and d not in dep]
    col = {d: i for i, d in enumerate(free)}
    rows_, cols_, vals_ = [], [], []
    for d in free:
        rows_.append(d), cols_.append(col[d]), vals_.append(1.0)
    for d, comb in dep.items():
        for c, v in comb.items():
            if c in col:
                rows_.append(d), cols_.append(col[c]), vals_.append(v)
    Tm = sp.csr_matrix((vals_, (rows_, cols_)), shape=(n, len(free)))
    # DOFs without stiffness and mass (grids only in-plane, unattached) are removed as well
    Kr = (Tm.T @ K @ Tm).tocsr()
    Mr = (Tm.T @ M @ Tm).tocsr()
    empty = np.flatnonzero((np.abs(Kr).sum(axis=1).A1 == 0) & (np.abs(Mr).sum(axis=1).A1 == 0))
    if empty.size:
        keep = np.setdiff1d(np.arange(len(free)), empty)
        Tm = Tm[:, keep]
        Kr = (Tm.T @ K @ Tm).tocsr()
        Mr = (Tm.T @ M @ Tm).tocsr()
    label = f"BDF {path.name}: {len(quads)} CQUAD4, {len(nids)} GRID"
    system = SupportedSystem(K=Kr, M=Mr, T=Tm.tocsr(), shaft_index=None, ground_index=None,
                             fictitious_inertia=0.0, shaft_nodes=np.array([], dtype=np.int64),
                             mesh=mesh, label=label)

    # ---- eigen and damping --------------------------------------------------------------
    n_modes = f_max = None
    meth = _case_value(model, "METHOD")
    methods = model.methods
    if methods:
        mth = methods.get(meth) if meth in methods else methods[sorted(methods)[0]]
        nd = getattr(mth, "nd", None)
        n_modes = int(nd) if nd else None
        v2 = getattr(mth, "v2", None) if mth.type == "EIGRL" else getattr(mth, "f2", None)
        f_max = float(v2) / T if v2 else None
    damping = None
    if getattr(model, "tables_sdamping", None):
        tab = model.tables_sdamping[sorted(model.tables_sdamping)[0]]
        g = np.asarray(tab.y, float) * (2.0 if tab.Type == "CRIT" else 1.0)
        if tab.Type not in ("G", "CRIT"):
            raise BdfError(f"TABDMP1 {tab.tid}: TYPE {tab.Type} is not supported (G, CRIT)")
        damping = tuple((float(f) / T, float(v)) for f, v in zip(tab.x, g))

    # ---- aero ---------------------------------------------------------------------------------
    boxes = box_ids = None
    b_ref = rho_ref = None
    symmetric = False
    machs, ks, flut = (), (), ()
    if model.caeros:
        boxes, box_ids = _boxes(model, L, z0 * L)
        _check_splines(model, box_ids, notes)
        aero = model.aero or model.aeros
        if aero is None:
            raise BdfError("CAERO1 without AERO / AEROS: the reference chord is unknown")
        b_ref = 0.5 * float(aero.cref) * L
        symmetric = int(aero.sym_xz or 0) == 1
        if int(getattr(aero, "sym_xy", 0) or 0) != 0:
            raise BdfError("SYMXY (ground effect) is not supported")
        if model.aero is not None:
            rho_ref = float(model.aero.rho_ref) * Mu / L**3
        pairs = []
        for mk in model.mkaeros:
            if mk.type != "MKAERO1":
                raise BdfError(f"{mk.type} is not supported (MKAERO1)")
            pairs += [(float(m), float(k)) for m in mk.machs for k in mk.reduced_freqs]
        machs = tuple(sorted({p[0] for p in pairs}))
        ks = tuple(sorted({p[1] for p in pairs}))
        for m in machs:
            if m >= 1.0:
                raise BdfError(f"MKAERO1 Mach {m} >= 1: asekit's doublet lattice is subsonic")
        flut = tuple(_flutter(model, f, rho_ref, L, Mu, T) for f in model.flutters.values())
    elif model.flutters:
        raise BdfError("FLUTTER without CAERO1 boxes")
    if ignored:
        warnings.warn(f"{path.name}: cards read but not represented by asekit: "
                      f"{_fmt(ignored)}", UnsupportedCardWarning, stacklevel=2)
    return BdfModel(mesh=mesh, node_ids=nids, K=K, M=M, system=system, boxes=boxes,
                    box_ids=box_ids, b_ref=b_ref, rho_ref=rho_ref, symmetric=symmetric,
                    machs=machs, reduced_frequencies=ks, flutter=flut, n_modes=n_modes,
                    f_max_hz=f_max, damping_g=damping, materials=materials,
                    element_pids=pids.copy(),
                    element_angles=_angles(keys, len(quads)),
                    springs=tuple(springs), masses=tuple(masses), fixed=tuple(sorted(fixed)),
                    rigid=tuple(rigid), ignored=tuple(ignored), notes=tuple(notes))


def _angles(keys, n):
    out = np.zeros(n)
    for (pid, ang), idx in keys.items():
        out[np.asarray(idx)] = ang
    return out


def _case_value(model, key: str):
    """The integer value of ``key`` (e.g. SPC, METHOD) in the first subcase, or None."""
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
    if n:
        return np.linspace(0.0, 1.0, int(n) + 1)
    if aefact is None:
        raise BdfError(f"CAERO1 {caero.eid}: neither N{name} nor L{name} given")
    f = np.asarray(aefact.fractions, float)
    if f[0] != 0.0 or f[-1] != 1.0 or np.any(np.diff(f) <= 0):
        raise BdfError(f"AEFACT {aefact.sid} (CAERO1 {caero.eid} L{name}): fractions must "
                       f"rise from 0 to 1")
    return f


def _boxes(model, L, z0):
    corners, strip, surface, ids, names = [], [], [], [], []
    s0 = 0
    for i, cid in enumerate(sorted(model.caeros)):
        c = model.caeros[cid]
        if c.type != "CAERO1":
            raise BdfError(f"{c.type} {cid} is not supported (CAERO1)")
        p1, p2, p3, p4 = (np.asarray(p, float) for p in c.get_points())
        if abs(p1[2] - p4[2]) > 1e-9 * max(1.0, abs(p4[1] - p1[1])) \
                or abs(p1[2] * L - z0) > 1e-6 * max(1.0, abs(z0)):
            raise BdfError(f"CAERO1 {cid}: the surface must lie in the structure's plane "
                           f"z = {z0 / L:g} (no dihedral)")
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
        # Nastran box ids run chordwise first, from P1 spanwise
        bid = cid + np.arange(ns * nc).reshape(ns, nc)
        if flip:
            bid = bid[::-1]
        corners.append(box * L)
        strip.append(s0 + np.repeat(np.arange(ns), nc))
        surface.append(np.full(ns * nc, i))
        ids.append(bid.ravel())
        names.append(f"CAERO1 {cid}")
        s0 += ns
    c = np.concatenate(corners)
    c[:, :, 2] = 0.0                                 # the structural plane is z = 0 in asekit
    return BoxMesh(c, np.concatenate(strip), np.concatenate(surface), tuple(names)), \
        np.concatenate(ids)


def _check_splines(model, box_ids, notes):
    splined = set()
    for s in model.splines.values():
        if s.type == "SPLINE1":
            splined.update(range(int(s.box1), int(s.box2) + 1))
        elif s.type == "SPLINE4":
            splined.update(int(b) for b in model.aelists[s.aelist].elements)
        else:
            raise BdfError(f"{s.type} {s.eid} is not supported (SPLINE1, SPLINE4)")
    missing = [int(b) for b in box_ids if int(b) not in splined]
    if missing:
        raise BdfError(f"boxes {missing[:10]}{'...' if len(missing) > 10 else ''} are not "
                       f"on any SPLINE1 / SPLINE4: Nastran would leave them rigid; asekit "
                       f"splines every box with the plate's shape functions")
    if model.splines:
        notes.append("SPLINE1 / SPLINE4 checked (every box splined); asekit interpolates the "
                     "modes with its finite-element shape functions, not the surface spline")


def _flutter(model, f, rho_ref, L, Mu, T) -> FlutterRequest:
    method = f.method
    if method not in ("PK", "PKNL"):
        raise BdfError(f"FLUTTER {f.sid}: method {method} is not supported (PK, PKNL)")
    if rho_ref is None:
        raise BdfError(f"FLUTTER {f.sid} needs AERO (RHOREF)")
    def fl(v):
        sid = v if isinstance(v, (int, np.integer)) else v.sid
        return np.asarray(model.flfacts[int(sid)].factors, float)
    dens = fl(f.density) * rho_ref
    mach = fl(f.mach)
    vel = np.abs(fl(f.reduced_freq_velocity)) * L / T
    if method == "PKNL" and not len(dens) == len(mach) == len(vel):
        raise BdfError(f"FLUTTER {f.sid} PKNL: FLFACT lists must have equal lengths")
    return FlutterRequest(int(f.sid), method, tuple(map(float, dens)), tuple(map(float, mach)),
                          tuple(map(float, vel)))


# ---------------------------------------------------------------------------------------------
# analysis of an imported model with asekit
# ---------------------------------------------------------------------------------------------
def modal_model(bdf: BdfModel, n_modes: int | None = None, f_max_hz: float | None = None):
    """The asekit modal model (n_rigid = 0) of an imported deck: the first ``n_modes``
    out-of-plane modes (default EIGR/EIGRL ND) or all below ``f_max_hz`` (default its V2 /
    F2, else 1000 Hz), with the TABDMP1 damping applied at each mode's frequency
    (g -> zeta = g / 2, :func:`asekit.structure.modes.with_damping`)."""
    from asekit.structure.modes import fixed_modal_model, with_damping
    n = bdf.n_modes if n_modes is None and f_max_hz is None else n_modes
    fm = f_max_hz if f_max_hz is not None else (bdf.f_max_hz or 1e300 if n else 1000.0)
    model = fixed_modal_model(bdf.system, bdf.M, fm, n)
    if bdf.damping_g:
        f, g = np.array(bdf.damping_g).T
        model = with_damping(model, structural_g=np.interp(model.frequencies_hz, f, g))
    return model


@dataclass(frozen=True)
class BdfFlutterPoint:
    """asekit's p-k flutter result of one (FLUTTER request, density, Mach): speed (m/s, None
    if no flutter in the sweep), frequency (Hz), mode index."""

    sid: int
    density: float
    mach: float
    speed: float | None
    frequency_hz: float | None
    mode: int | None


def flutter(bdf: BdfModel, model=None, progress: bool = False, method: str = "quartic"):
    """asekit's own analysis of the deck's FLUTTER requests: the GAFs of ``model`` (default
    :func:`modal_model`) with asekit's doublet lattice on the CAERO1 boxes over the MKAERO1
    grid, then p-k (:func:`asekit.aeroelastic.flutter.pk_flutter`) at every density x Mach over the
    velocities. Returns (list of :class:`BdfFlutterPoint`, GafDatabase, model)."""
    from asekit.aero.gaf import build_gaf_database
    from asekit.aero.spline import fe_spline
    from asekit.aeroelastic.flutter import TabulatedGaf, first_of, pk_flutter, pk_instabilities
    if bdf.boxes is None or not bdf.flutter:
        raise ValueError("bdf has no CAERO1 boxes or no FLUTTER request")
    model = modal_model(bdf) if model is None else model
    db = build_gaf_database(fe_spline(model, bdf.boxes), bdf.boxes, bdf.machs,
                            bdf.reduced_frequencies, bdf.b_ref, model.n_rigid, bdf.symmetric,
                            method, progress)
    out = []
    for req in bdf.flutter:
        combos = (list(zip(req.densities, req.machs)) if req.method == "PKNL"
                  else [(r, m) for r in req.densities for m in req.machs])
        for rho, mach in combos:
            i = int(np.argmin(np.abs(db.machs - mach)))
            if abs(db.machs[i] - mach) > 1e-9:
                raise ValueError(f"FLUTTER {req.sid}: Mach {mach} is not on the MKAERO1 grid "
                                 f"{db.machs.tolist()}")
            gaf = TabulatedGaf(db.k, db.Q[i], db.b_ref, mach=float(mach))
            U = np.array(sorted(set(req.velocities)))
            pk = pk_flutter(model, gaf, rho, U)
            inst = first_of(list(pk_instabilities(pk, model, gaf)), "flutter")
            out.append(BdfFlutterPoint(req.sid, rho, float(mach),
                                       None if inst is None else float(inst.speed),
                                       None if inst is None else float(inst.frequency_hz),
                                       None if inst is None else int(inst.mode)))
    return out, db, model


# ---------------------------------------------------------------------------------------------
# export of a case
# ---------------------------------------------------------------------------------------------
def _mkaero_cards(bdf, machs, ks):
    for i in range(0, len(machs), 8):
        for j in range(0, len(ks), 8):
            bdf.add_mkaero1(list(machs[i:i + 8]), list(ks[j:j + 8]))


def case_bdf(case, sol: int = 145, n_modes: int | None = None):
    """The case as a pyNastran ``BDF`` object (SI units: m, kg, s, N).

    Structure: one GRID per node (PS = 126: the in-plane DOFs, uncoupled from bending, are
    held), one CQUAD4 per element with its corner thicknesses T1-T4 from the case's
    thickness law, PSHELL (MID1 = MID2 = MID3) and MAT1 or MAT8 (material angle THETA from the
    G1-G2 edge), CONM2 for point masses at nodes, SPC1 for a clamped root; a shaft as a shaft
    GRID held in T3 and R1 (or on a CELAS2 in R1 with ``bending_stiffness``), an RBE2 (CM 345)
    to the nodes of a shaft region, the torsional spring as CELAS2 on R2 (FN1: to ground; FN2:
    to a ground GRID carrying the fictitious inertia as CONM2 I22). Aerodynamics: one CAERO1
    (PAERO1) per panel with the case's boxes, SPLINE1 (IPS) on all grids, AERO (REFC = 2 b,
    RHOREF = 1 so the FLFACT densities are in kg/m^3), MKAERO1 over the case's Mach and k,
    FLFACT densities / Machs / velocities and FLUTTER (PK). Case control: SOL 103 (METHOD =
    EIGRL) or SOL 145 (also FMETHOD).
    """
    from pyNastran.bdf.case_control_deck import CaseControlDeck
    from asekit.case import pipeline as pl
    BDF = _need_pynastran()
    if sol not in (103, 145):
        raise ValueError(f"sol must be 103 or 145, got {sol!r}")
    mesh = pl.structural_mesh(case)
    model = BDF(debug=None)
    nn = mesh.n_nodes
    for i, (x, y) in enumerate(mesh.nodes):
        model.add_grid(i + 1, [float(x), float(y), 0.0], ps="126")
    xy = mesh.nodes[mesh.elements]
    # corner thicknesses from the case's law (evaluated at the nodes)
    cth = mesh.thickness_xy(xy[:, :, 0].ravel(), xy[:, :, 1].ravel()).reshape(-1, 4)
    mat = case.material
    if isinstance(mat, Material):
        model.add_mat1(1, mat.youngs_modulus, None, mat.poisson_ratio, rho=mat.density)
        ang_mat = 0.0
    else:
        model.add_mat8(1, mat.e1, mat.e2, mat.nu12, g12=mat.g12, g1z=mat.g13, g2z=mat.g23,
                       rho=mat.density)
        ang_mat = mat.fibre_angle
    t_ref = float(np.max(cth))
    model.add_pshell(1, mid1=1, t=t_ref, mid2=1, mid3=1)
    for e, conn in enumerate(mesh.elements):
        d = xy[e, 1] - xy[e, 0]
        theta = math.degrees(ang_mat - math.atan2(d[1], d[0]))
        model.add_cquad4(e + 1, 1, [int(c) + 1 for c in conn], theta_mcid=float(theta),
                         T1=float(cth[e, 0]), T2=float(cth[e, 1]), T3=float(cth[e, 2]),
                         T4=float(cth[e, 3]))
    eid = mesh.n_elements + 1
    for pm in case.point_masses:
        i = mesh.node_at(pm.position, tol=1e-9 * max(mesh.span, 1.0),
                         name="point_mass position (BDF export puts a CONM2 on a node)")
        model.add_conm2(eid, i + 1, pm.mass, I=[pm.inertia[0], 0.0, pm.inertia[1], 0.0, 0.0,
                                                0.0])
        eid += 1
    s = case.support
    if s.kind == "clamped_root":
        root = np.flatnonzero(np.abs(mesh.nodes[:, 1] - mesh.y_root) <= 1e-9 * mesh.span)
        model.add_spc1(1, "345", [int(i) + 1 for i in root])
    else:
        if s.radius is None:
            shaft = mesh.node_at(s.axis_point, tol=1e-9 * max(mesh.span, 1.0),
                                 name="shaft axis_point") + 1
        else:
            shaft = nn + 1
            model.add_grid(shaft, [float(s.axis_point[0]), float(s.axis_point[1]), 0.0],
                           ps="126")
            d = np.hypot(*(mesh.nodes - np.asarray(s.axis_point)).T)
            region = np.flatnonzero(d <= s.radius * (1 + 1e-9))
            model.add_rbe2(eid, shaft, "345", [int(i) + 1 for i in region])
            eid += 1
        if s.bending_stiffness is None:
            model.add_spc1(1, "34", [shaft])
        else:
            model.add_spc1(1, "3", [shaft])
            model.add_celas2(eid, s.bending_stiffness, [shaft, 0], 4, 0)
            eid += 1
        if s.model == "FN1" or not case.modes.keep_rigid:
            model.add_celas2(eid, s.torsional_stiffness, [shaft, 0], 5, 0)
            eid += 1
        else:
            from asekit.structure.assembly import pitch_inertia
            ground = nn + 2
            model.add_grid(ground, [float(s.axis_point[0]), float(s.axis_point[1]), 0.0],
                           ps="12346")
            _, Mp = pl.mass_and_stiffness(case)
            i_f = s.fictitious_inertia_factor * pitch_inertia(mesh, Mp, s.axis_point[0])
            model.add_celas2(eid, s.torsional_stiffness, [shaft, ground], 5, 5)
            eid += 1
            model.add_conm2(eid, ground, 0.0, I=[0.0, 0.0, i_f, 0.0, 0.0, 0.0])
            eid += 1
    nmod = n_modes if n_modes is not None else case.modes.count
    model.add_eigrl(10, v1=None if nmod else -1.0e-3,
                    v2=None if nmod else float(case.modes.f_max), nd=nmod)
    lines = [f"TITLE = {case.name} (asekit export, SI: m kg s N)", "ECHO = NONE", "SPC = 1",
             "METHOD = 10", "DISP = ALL"]
    if sol == 145:
        a = case.aero
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
        model.add_aero(None, 2.0 * a.reference_semichord, 1.0,
                       sym_xz=1 if a.symmetry == "wall" else 0)
        _mkaero_cards(model, list(a.machs), [float(k) for k in pl.reduced_frequencies(case)])
        conds = pl.flight_conditions(case)
        model.add_flfact(1, [c.density for c in conds])
        model.add_flfact(2, list(a.machs))
        model.add_flfact(3, list(case.flight.velocities))
        model.add_flutter(20, "PK", 1, 2, 3, imethod="L")
        lines.insert(4, "FMETHOD = 20")
    d = case.damping
    if d.modal_damping_ratio is not None or d.structural_g is not None:
        ref = pl.modal_model(case)
        f = ref.frequencies_hz[ref.n_rigid:]
        if d.structural_g is not None:
            g = np.broadcast_to(np.asarray(d.structural_g, float), f.shape)
            kind = "G"
        else:
            g = np.broadcast_to(np.asarray(d.modal_damping_ratio, float), f.shape)
            kind = "CRIT"
        if np.ptp(g) == 0:
            x, y = [0.0, 1.0e5], [float(g[0])] * 2
        else:                                          # per mode: a table through each mode
            x, y = list(map(float, f)), list(map(float, g))
        model.add_tabdmp1(30, np.array(x), np.array(y), Type=kind)
        lines.append("SDAMP = 30")
    model.sol = sol
    model.case_control_deck = CaseControlDeck(lines + ["BEGIN BULK"])
    return model


def write_case_bdf(case, path, sol: int = 145, n_modes: int | None = None) -> Path:
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
        c = boxes.corners[boxes.surface == i]
        st = boxes.strip[boxes.surface == i]
        nc = int(np.sum(st == st[0]))
        ns = c.shape[0] // nc
        g = c.reshape(ns, nc, 4, 3)
        r_le, r_c = g[0, 0, 0], g[0, -1, 1, 0] - g[0, 0, 0, 0]
        t_le, t_c = g[-1, 0, 3], g[-1, -1, 2, 0] - g[-1, 0, 3, 0]
        xi = np.concatenate([[0.0], (g[0, :, 1, 0] - r_le[0]) / r_c])
        span = t_le[1] - r_le[1]
        eta = np.concatenate([[0.0], (g[:, 0, 3, 1] - r_le[1]) / span])
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


def bdf_model_deck(bdf: BdfModel):
    """An imported :class:`BdfModel` as a pyNastran ``BDF`` (SI units), rebuilt from the
    asekit model's parts: GRIDs (PS 126), CQUAD4 with corner thicknesses, one PSHELL and
    MAT1 / MAT8 per property (MAT8 angle as CQUAD4 THETA), CONM2, CELAS2, RBE2, SPC1, and
    the aerodynamic and flutter cards when present (SOL 145, else SOL 103)."""
    from pyNastran.bdf.case_control_deck import CaseControlDeck
    BDF = _need_pynastran()
    model = BDF(debug=None)
    ids = [int(g) for g in bdf.node_ids]
    for g, (x, y) in zip(ids, bdf.mesh.nodes):
        model.add_grid(g, [float(x), float(y), 0.0], ps="126")
    done = set()
    for (pid, ang), mat in bdf.materials.items():
        if pid in done:
            continue
        done.add(pid)
        if isinstance(mat, Material):
            model.add_mat1(pid, mat.youngs_modulus, None, mat.poisson_ratio, rho=mat.density)
        else:
            model.add_mat8(pid, mat.e1, mat.e2, mat.nu12, g12=mat.g12, g1z=mat.g13,
                           g2z=mat.g23, rho=mat.density)
        sel = bdf.element_pids == pid
        model.add_pshell(pid, mid1=pid, t=float(bdf.mesh.corner_thickness[sel].max()),
                         mid2=pid, mid3=pid)
    xy = bdf.mesh.nodes[bdf.mesh.elements]
    th = bdf.mesh.corner_thickness
    for e, conn in enumerate(bdf.mesh.elements):
        pid = int(bdf.element_pids[e])
        mat = bdf.materials[(pid, float(bdf.element_angles[e]))] \
            if (pid, float(bdf.element_angles[e])) in bdf.materials else None
        theta = 0.0
        if mat is not None and not isinstance(mat, Material):
            d = xy[e, 1] - xy[e, 0]
            theta = math.degrees(float(bdf.element_angles[e]) - math.atan2(d[1], d[0]))
        if conn[2] == conn[3]:
            model.add_ctria3(e + 1, pid, [ids[c] for c in conn[:3]], theta_mcid=float(theta),
                             T1=float(th[e, 0]), T2=float(th[e, 1]), T3=float(th[e, 2]))
        else:
            model.add_cquad4(e + 1, pid, [ids[c] for c in conn], theta_mcid=float(theta),
                             T1=float(th[e, 0]), T2=float(th[e, 1]), T3=float(th[e, 2]),
                             T4=float(th[e, 3]))
    eid = bdf.mesh.n_elements + 1
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
    by_comp = {}
    for d in bdf.fixed:
        by_comp.setdefault(str(d % 3 + 3), []).append(ids[d // 3])
    for comp, nodes in sorted(by_comp.items()):
        model.add_spc1(1, comp, nodes)
    nd = bdf.n_modes
    model.add_eigrl(10, v1=None if nd else -1.0e-3, v2=bdf.f_max_hz if not nd else None, nd=nd)
    lines = ["TITLE = asekit export of an imported deck (SI: m kg s N)", "ECHO = NONE",
             "SPC = 1", "METHOD = 10", "DISP = ALL"]
    sol = 103
    if bdf.damping_g:
        f, g = zip(*bdf.damping_g)
        model.add_tabdmp1(30, np.array(f), np.array(g), Type="G")
        lines.append("SDAMP = 30")
    if bdf.boxes is not None:
        _aero_cards(model, bdf.boxes, 100001, ids)
        model.add_aero(None, 2.0 * bdf.b_ref, bdf.rho_ref or 1.0,
                       sym_xz=1 if bdf.symmetric else 0)
        _mkaero_cards(model, list(bdf.machs), list(bdf.reduced_frequencies))
        for j, req in enumerate(bdf.flutter):
            f0 = 3 * j + 1
            model.add_flfact(f0, [r / (bdf.rho_ref or 1.0) for r in req.densities])
            model.add_flfact(f0 + 1, list(req.machs))
            model.add_flfact(f0 + 2, list(req.velocities))
            model.add_flutter(req.sid, req.method, f0, f0 + 1, f0 + 2, imethod="L")
        if bdf.flutter:
            sol = 145
            lines.insert(4, f"FMETHOD = {bdf.flutter[0].sid}")
    model.sol = sol
    model.case_control_deck = CaseControlDeck(lines + ["BEGIN BULK"])
    return model


def write_bdf_model(bdf: BdfModel, path) -> Path:
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
