"""Nastran stick-model decks (CBAR / CBEAM beams) in: the structure of a bar deck as 3-D frame
matrices.

:func:`read_stick_deck` reads, through pyNastran, a deck whose structure is made of bars:

- GRID (basic position through any CORD2R/CORD1R/CORD2C/CORD2S of CP; displacement system CD
  rectangular; permanent constraints PS),
- CBAR (orientation vector X1-X3 in GA's displacement system, or G0; OFFT blank, GGG, or the
  old integer flag 1 "X1-X3 is a vector"; pin flags PA/PB and offsets WA/WB refused),
- PBAR (A, I1, I2, J, NSM; I12 refused) with MAT1 (E, G, RHO),
- CBEAM as the same bar plus its polar mass rho (I1 + I2) on the twist (orientation as CBAR; OFFT blank or GGG, BIT, pin flags, offsets
  WA/WB and warping scalar points SA/SB refused) with PBEAM (A, I1, I2, J, NSM at end A, the
  intermediate stations X/XB and end B, each linearly interpolated between stations; a
  station differing from end A makes the element tapered,
  :func:`asekit.structure.frame.tapered_bar_matrices`; K1/K2 the shear factors (0.0: shear
  flexibility neglected); I12, shear relief S1/S2, NSI, warping CW and the NSM / neutral-axis
  offsets M1-N2 must be 0) or PBEAML (GROUP MSCBML0, the PBARL types below through
  :func:`pbarl_section`, the dimensions DIMi and NSM linearly interpolated between stations),
- PBARL of type BAR, ROD, TUBE, BOX or (doubly symmetric) I with GROUP MSCBML0, its A, I1, I2
  and J from the closed forms of :func:`pbarl_section` (dimensions as the MSC Nastran Quick
  Reference Guide's PBARL figures define them) and the library's shear factor
  (:data:`_LIBRARY_SHEAR`: ROD 0.9, the others none),
- CMASS2 (scalar mass on a grid component, or between two), CONM2 (mass and inertia with
  offset, CID 0 or blank),
- SPC1 / SPC (zero enforced value) of the case control's SPC set, PARAM COUPMASS (> 0: the
  consistent bar mass, else lumped), PARAM WTMASS,
- RBE2 (GN independent, CM components of the GMi dependent) and RBAR (GA independent in all
  six components, CMB of GB dependent), eliminated by the rigid-link transformation
  u_d = u_i + theta_i x (x_d - x_i), theta_d = theta_i (Przemieniecki Sec. 11.7; in the grids'
  CD systems), K_r = T^T K T, M_r = T^T M T; chains (a dependent DOF independent elsewhere)
  resolved by substitution in dependency order, cycles and SPC on a dependent DOF refused,
- RBE3 (REFGRID's REFC components dependent on the weighted least-squares rigid fit of the
  independent grids' WTi / Ci / Gi,j components, :func:`rbe3_weights`; the UM alternative
  refused), eliminated and chained as RBE2 / RBAR.

The element is :mod:`asekit.structure.frame` (Przemieniecki 1968 Eqs. 5.116 and 11.41, rotated
by the direction cosines, Eq. 6.26). Every grid carries six DOFs (T1, T2, T3, R1, R2, R3) in its
displacement system CD, as Nastran's g-set: with R_cd the rows of CD's axes in basic, the
basic-frame matrices become K_cd = T^T K_basic T, T = diag(R_cd^T, R_cd^T) per grid.
Massless DOFs are condensed statically (exact for them: no inertia) before the eigen-solution.

Other structural cards (CROD, RBE1, PBEAML, shells, ...) are refused with the card and its
first id; an unsupported field is refused with card, id and field. Aerodynamic and solution
cards are read elsewhere (:mod:`asekit.io.bdf`); here they are ignored.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import scipy.linalg as sla

from asekit.io.bdf import (
    UNITS,
    BdfError,
    Deck,
    case_value,
    check_caero1,
    deck_boxes_aero,
    need_pynastran,
    read_aero_card,
    read_flutter,
    read_mkaero1,
    solve_request,
)
from asekit.structure.frame import (
    BarSection,
    global_bar_matrices,
    global_tapered_bar_matrices,
)

#: structural cards a stick deck may hold (others are refused).
STICK_CARDS = ("GRID", "CORD2R", "CORD1R", "CORD2C", "CORD2S", "CBAR", "PBAR", "MAT1",
               "CMASS2", "CONM2", "SPC", "SPC1", "RBE2", "RBAR", "RBE3", "CBEAM", "PBEAM",
               "PBARL", "PBEAML")

#: structural cards refused in a stick deck (asekit cannot represent them here).
REFUSED_CARDS = ("CROD", "CONROD", "PROD", "CTUBE",
                 "RBE1", "RROD", "MPC", "CELAS1", "CELAS2", "CELAS3",
                 "CELAS4", "CMASS1", "CMASS3", "CMASS4", "CONM1", "CQUAD4", "CTRIA3", "CQUAD8",
                 "CTRIA6", "CSHEAR", "CHEXA", "CPENTA", "CTETRA", "CBUSH", "CDAMP1", "CDAMP2",
                 "CVISC", "SPOINT", "EPOINT", "GENEL", "SPCD", "SUPORT")

NODE_DOF = 6


@dataclass(frozen=True)
class StickModel:
    """A bar deck's structure (SI).

    Attributes
    ----------
    node_ids : (n,) GRID ids; xyz : (n, 3) basic positions (m); cd_axes : (n, 3, 3) rows of
        each grid's displacement-system axes in basic.
    K, M : (6n, 6n) stiffness and mass, DOF 6 i + c - 1 = component c of grid i in its CD
        system (N/m, N, N m; kg, kg m, kg m^2).
    fixed : sorted constrained DOFs (SPC, SPC1, GRID PS); coupled : the consistent bar mass
        (PARAM COUPMASS > 0) or lumped; notes : what was read and how; path, units.
    rigid : (dependent DOF, ((independent DOF, coefficient), ...)) per DOF an RBE2 / RBAR /
        RBE3 makes dependent.
    """

    node_ids: np.ndarray
    xyz: np.ndarray
    cd_axes: np.ndarray
    K: np.ndarray
    M: np.ndarray
    fixed: tuple
    coupled: bool
    notes: tuple = ()
    path: str = ""
    units: str = "SI"
    rigid: tuple = ()

    @property
    def free(self) -> np.ndarray:
        """The DOFs neither constrained nor dependent (the solution's unknowns)."""
        mask = np.ones(self.K.shape[0], bool)
        mask[list(self.fixed)] = False
        mask[[d for d, _ in self.rigid]] = False
        return np.flatnonzero(mask)

    def reduction(self) -> np.ndarray:
        """T (n_dof, n_free): all DOFs from the free ones (constrained rows 0, dependent rows
        the rigid links' coefficients; a coefficient on a constrained DOF drops out)."""
        free = self.free
        col = {int(d): j for j, d in enumerate(free)}
        T = np.zeros((self.K.shape[0], free.size))
        T[free, np.arange(free.size)] = 1.0
        for d, row in self.rigid:
            for i, c in row:
                if i in col:
                    T[d, col[i]] += c
        return T

    def dof(self, grid_id: int, component: int) -> int:
        """Global DOF of GRID ``grid_id``, Nastran component 1-6."""
        hit = np.flatnonzero(self.node_ids == int(grid_id))
        if not hit.size or not 1 <= int(component) <= 6:
            raise ValueError(f"grid_id {grid_id} / component {component}: not a GRID of the "
                             f"deck or not in 1..6")
        return NODE_DOF * int(hit[0]) + int(component) - 1


@dataclass(frozen=True)
class StickModes:
    """Normal modes of a :class:`StickModel`: ``frequencies_hz`` (n_modes,), ``shapes``
    (6 n_nodes, n_modes) in the grids' CD systems, mass-normalised (phi^T M phi = 1)."""

    frequencies_hz: np.ndarray
    shapes: np.ndarray
    notes: tuple = field(default=())


def card_ids(model, card: str) -> list:
    """The ids of every ``card`` (e.g. ``"CBAR"``) of a pyNastran model, in its order.

    Examples
    --------
    >>> from types import SimpleNamespace as NS
    >>> card_ids(NS(_type_to_id_map={"CBAR": [3, 1]}), "CBAR")
    [3, 1]
    """
    return list(model._type_to_id_map.get(card, ()))


#: the structural cards of each pyNastran container a stick deck may hold.
_ALLOWED = {"elements": ("CBAR", "CBEAM"), "masses": ("CMASS2", "CONM2"),
            "rigid_elements": ("RBE2", "RBAR", "RBE3"),
            "properties": ("PBAR", "PBEAM", "PBARL", "PBEAML")}

#: the line elements a stick deck's structure is made of.
BAR_CARDS = ("CBAR", "CBEAM")


def _refuse_cards(model, name: str) -> None:
    found = {c for c in REFUSED_CARDS if card_ids(model, c)}
    for attr, ok in _ALLOWED.items():
        found |= {v.type for v in getattr(model, attr).values() if v.type not in ok}
    bad = [(c, len(card_ids(model, c)), (card_ids(model, c) or ["?"])[0])
           for c in sorted(found)]
    if bad:
        listed = ", ".join(f"{c} (x{n}, first id {i})" for c, n, i in bad)
        raise BdfError(f"{name}: the stick-model import cannot represent {listed}; it reads "
                       f"CBAR/CBEAM with PBAR/PBEAM/PBARL/PBEAML and MAT1, CMASS2, CONM2, RBE2, RBAR, RBE3, "
                       f"SPC/SPC1 and GRID PS")
    if not any(card_ids(model, c) for c in BAR_CARDS):
        raise BdfError(f"{name}: no CBAR or CBEAM element: not a stick model")


def _rect_axes(model, cid: int, what: str) -> np.ndarray:
    """Rows of a rectangular system's axes in basic; a curvilinear CD is refused."""
    if not cid:
        return np.eye(3)
    c = model.coords[cid]
    if c.type not in ("CORD2R", "CORD1R"):
        raise BdfError(f"{what}: CD = {cid} is a {c.type}; only rectangular displacement "
                       f"systems (CORD2R, CORD1R) are supported")
    return np.asarray(c.beta(), float)


def _grids(model, L: float):
    ids = np.array(sorted(model.nodes), dtype=np.int64)
    xyz = np.array([model.nodes[i].get_position() for i in ids], float) * L
    axes = np.array([_rect_axes(model, model.nodes[i].cd, f"GRID {i}") for i in ids])
    return ids, xyz, axes


def bar_orientation(model, e, axes_of, xyz_of) -> np.ndarray:
    """Orientation vector of a CBAR / CBEAM in basic (m or deck units, as ``xyz_of``).

    Parameters
    ----------
    model : pyNastran ``BDF``; e : the CBAR / CBEAM card.
    axes_of : GRID id -> (3, 3) rows of its CD system's axes in basic.
    xyz_of : GRID id -> (3,) its basic position.

    Returns
    -------
    (3,) X1-X3 rotated from GA's CD system to basic, or G0 - GA (MSC QRG CBAR, CBEAM).
    """
    if e.g0:
        return xyz_of(e.g0) - xyz_of(e.ga)
    return axes_of(e.ga).T @ np.asarray(e.x, float)


def _check_bar(e) -> None:
    """The CBAR / CBEAM fields asekit's bar cannot represent, refused with card, id, field."""
    card = f"{e.type} {e.eid}"
    if e.offt not in ("GGG", 1, "1", None, ""):
        raise BdfError(f"{card}: OFFT = {e.offt!r} is not supported (blank or GGG: the "
                       f"orientation vector in GA's displacement system)")
    if e.pa or e.pb:
        raise BdfError(f"{card}: pin flags PA = {e.pa}, PB = {e.pb} are not supported "
                       f"(blank or 0)")
    if np.any(np.asarray(e.wa, float)) or np.any(np.asarray(e.wb, float)):
        raise BdfError(f"{card}: offsets WA/WB are not supported (blank or 0)")
    if e.type == "CBEAM":
        if getattr(e, "bit", None) is not None:
            raise BdfError(f"{card}: BIT = {e.bit!r} (beam-in-tapered) is not supported "
                           f"(blank, or OFFT blank / GGG)")
        if e.sa or e.sb:
            raise BdfError(f"{card}: warping scalar points SA = {e.sa}, SB = {e.sb} are not "
                           f"supported (blank or 0: no warping)")


def _shear_factor(p, name: str) -> float:
    """PBAR / PBEAM K1 or K2 (> 0: shear area factor, K G A the shear stiffness), or 0.0 for
    no shear flexibility (PBAR blank, which pyNastran stores as 1e8; PBEAM 0.0)."""
    k = getattr(p, name, None)
    if k is None or k == 1e8 and p.type == "PBAR":
        return 0.0
    k = float(k)
    if not (math.isfinite(k) and k >= 0):
        raise BdfError(f"{p.type} {p.pid}: {name.upper()} = {k:g} must be >= 0")
    return k


def _pbar_values(p) -> tuple:
    """PBAR: (A, I1, I2, J, NSM, K1, K2) in deck units; I12 refused."""
    if p.i12:
        raise BdfError(f"PBAR {p.pid}: I12 = {p.i12:g} is not supported (0: principal axes)")
    return (p.A, p.i1, p.i2, p.j, p.nsm or 0.0, _shear_factor(p, "k1"),
            _shear_factor(p, "k2"))


#: PBEAM fields that must be zero for asekit's bar (constant section, no shear relief, no NSM
#: inertia, no warping, no NSM or neutral-axis offsets).
_PBEAM_ZERO = ("s1", "s2", "nsia", "nsib", "cwa", "cwb", "m1a", "m2a", "m1b", "m2b", "n1a",
               "n2a", "n1b", "n2b")


def _pbeam_stations(p) -> tuple:
    """PBEAM: (x/XB stations, rows (A, I1, I2, J, NSM) per station, K1, K2) in deck units.

    End A, the intermediate stations and end B as pyNastran reads them (a blank end B equal
    to end A: MSC QRG PBEAM remark 5); x/XB strictly ascending from 0.0 to 1.0; I12 = 0 and
    the :data:`_PBEAM_ZERO` fields 0 at every station, else refused naming the field (MSC QRG
    PBEAM: K1, K2 default 1.0, the shear stiffness K G A; 0.0 neglects the shear
    flexibility)."""
    xs = np.atleast_1d(np.asarray(getattr(p, "xxb", [0.0]), float))
    vals = {name: np.atleast_1d(np.asarray(getattr(p, key), float)) for name, key in
            (("A", "A"), ("I1", "i1"), ("I2", "i2"), ("J", "j"), ("NSM", "nsm"),
             ("I12", "i12"))}
    if np.any(vals["I12"]):
        raise BdfError(f"PBEAM {p.pid}: I12 = {vals['I12'][vals['I12'] != 0][0]:g} is not "
                       f"supported (0: principal axes)")
    for key in _PBEAM_ZERO:
        x = float(getattr(p, key) or 0.0)
        if x != 0.0:
            raise BdfError(f"PBEAM {p.pid}: {key.upper()} = {x:g} is not supported (0.0)")
    rows = np.column_stack([vals[n] for n in ("A", "I1", "I2", "J", "NSM")])
    xs, rows = _stations(xs, rows, f"PBEAM {p.pid}")
    return xs, rows, _shear_factor(p, "k1"), _shear_factor(p, "k2")


def _stations(xs, rows, where: str):
    """The stations x/XB (ascending from 0.0; end B at 1.0 added equal to the last one when
    absent) and their rows, refused naming ``where`` when not strictly ascending in [0, 1]."""
    xs = np.asarray(xs, float)
    if xs.size != rows.shape[0]:
        raise BdfError(f"{where}: {xs.size} stations X/XB for {rows.shape[0]} sections")
    if xs[0] != 0.0 or np.any(np.diff(xs) <= 0) or xs[-1] > 1.0:
        raise BdfError(f"{where}: X/XB = {xs.tolist()} must ascend strictly from 0.0 (end A) "
                       f"to 1.0 (end B)")
    if xs[-1] < 1.0:
        xs, rows = np.r_[xs, 1.0], np.vstack([rows, rows[-1]])
    return xs, rows


#: shear factors K1 = K2 the beam library gives a PBARL / PBEAML section: ROD 0.9, as
#: Simcenter Nastran 2019.2 echoes a PBARL / PBEAML ROD as a PBAR / PBEAM (user information
#: message 4379 in pyNastran's models/beam_modes/beam_modes.f06, data/benchmarks/beam_modes);
#: the other types' factors are not known here and are 0.0 (no shear flexibility).
_LIBRARY_SHEAR = {"ROD": 0.9}

#: PBARL section types :func:`pbarl_section` evaluates, with their number of dimensions.
PBARL_TYPES = {"BAR": 2, "ROD": 1, "TUBE": 2, "BOX": 4, "I": 6}


def _pbarl_geometry(t: str, d) -> str:
    """The reason a PBARL's dimensions do not make a section (empty when they do)."""
    if t == "TUBE" and not d[1] < d[0]:
        return "DIM2 (inner radius) must be < DIM1 (outer radius)"
    if t == "BOX" and not (2 * d[3] < d[0] and 2 * d[2] < d[1]):
        return "2 DIM4 < DIM1 and 2 DIM3 < DIM2 (the walls leave a hole)"
    if t == "I" and not (d[4] + d[5] < d[0] and d[3] < min(d[1], d[2])):
        return "DIM5 + DIM6 < DIM1 and DIM4 < DIM2, DIM3 (a web between the flanges)"
    if t == "I" and (d[1] != d[2] or d[4] != d[5]):
        return ("DIM2 = DIM3 and DIM5 = DIM6 (doubly symmetric; an unsymmetric I has its "
                "centroid off the reference axis, an offset asekit's bar does not have)")
    return ""


def pbarl_section(section_type: str, dims, where: str = "PBARL") -> tuple:
    """A, I1, I2, J of a PBARL cross-section from its DIMi (any consistent length unit).

    The dimensions are those of the PBARL figures of the MSC Nastran Quick Reference Guide
    (element y axis = plane 1, z axis = plane 2; I1 = int y^2 dA, I2 = int z^2 dA):

    - BAR: DIM1 width along z, DIM2 height along y. A = b h, I1 = b h^3 / 12,
      I2 = h b^3 / 12; J = a c^3 (1/3 - 0.21 (c/a)(1 - c^4 / (12 a^4))), a = max(b, h),
      c = min(b, h) (Roark, *Formulas for Stress and Strain*, 7th ed., Table 10.7 case 4).
    - ROD: DIM1 radius r. A = pi r^2, I1 = I2 = pi r^4 / 4, J = pi r^4 / 2.
    - TUBE: DIM1 outer, DIM2 inner radius. A = pi (ro^2 - ri^2), I1 = I2 = pi (ro^4 - ri^4)/4,
      J = pi (ro^4 - ri^4) / 2.
    - BOX: DIM1 width b (z), DIM2 height h (y), DIM3 thickness t1 of the walls normal to y,
      DIM4 thickness t2 of the walls normal to z. A = b h - bi hi (bi = b - 2 t2,
      hi = h - 2 t1), I1 = (b h^3 - bi hi^3) / 12, I2 = (h b^3 - hi bi^3) / 12; J of the
      closed thin-walled section on the wall mid-lines (Bredt-Batho, Roark Table 10.7 case 16):
      J = 2 t1 t2 (b - t2)^2 (h - t1)^2 / (b t2 + h t1 - t2^2 - t1^2).
    - I (doubly symmetric: DIM2 = DIM3, DIM5 = DIM6): DIM1 height h (y), DIM2 flange width b,
      DIM4 web thickness tw, DIM5 flange thickness tf; web height hw = h - 2 tf.
      A = 2 b tf + hw tw, I1 = (b h^3 - (b - tw) hw^3) / 12, I2 = (2 tf b^3 + hw tw^3) / 12,
      J = (2 b tf^3 + hw tw^3) / 3 (open thin-walled section, sum of its rectangles).

    Parameters
    ----------
    section_type : one of :data:`PBARL_TYPES`.
    dims : its DIMi (> 0; DIM2 of TUBE >= 0).
    where : the card named in an error (e.g. ``"PBARL 7"``).

    Returns
    -------
    (A, I1, I2, J) : floats in the unit of ``dims`` squared and to the fourth power.

    Raises
    ------
    BdfError
        An unsupported type, the wrong number of dimensions, or dimensions that make no
        section, naming ``where`` and the field.

    Examples
    --------
    >>> A, I1, I2, J = pbarl_section("BAR", [0.2, 0.1])
    >>> round(A, 6), round(I1 * 1e6, 4), round(I2 * 1e6, 4)
    (0.02, 16.6667, 66.6667)
    """
    t = str(section_type).upper()
    if t not in PBARL_TYPES:
        raise BdfError(f"{where}: TYPE = {t!r} is not supported ({', '.join(PBARL_TYPES)})")
    d = [float(x) for x in dims]
    if len(d) != PBARL_TYPES[t]:
        raise BdfError(f"{where}: TYPE {t} needs {PBARL_TYPES[t]} dimensions DIMi, got {len(d)}")
    for i, x in enumerate(d):
        if not (np.isfinite(x) and (x > 0 or (t == "TUBE" and i == 1 and x == 0))):
            raise BdfError(f"{where}: DIM{i + 1} = {x:g} must be > 0")
    why = _pbarl_geometry(t, d)
    if why:
        raise BdfError(f"{where}: TYPE {t} DIM = {d}: {why}")
    return _PBARL_FORMS[t](*d)


def _bar_form(b, h):
    a, c = max(b, h), min(b, h)
    return (b * h, b * h ** 3 / 12, h * b ** 3 / 12,
            a * c ** 3 * (1 / 3 - 0.21 * (c / a) * (1 - c ** 4 / (12 * a ** 4))))


def _tube_form(ro, ri=0.0):
    i = np.pi * (ro ** 4 - ri ** 4) / 4
    return np.pi * (ro ** 2 - ri ** 2), i, i, 2 * i


def _box_form(b, h, t1, t2):
    bi, hi = b - 2 * t2, h - 2 * t1
    J = 2 * t1 * t2 * (b - t2) ** 2 * (h - t1) ** 2 / (b * t2 + h * t1 - t2 ** 2 - t1 ** 2)
    return b * h - bi * hi, (b * h ** 3 - bi * hi ** 3) / 12, (h * b ** 3 - hi * bi ** 3) / 12, J


def _i_form(h, b, _b2, tw, tf, _tf2):
    hw = h - 2 * tf
    return (2 * b * tf + hw * tw, (b * h ** 3 - (b - tw) * hw ** 3) / 12,
            (2 * tf * b ** 3 + hw * tw ** 3) / 12, (2 * b * tf ** 3 + hw * tw ** 3) / 3)


_PBARL_FORMS = {"BAR": _bar_form, "ROD": _tube_form, "TUBE": _tube_form, "BOX": _box_form,
                "I": _i_form}


def _pbarl_values(p) -> tuple:
    """PBARL: (A, I1, I2, J, NSM, K, K) in deck units (:func:`pbarl_section`; K the library's
    shear factor, :data:`_LIBRARY_SHEAR`: PBARL has no K1 / K2 field); GROUP MSCBML0 only."""
    group = str(getattr(p, "group", "MSCBML0") or "MSCBML0").strip().upper()
    if group != "MSCBML0":
        raise BdfError(f"PBARL {p.pid}: GROUP = {group!r} is not supported (MSCBML0, the "
                       f"standard beam library)")
    k = _LIBRARY_SHEAR.get(str(p.beam_type).upper(), 0.0)
    return (*pbarl_section(p.beam_type, p.dim, f"PBARL {p.pid}"), float(p.nsm or 0.0), k, k)


def _pbeaml_stations(p) -> tuple:
    """PBEAML: (x/XB stations, rows (DIM1..DIMn, NSM) per station, 0, 0) in deck units, the
    section type one of :data:`PBARL_TYPES` (shared with PBARL, :func:`pbarl_section`, which
    checks every station's dimensions); GROUP MSCBML0 only; shear factors as PBARL's."""
    where = f"PBEAML {p.pid}"
    group = str(getattr(p, "group", "MSCBML0") or "MSCBML0").strip().upper()
    if group != "MSCBML0":
        raise BdfError(f"{where}: GROUP = {group!r} is not supported (MSCBML0, the standard "
                       f"beam library)")
    dims = np.atleast_2d(np.asarray(p.dim, float))
    nsm = np.atleast_1d(np.asarray(p.nsm, float))
    for d in dims:
        pbarl_section(p.beam_type, d, where)
    xs, rows = _stations(p.xxb, np.column_stack([dims, nsm]), where)
    k = _LIBRARY_SHEAR.get(str(p.beam_type).upper(), 0.0)
    return xs, rows, k, k


def _single_station(values):
    """A PBAR / PBARL as one station: (x/XB = [0, 1], rows (A, I1, I2, J, NSM) twice, K1, K2)."""
    row = np.asarray(values[:5], float)
    return np.array([0.0, 1.0]), np.vstack([row, row]), values[5], values[6]


#: per property card: (x/XB stations, rows, K1, K2) and the row -> (A, I1, I2, J, NSM) map.
_STATIONS = {"PBAR": lambda p: _single_station(_pbar_values(p)),
             "PBARL": lambda p: _single_station(_pbarl_values(p)),
             "PBEAM": _pbeam_stations, "PBEAML": _pbeaml_stations}
#: the properties each line element may reference (MSC QRG CBAR / CBEAM PID).
_ELEMENT_PROPERTIES = {"CBAR": ("PBAR", "PBARL"), "CBEAM": ("PBEAM", "PBARL", "PBEAML")}


def _row_values(p):
    """Row of :data:`_STATIONS` -> (A, I1, I2, J, NSM) of property ``p``."""
    if p.type == "PBEAML":
        return lambda r: (*pbarl_section(p.beam_type, r[:-1], f"PBEAML {p.pid}"), r[-1])
    return lambda r: tuple(r)


def _si_section(values, k1, k2, mat, deck_units, polar: bool = False) -> BarSection:
    """(A, I1, I2, J, NSM) in deck units + MAT1 -> :class:`BarSection` (SI); ``polar``: the
    section's polar mass moment rho (I1 + I2) on the twist (a CBEAM's, not a CBAR's)."""
    L, Mu, T, wt = deck_units
    A, i1, i2, j, nsm = (float(v) for v in values)
    E, G, rho = mat.e, mat.g, mat.rho or 0.0
    stress = Mu / (L * T * T)                      # deck pressure in Pa
    gas = [k * G * A * stress * L ** 2 if k else math.inf for k in (k1, k2)]
    return BarSection(ea=E * A * stress * L ** 2, gj=G * j * stress * L ** 4,
                      ei1=E * i1 * stress * L ** 4, ei2=E * i2 * stress * L ** 4,
                      mass=(rho * A + (nsm or 0.0)) * wt * Mu / L, gas1=gas[0], gas2=gas[1],
                      polar=rho * (i1 + i2) * wt * Mu * L if polar else 0.0)


def bar_stations(model, pid: int, eid: int, deck_units, card: str = "CBAR"):
    """The section of a CBAR / CBEAM along it: PBAR / PBARL (uniform), PBEAM (stations x/XB,
    each property linearly interpolated between them) or PBEAML (stations, the dimensions
    DIMi and NSM linearly interpolated, the section from :func:`pbarl_section` at each point)
    + MAT1, in SI.

    Parameters
    ----------
    model : pyNastran ``BDF``, cross-referenced.
    pid, eid : the element's PID and id; card : "CBAR" or "CBEAM" (which properties it takes).
    deck_units : (L m, Mu kg, T s, PARAM WTMASS) of one deck unit.

    Returns
    -------
    (breaks, section_at, uniform) : the stations (ascending, 0.0 ... 1.0), a callable
        xi -> :class:`~asekit.structure.frame.BarSection` (EA = E A, GJ = G J, EI1 = E I1,
        EI2 = E I2 in N, N m^2; mass = (rho A + NSM) WTMASS in kg/m; K G A from K1 / K2; a
        CBEAM's polar mass moment rho (I1 + I2) WTMASS in kg m) and whether every station is
        the same.

    Raises
    ------
    BdfError
        Naming the card, its id and the field asekit cannot represent.
    """
    p = model.properties[pid]
    if p.type not in _ELEMENT_PROPERTIES[card]:
        raise BdfError(f"{card} {eid}: PID {pid} is a {p.type}; a {card} takes "
                       f"{' or '.join(_ELEMENT_PROPERTIES[card])}")
    xs, rows, k1, k2 = _STATIONS[p.type](p)
    to_values = _row_values(p)
    for r in rows:
        A = to_values(r)[0]
        if not A > 0:
            raise BdfError(f"{p.type} {pid}: A = {A!r} must be > 0")
    mat = model.materials[p.mid]
    if mat.type != "MAT1":
        raise BdfError(f"{p.type} {pid}: MID {p.mid} is a {mat.type}; only MAT1 is supported")
    E, G = mat.e, mat.g
    if not (E and E > 0 and G is not None and G >= 0):
        raise BdfError(f"MAT1 {p.mid}: E must be > 0 and G >= 0, got E = {E!r}, G = {G!r}")
    if (k1 or k2) and not G > 0:
        raise BdfError(f"{p.type} {pid}: K1 / K2 (shear flexibility) need MAT1 {p.mid} G > 0")

    def section_at(xi: float) -> BarSection:
        r = np.array([np.interp(xi, xs, col) for col in rows.T])
        return _si_section(to_values(r), k1, k2, mat, deck_units, card == "CBEAM")

    return xs, section_at, bool(np.all(rows == rows[0]))


def bar_section(model, pid: int, eid: int, deck_units, card: str = "CBAR") -> BarSection:
    """PBAR / PBEAM / PBARL / PBEAML + MAT1 of a CBAR / CBEAM of uniform section as SI section
    properties (:func:`bar_stations`).

    Parameters
    ----------
    model : pyNastran ``BDF``, cross-referenced.
    pid, eid : the element's PID and id; card : "CBAR" or "CBEAM" (which properties it takes).
    deck_units : (L m, Mu kg, T s, PARAM WTMASS) of one deck unit.

    Returns
    -------
    :class:`~asekit.structure.frame.BarSection`
        EA = E A, GJ = G J, EI1 = E I1, EI2 = E I2 (N, N m^2), mass = (rho A + NSM) WTMASS
        (kg/m).

    Raises
    ------
    BdfError
        Naming the card, its id and the field asekit cannot represent, or a section that
        varies along the element (a tapered PBEAM / PBEAML).
    """
    xs, section_at, uniform = bar_stations(model, pid, eid, deck_units, card)
    if not uniform:
        p = model.properties[pid]
        raise BdfError(f"{p.type} {pid}: the section varies along the beam (stations X/XB "
                       f"{xs.tolist()}); only a uniform section is supported here")
    return section_at(0.0)


def _add_bars(model, K, M, index, xyz, axes, coupled, deck_units) -> None:
    for eid in [i for c in BAR_CARDS for i in card_ids(model, c)]:
        e = model.elements[eid]
        _check_bar(e)
        ia, ib = index[e.ga], index[e.gb]
        v = bar_orientation(model, e, lambda g: axes[index[g]], lambda g: xyz[index[g]])
        try:
            xs, section_at, uniform = bar_stations(model, e.pid, eid, deck_units, e.type)
            if uniform:
                Ke, Me = global_bar_matrices(xyz[ia], xyz[ib], v, section_at(0.0), coupled)
            else:
                Ke, Me = global_tapered_bar_matrices(xyz[ia], xyz[ib], v, section_at, xs,
                                                     coupled)
        except BdfError:
            raise
        except ValueError as exc:
            raise BdfError(f"{e.type} {eid}: {exc}") from None
        d = np.r_[NODE_DOF * ia:NODE_DOF * ia + 6, NODE_DOF * ib:NODE_DOF * ib + 6]
        K[np.ix_(d, d)] += Ke
        M[np.ix_(d, d)] += Me


def _skew(x) -> np.ndarray:
    return np.array([[0.0, -x[2], x[1]], [x[2], 0.0, -x[0]], [-x[1], x[0], 0.0]])


def _add_conm2(model, M, index, deck_units) -> None:
    """CONM2: rigid mass m at offset x from its grid, inertia I about its centre, both in basic
    (CID 0): u_p = u + theta x x, so M_grid = G^T diag(m, m, m, I) G, G = [[1, -S(x)], [0, 1]]."""
    L, Mu, T, wt = deck_units
    for eid in card_ids(model, "CONM2"):
        m = model.masses[eid]
        if m.cid not in (0, None):
            raise BdfError(f"CONM2 {eid}: CID = {m.cid} is not supported (0: basic)")
        i = index[m.nid]
        x = np.asarray(m.X, float) * L
        inertia = np.asarray(m.Inertia(), float) * wt * Mu * L * L
        mass = m.mass * wt * Mu
        G = np.eye(6)
        G[:3, 3:] = -_skew(x)
        Mb = G.T @ np.block([[mass * np.eye(3), np.zeros((3, 3))],
                             [np.zeros((3, 3)), inertia]]) @ G
        d = np.r_[NODE_DOF * i:NODE_DOF * i + 6]
        M[np.ix_(d, d)] += Mb            # basic; the whole model is rotated to CD afterwards


def _components(c) -> list[int]:
    return [int(ch) for ch in str(c or "") if ch in "123456"]


def _spc_sets(model, name: str) -> list[int]:
    sets = sorted(set(model.spcs) | set(getattr(model, "spcadds", {})))
    cc = getattr(model, "case_control_deck", None)
    if cc is not None:
        for sub in cc.subcases.values():
            if "SPC" in sub:
                return [int(sub["SPC"][0])]
    if len(sets) > 1:
        raise BdfError(f"{name}: several SPC sets {sets} and no SPC in the case control")
    return sets


def _fixed_dofs(model, index, name: str) -> set:
    fixed = set()
    for nid, n in model.nodes.items():
        fixed |= {NODE_DOF * index[nid] + c - 1 for c in _components(n.ps)}
    for sid in _spc_sets(model, name):
        for s in model.spcs.get(sid, ()):
            if s.type == "SPC1":
                pairs = [(g, s.components) for g in s.node_ids]
            elif s.type == "SPC":
                if any(float(v or 0.0) for v in s.enforced):
                    raise BdfError(f"SPC {sid}: enforced displacement D is not supported (0)")
                pairs = list(zip(s.node_ids, s.components))
            else:
                raise BdfError(f"{s.type} {sid} is not supported (SPC, SPC1)")
            for g, comps in pairs:
                if g not in index:
                    raise BdfError(f"{s.type} {sid}: G = {g} is not a GRID")
                fixed |= {NODE_DOF * index[g] + c - 1 for c in _components(comps)}
    return fixed


def _link(dep: dict, what: str, i: int, d: int, comps, xyz, axes, who=None) -> None:
    """The rows of grid d's ``comps`` (CD components) from grid i's six DOFs (CD): rigid
    kinematics u_d = u_i - S(x_d - x_i) theta_i, theta_d = theta_i in basic (``who``: the
    card naming each row, for the chain resolution's messages)."""
    G = np.eye(6)
    G[:3, 3:] = -_skew(xyz[d] - xyz[i])
    Gc = np.kron(np.eye(2), axes[d]) @ G @ np.kron(np.eye(2), axes[i].T)
    for c in comps:
        row = NODE_DOF * d + c - 1
        if row in dep:
            raise BdfError(f"{what}: component {c} of its dependent grid is already dependent "
                           f"on another rigid element")
        dep[row] = tuple((NODE_DOF * i + k, float(Gc[c - 1, k])) for k in range(6)
                         if abs(Gc[c - 1, k]) > 1e-15)
        if who is not None:
            who[row] = what


def _dof_name(d: int, ids) -> str:
    return f"component {d % NODE_DOF + 1} of GRID {int(ids[d // NODE_DOF])}"


def _resolve_chains(dep: dict, who: dict, ids) -> dict:
    """Chained rigid elements (a dependent DOF of one independent in another) by substitution
    in dependency order: u_d = sum_j c_dj u_j with every u_j that is itself dependent replaced
    by its own (already resolved) row, until only true independents remain; exact, since each
    link is linear (Przemieniecki Sec. 11.7 applied link by link). A cycle (a DOF dependent,
    through the chain, on itself) is refused naming the cards."""
    done, state = {}, {}
    for root in sorted(dep):
        stack = [root]
        while stack:
            d = stack[-1]
            if d in done:
                stack.pop()
                continue
            state[d] = 1
            todo = [i for i, _ in dep[d] if i in dep and i not in done]
            cyc = [i for i in todo if state.get(i) == 1]
            if cyc:
                loop = stack[stack.index(cyc[0]):]
                raise BdfError("rigid elements form a cycle: " + " -> ".join(
                    f"{who.get(x, '?')} ({_dof_name(x, ids)})" for x in loop)
                    + " depends on itself (Nastran refuses it too)")
            if todo:
                stack.extend(todo[:1])
                continue
            acc = {}
            for i, c in dep[d]:
                for j, cj in (done[i] if i in dep else ((i, 1.0),)):
                    acc[j] = acc.get(j, 0.0) + c * cj
            done[d] = tuple((j, v) for j, v in sorted(acc.items()) if abs(v) > 1e-15)
            state[d] = 2
            stack.pop()
    return done


def rbe3_weights(x_ref, x_ind, comps, weights, axes_ind=None, refc=(1, 2, 3, 4, 5, 6),
                 axes_ref=None) -> np.ndarray:
    """The RBE3 interpolation: the reference grid's REFC components from the independent grids'
    weighted components, as a weighted least-squares fit of a rigid motion.

    MSC Nastran Quick Reference Guide, RBE3 ("defines the motion at a reference grid point as
    the weighted average of the motions at a set of other grid points"; remark: the
    independent components must be able to react the rigid-body motion of the REFC
    components) and the MSC Nastran Reference Manual's RBE3 description (MSC.Nastran 2005
    seminar NAS105, Sec. 2 "RBE3: how it works"): with S_i the rigid-body map of the reference
    grid's motion u_ref = (u, theta) (basic) to grid i's six DOFs,

        S_i = A_i [[I, -S(x_i - x_ref)], [0, I]],   A_i = diag(R_i, R_i) (basic -> grid i's CD),

    P_i the rows of grid i's components C_i and W_i = WT_i diag(1 translation, L_c^2
    rotation) (L_c the mean distance of the independent grids from the reference grid, which
    makes a rotational weight comparable with a translational one; asekit's reading of MSC's
    description, not compared with an f06: it matters only with rotations in Ci and a fit that
    is not exact), the reference motion is
    the least-squares fit of a rigid motion to the independent motions,

        u_ref = N^+ sum_i G_i^T W_i u_i,   N = sum_i G_i^T W_i G_i,   G_i = P_i S_i,

    and REFC component c (row a_c of A_ref) is a_c u_ref. N may be singular (a planar model's
    out-of-plane components react only its out-of-plane motion): a_c must then be normal to
    N's null space (every least-squares fit gives component c the same value), else it is
    refused. The constraint is the transpose of the load distribution F_i = W_i G_i N^+ F_ref,
    so an RBE3 carries loads and mass without stiffening: a rigid motion of the independent
    grids gives the same rigid motion at the reference grid (u_i = G_i u_ref fits exactly).

    Parameters
    ----------
    x_ref : (3,) reference grid position (basic, m).
    x_ind : (n, 3) independent grid positions (basic, m).
    comps : n component lists (1-6, each grid's CD system).
    weights : (n,) WT of each grid (> 0).
    axes_ind : (n, 3, 3) rows of each grid's CD axes in basic (default basic).
    refc : the reference grid's dependent components (1-6, its CD system).
    axes_ref : (3, 3) rows of the reference grid's CD axes in basic (default basic).

    Returns
    -------
    (len(refc), sum len(comps)) : the REFC components from the independent components, in
        the order grid by grid, component by component.

    Raises
    ------
    ValueError
        When a REFC component is not determined (the independent components cannot react its
        rigid-body motion, e.g. translations of collinear grids only).

    Examples
    --------
    Four equally weighted grids around the origin: the reference moves with their mean.

    >>> x = [[1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0]]
    >>> W = rbe3_weights([0, 0, 0], x, [[1, 2, 3]] * 4, [1.0] * 4, refc=[3])
    >>> W[0].round(12).tolist()[2::3]               # u_z of the reference from the four u_z
    [0.25, 0.25, 0.25, 0.25]
    """
    x_ref = np.asarray(x_ref, float)
    x_ind = np.atleast_2d(np.asarray(x_ind, float))
    n = x_ind.shape[0]
    axes_ind = np.array([np.eye(3)] * n) if axes_ind is None else np.asarray(axes_ind, float)
    A_ref = np.kron(np.eye(2), np.eye(3) if axes_ref is None else np.asarray(axes_ref, float))
    wt = np.asarray(weights, float)
    if wt.shape != (n,) or len(comps) != n or not np.all(wt > 0):
        raise ValueError("weights must hold one WT > 0 per independent grid, and comps one "
                         "component list per grid")
    lc = float(np.mean(np.linalg.norm(x_ind - x_ref, axis=1)))
    rows, wdiag = [], []
    for i in range(n):
        S = np.eye(6)
        S[:3, 3:] = -_skew(x_ind[i] - x_ref)
        G = np.kron(np.eye(2), axes_ind[i]) @ S
        for c in comps[i]:
            rows.append(G[int(c) - 1])
            wdiag.append(wt[i] * (1.0 if int(c) <= 3 else lc * lc))
    G = np.array(rows).reshape(-1, 6)
    GW = G.T * np.array(wdiag)
    lam, V = np.linalg.eigh(GW @ G)
    tol = 1e-10 * max(float(lam.max(initial=0.0)), 1e-300)
    null, keep = V[:, lam <= tol], lam > tol
    a = A_ref[[int(c) - 1 for c in refc]]
    if null.size and np.abs(a @ null).max() > 1e-8:
        raise ValueError("the independent grids' components cannot react the reference "
                         "grid's rigid-body motion in REFC (e.g. translations of collinear "
                         "grids only: add a rotation to Ci, MSC QRG RBE3 remark)")
    Ninv = (V[:, keep] / lam[keep]) @ V[:, keep].T
    return a @ Ninv @ GW


def _rbe3_link(dep: dict, r, index, xyz, axes, who: dict) -> None:
    """RBE3 (:func:`rbe3_weights`): the REFC components (CD) of REFGRID as dependent rows of
    the independent grids' weighted components; the UM alternative and a REFGRID that is also
    independent are refused naming the card and field."""
    what = f"RBE3 {r.eid}"
    if r.Gmi:
        raise BdfError(f"{what}: UM (GM1 = {r.Gmi[0]}) is not supported (blank: the REFC "
                       f"components of REFGRID are the dependent ones)")
    ref = int(r.refgrid)
    if ref not in index:
        raise BdfError(f"{what}: REFGRID = {ref} is not a GRID")
    grids, comps, wts = [], [], []
    for wt, c, gs in zip(r.weights, r.comps, r.Gijs):
        for g in gs:
            g = int(g)
            if g == ref:
                raise BdfError(f"{what}: REFGRID {ref} is also an independent grid Gi,j "
                               f"(Nastran refuses it too)")
            if g not in index:
                raise BdfError(f"{what}: Gi,j = {g} is not a GRID")
            if not (wt is not None and float(wt) > 0):
                raise BdfError(f"{what}: WT = {wt!r} of G {g} must be > 0")
            grids.append(index[g])
            comps.append(_components(c))
            wts.append(float(wt))
    d = index[ref]
    refc = _components(r.refc)
    try:
        Wc = rbe3_weights(xyz[d], xyz[grids], comps, wts, axes[grids], refc, axes[d])
    except ValueError as exc:
        raise BdfError(f"{what}: {exc}") from None
    cols = [NODE_DOF * g + c - 1 for g, cs in zip(grids, comps) for c in cs]
    for c, wrow in zip(refc, Wc):
        row = NODE_DOF * d + c - 1
        if row in dep:
            raise BdfError(f"{what}: REFC component {c} of REFGRID {ref} is already dependent "
                           f"on another rigid element")
        acc = {}
        for j, v in zip(cols, wrow):
            acc[j] = acc.get(j, 0.0) + float(v)
        dep[row] = tuple((j, v) for j, v in sorted(acc.items()) if abs(v) > 1e-15)
        who[row] = what


def _rigid_links(model, index, xyz, axes, fixed: set, ids) -> tuple:
    """RBE2 / RBAR / RBE3 as dependent DOF rows (module docstring)."""
    dep, who = {}, {}
    for eid in sorted(model.rigid_elements):
        r = model.rigid_elements[eid]
        if r.type == "RBE2":
            for g in r.Gmi:
                _link(dep, f"RBE2 {eid} (GM {g})", index[r.gn], index[g], _components(r.cm),
                      xyz, axes, who)
        elif r.type == "RBAR":
            if str(r.cna) != "123456" or str(r.cnb or "").strip() or str(r.cma or "").strip():
                raise BdfError(f"RBAR {eid}: CNA = {r.cna!r}, CNB = {r.cnb!r}, CMA = {r.cma!r}: "
                               f"only GA independent in all six components is supported "
                               f"(CNA 123456, CNB and CMA blank)")
            _link(dep, f"RBAR {eid}", index[r.ga], index[r.gb], _components(r.cmb or "123456"),
                  xyz, axes, who)
        elif r.type == "RBE3":
            _rbe3_link(dep, r, index, xyz, axes, who)
        else:
            raise BdfError(f"{r.type} {eid} is not supported (RBE2, RBAR, RBE3)")
    dep = _resolve_chains(dep, who, ids)
    if fixed & set(dep):
        d = min(fixed & set(dep))
        raise BdfError(f"an SPC / GRID PS constrains component {d % NODE_DOF + 1} of a grid "
                       f"an RBE2 / RBAR makes dependent (Nastran refuses it too)")
    return tuple(sorted(dep.items()))


def deck_param(model, key: str, default):
    """The first value of PARAM ``key`` (e.g. ``"WTMASS"``), or ``default`` without it.

    Examples
    --------
    >>> from types import SimpleNamespace as NS
    >>> deck_param(NS(params={"WTMASS": NS(values=[0.00259])}), "WTMASS", 1.0)
    0.00259
    """
    p = model.params.get(key)
    return p.values[0] if p is not None else default


def read_stick_deck(path, units: str = "SI") -> StickModel:
    """Read a CBAR stick-model deck's structure (module docstring) into SI matrices.

    Parameters
    ----------
    path : str or Path
        The deck.
    units : str
        Its unit system, a key of :data:`asekit.io.bdf.UNITS`.

    Returns
    -------
    StickModel
        Raises :class:`asekit.io.bdf.BdfError` (one line: card, id, field) for what it cannot
        represent.

    Examples
    --------
    >>> from asekit.util.paths import DATA_DIR                      # doctest: +SKIP
    >>> sm = read_stick_deck(DATA_DIR / "benchmarks/pt145/pt145.bdf",
    ...                      units="in-lbf-s")                          # doctest: +SKIP
    >>> sm.K.shape, sm.coupled                                      # doctest: +SKIP
    ((66, 66), True)
    """
    if units not in UNITS:
        raise ValueError(f"units must be one of {sorted(UNITS)}, got {units!r}")
    BDF = need_pynastran()
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"BDF not found: {path}")
    model = BDF(debug=None)
    try:
        model.read_bdf(str(path), xref=True)
    except Exception as exc:  # pyNastran's own error: card and field in its words
        raise BdfError(f"{path.name}: {str(exc).strip().splitlines()[0]}") from None
    _refuse_cards(model, path.name)
    L, Mu, T = UNITS[units]
    wt = float(deck_param(model, "WTMASS", 1.0))
    coupled = int(deck_param(model, "COUPMASS", -1)) > 0
    deck_units = (L, Mu, T, wt)
    ids, xyz, axes = _grids(model, L)
    index = {int(g): i for i, g in enumerate(ids)}
    n = NODE_DOF * len(ids)
    K, M = np.zeros((n, n)), np.zeros((n, n))
    _add_bars(model, K, M, index, xyz, axes, coupled, deck_units)
    _add_conm2(model, M, index, deck_units)
    # basic -> each grid's CD system: u_basic = A u_cd, A = diag(R^T, R^T) per grid
    A = sla.block_diag(*[np.kron(np.eye(2), a.T) for a in axes])
    K, M = A.T @ K @ A, A.T @ M @ A
    _add_cmass2_si(model, M, index, deck_units)
    fixed = _fixed_dofs(model, index, path.name)
    rigid = _rigid_links(model, index, xyz, axes, fixed, ids)
    notes = (f"{len(card_ids(model, 'CBAR'))} CBAR, {len(card_ids(model, 'CBEAM'))} CBEAM, "
             f"{len(ids)} GRID; bar mass "
             f"{'consistent (PARAM COUPMASS 1)' if coupled else 'lumped'}",)
    return StickModel(node_ids=ids, xyz=xyz, cd_axes=axes, K=0.5 * (K + K.T),
                      M=0.5 * (M + M.T), fixed=tuple(sorted(fixed)), coupled=coupled,
                      notes=notes, path=str(path), units=units, rigid=rigid)


def _add_cmass2_si(model, M, index, deck_units) -> None:
    """CMASS2 in SI: the scalar element's matrix m [[1, -1], [-1, 1]] (one grid: m) with each
    entry scaled by the SI factor of its two DOFs, Mu s_i s_j (s = 1 for a translation, L for
    a rotation: a mass in kg, a rotary inertia in kg m^2, a coupling in kg m)."""
    L, Mu, T, wt = deck_units
    for eid in card_ids(model, "CMASS2"):
        c = model.masses[eid]
        dofs, scale = [], []
        for g, comp in ((c.nodes[0], c.c1), (c.nodes[1], c.c2)):
            if not g:
                continue
            if g not in index or not comp or not 1 <= int(comp) <= 6:
                raise BdfError(f"CMASS2 {eid}: G/C = {g}/{comp}: a GRID and a component 1-6 "
                               f"are required")
            dofs.append(NODE_DOF * index[g] + int(comp) - 1)
            scale.append(1.0 if int(comp) <= 3 else L)
        if not dofs:
            continue
        pattern = np.array([[1.0, -1.0], [-1.0, 1.0]]) if len(dofs) == 2 else np.ones((1, 1))
        sc = np.asarray(scale)
        M[np.ix_(dofs, dofs)] += c.mass * wt * Mu * pattern * np.outer(sc, sc)


def _shifted_eigh(K: np.ndarray, M: np.ndarray, n: int):
    """The n largest lambda of M phi = lambda (K + s M) phi, lambda = 1 / (omega^2 + s): s = 0
    when K is positive definite, else (free-free: rigid-body modes, omega = 0) the shift
    s = 1e-6 max diag K / max diag M, which makes K + s M positive definite whenever every
    mode of zero stiffness carries mass; a massless mechanism, or more zero-stiffness modes
    than a free body's six rigid-body modes (a mechanism), is refused. Returns
    (lambda ascending, phi, s)."""
    idx = [K.shape[0] - n, K.shape[0] - 1]
    try:
        return (*sla.eigh(M, K, subset_by_index=idx), 0.0)
    except np.linalg.LinAlgError:
        pass
    s = 1e-6 * np.abs(np.diag(K)).max() / max(np.abs(np.diag(M)).max(), 1e-300)
    try:
        lam_all, phi_all = sla.eigh(M, K + s * M)
    except np.linalg.LinAlgError:
        lam_all = None
    n_zero = 0 if lam_all is None else int(np.sum(1.0 / np.maximum(lam_all, 1e-300) - s
                                                   < 1e-6 * s))
    if lam_all is None or n_zero > 6:
        raise BdfError(f"the stick model's stiffness is singular on its free DOFs (a "
                       f"mechanism: {'massless' if lam_all is None else n_zero} zero-stiffness "
                       f"modes, a free body has at most 6 rigid-body modes): constrain them "
                       f"with SPC or GRID PS")
    return lam_all[idx[0]:], phi_all[:, idx[0]:], s


def stick_modes(model: StickModel, n_modes: int = 6) -> StickModes:
    """Normal modes K phi = omega^2 M phi of the free DOFs, solved as M phi = lambda K phi,
    lambda = 1 / omega^2 (shifted, K + s M, when free-free: :func:`_shifted_eigh`), for the
    largest lambda: exact with DOFs that carry no mass (e.g. the
    twist of a bar without torsional inertia, in any frame: lambda = 0 there) and accurate for
    the lowest modes of stiff bars (no stiffness-times-mass-basis mixing).

    Parameters
    ----------
    model : :class:`StickModel`.
    n_modes : how many, lowest first (>= 1).

    Returns
    -------
    StickModes

    Examples
    --------
    One clamped-free Hermite bar (E I = m = L = 1): omega_1 = sqrt(12.48) = 3.533 (the exact
    beam: 1.875^2 = 3.516)

    >>> from asekit.structure.frame import BarSection, global_bar_matrices
    >>> K, M = global_bar_matrices([0, 0, 0], [1, 0, 0], [0, 0, 1],
    ...                            BarSection(1e6, 1.0, 1.0, 1.0, 1.0))
    >>> sm = StickModel(np.array([1, 2]), np.zeros((2, 3)), np.array([np.eye(3)] * 2), K, M,
    ...                 tuple(range(6)), True)
    >>> round(float(stick_modes(sm, 1).frequencies_hz[0] * 2 * np.pi), 3)
    3.533
    """
    free = model.free
    Tr = model.reduction()
    K = Tr.T @ model.K @ Tr
    M = Tr.T @ model.M @ Tr
    n = min(int(n_modes), free.size)
    if n < 1:
        raise ValueError(f"n_modes must be >= 1, got {n_modes}")
    lam, phi, shift = _shifted_eigh(K, M, n)
    lam, phi = lam[::-1], phi[:, ::-1]
    if lam[-1] <= 1e-14 * lam[0]:
        raise BdfError(f"fewer than {n} modes carry mass (the DOFs without mass have no "
                       f"frequency): ask for fewer modes")
    phi = phi / np.sqrt(np.einsum("ij,ik,kj->j", phi, M, phi))
    full = Tr @ phi
    w2 = 1.0 / lam - shift
    return StickModes(frequencies_hz=np.sqrt(np.clip(w2, 0.0, None)) / (2 * np.pi),
                      shapes=full)


def _rigid_body_vectors(model: StickModel) -> np.ndarray:
    """(6 n, 6): unit rigid-body motions of every grid (translations along basic x, y, z and
    rotations about basic x, y, z through the origin), in each grid's CD components."""
    U = np.zeros((model.K.shape[0], 6))
    for i, (r, R) in enumerate(zip(model.xyz, model.cd_axes)):
        for d in range(6):
            t, rot = np.zeros(3), np.zeros(3)
            if d < 3:
                t[d] = 1.0
            else:
                rot[d - 3] = 1.0
                t = np.cross(rot, r)
            U[NODE_DOF * i:NODE_DOF * i + 3, d] = R @ t
            U[NODE_DOF * i + 3:NODE_DOF * i + 6, d] = R @ rot
    return U


def residual_vector_modes(model: StickModel, modes: StickModes, n_total: int) -> StickModes:
    """The modal basis augmented to ``n_total`` modes by residual vectors for inertia-relief
    loads (MSC Nastran case control RESVEC, INRLOD; the basis a SOL 145 deck gets when PARAM
    LMODES exceeds the EIGR / EIGRL ND).

    Loads: the inertia of the six rigid-body accelerations, f_d = M u_d (u_d a unit
    translation or rotation of the whole model), with inertia relief against the free
    rigid-body modes phi_r (f <- f - M phi_r phi_r^T f, so that K u = f is consistent). Static
    responses u_d (solved with K + M phi_r phi_r^T M, nonsingular and equal to K on them) are
    made M-orthogonal to the eigenvectors; the Rayleigh-Ritz eigenproblem on their span gives
    the augmented modes, lowest first (MSC Nastran Dynamic Analysis User's Guide, residual
    vectors). On pyNastran's bah_plane_qhh deck (8 eigenvectors, grid 1 free in plunge and
    pitch) this gives the f06's "AFTER AUGMENTATION OF RESIDUAL VECTORS" 41.22899, 56.55734,
    120.5794, 180.3152 Hz to 1e-6.

    Parameters
    ----------
    model : :class:`StickModel`; modes : its eigenvectors (:func:`stick_modes`);
    n_total : modes wanted (LMODES); at most len(modes) + the independent residual vectors.

    Returns
    -------
    StickModes, the eigenvectors followed by the residual-vector modes (mass-normalised).

    Examples
    --------
    A clamped two-bar cantilever (E I = m = L = 1), one eigenvector plus one residual vector:
    the augmented frequency lies above the first and no higher than the exact second mode.

    >>> from asekit.structure.frame import BarSection, global_bar_matrices
    >>> sec = BarSection(1e6, 1.0, 1.0, 1.0, 1.0)
    >>> K, M = np.zeros((18, 18)), np.zeros((18, 18))
    >>> for a, b in ((0, 1), (1, 2)):
    ...     k, m = global_bar_matrices([0.5 * a, 0, 0], [0.5 * b, 0, 0], [0, 0, 1], sec)
    ...     ix = np.r_[6 * a:6 * a + 6, 6 * b:6 * b + 6]
    ...     K[np.ix_(ix, ix)] += k
    ...     M[np.ix_(ix, ix)] += m
    >>> sm = StickModel(np.array([1, 2, 3]), np.array([[0, 0, 0], [.5, 0, 0], [1, 0, 0]]),
    ...                 np.array([np.eye(3)] * 3), K, M, tuple(range(6)), True)
    >>> m1, m2 = stick_modes(sm, 1), stick_modes(sm, 2)
    >>> f = residual_vector_modes(sm, m1, 2).frequencies_hz
    >>> bool(f[0] == m1.frequencies_hz[0] and f[1] >= m2.frequencies_hz[1] * (1 - 1e-9))
    True
    """
    n_eig = modes.shapes.shape[1]
    if n_total <= n_eig:
        return modes
    free, Tr = model.free, model.reduction()
    K, M = Tr.T @ model.K @ Tr, Tr.T @ model.M @ Tr
    phi = modes.shapes[free]
    f_hz = modes.frequencies_hz
    rigid = phi[:, f_hz <= 1e-5 * max(float(f_hz.max()), 1e-300)]
    F = Tr.T @ (model.M @ _rigid_body_vectors(model))
    F = F - M @ rigid @ (rigid.T @ F)
    U = np.linalg.solve(K + M @ rigid @ rigid.T @ M, F)
    U = U - phi @ (phi.T @ M @ U)
    w, Q = np.linalg.eigh(U.T @ M @ U)
    ok = w > 1e-10 * max(float(w.max()), 1e-300)
    if not ok.any():
        return modes
    V = U @ (Q[:, ok] / np.sqrt(w[ok]))
    lam, X = sla.eigh(V.T @ K @ V, V.T @ M @ V)
    n_add = min(n_total - n_eig, lam.size)
    R = V @ X[:, :n_add]
    R = R / np.sqrt(np.einsum("ij,ik,kj->j", R, M, R))
    return replace(modes, frequencies_hz=np.r_[f_hz, np.sqrt(np.clip(lam[:n_add], 0.0, None))
                                                / (2 * np.pi)],
                   shapes=np.c_[modes.shapes, Tr @ R])


# ---------------------------------------------------------------------------------------------
# SPLINE2 (beam spline) and the deck's flutter requests
# ---------------------------------------------------------------------------------------------
def _hermite_row(s_nodes: np.ndarray, s: float):
    """Weights of (w_j, w'_j) for w(s) and w'(s) and of theta_j for theta(s), theta'(s) on the
    axis stations ``s_nodes`` (ascending): cubic Hermite between stations (a beam loaded only
    at its stations), straight beyond the ends (an unloaded beam's extension)."""
    n = s_nodes.size
    ww, wd, dw, dd, tt, td = (np.zeros(n) for _ in range(6))
    if s <= s_nodes[0] or s >= s_nodes[-1]:
        j = 0 if s <= s_nodes[0] else n - 1
        ww[j], wd[j], dd[j], tt[j] = 1.0, s - s_nodes[j], 1.0, 1.0
        return ww, wd, dw, dd, tt, td
    j = int(np.searchsorted(s_nodes, s) - 1)
    h = s_nodes[j + 1] - s_nodes[j]
    t = (s - s_nodes[j]) / h
    ww[[j, j + 1]] = 1 - 3 * t * t + 2 * t ** 3, 3 * t * t - 2 * t ** 3
    wd[[j, j + 1]] = h * (t - 2 * t * t + t ** 3), h * (t ** 3 - t * t)
    dw[[j, j + 1]] = (-6 * t + 6 * t * t) / h, (6 * t - 6 * t * t) / h
    dd[[j, j + 1]] = 1 - 4 * t + 3 * t * t, 3 * t * t - 2 * t
    tt[[j, j + 1]] = 1 - t, t
    td[[j, j + 1]] = -1 / h, 1 / h
    return ww, wd, dw, dd, tt, td


def beam_axis_spline(s_nodes, points_s, points_x, ex_flow: float, ey_flow: float):
    """Interpolation of a beam spline's axis motion to points off the axis (MSC Nastran
    SPLINE2 with its grids attached in deflection, slope and twist: DZ = DTHX = DTHY = 0).

    The spline is a beam along its y axis (MSC Nastran Aeroelastic Analysis User's Guide,
    Sec. 2.3 "Beam splines"): deflection w(s) along its z axis and slope w' = theta_x
    interpolated by the cubic Hermite functions of a beam loaded only at the stations (exact
    for it), twist theta_y linearly, both straight beyond the end stations. A point at chordwise
    distance x from the axis moves

        h = w(s) - x theta_y(s),   dh/dX = (w'(s) - x theta_y'(s)) e_y,X - theta_y(s) e_x,X,

    X the flow direction (the basic x axis) and e_x,X, e_y,X the spline axes' X components.

    Parameters
    ----------
    s_nodes : (n,) stations along the axis (m), strictly ascending.
    points_s, points_x : (p,) the points' axial and chordwise coordinates (m).
    ex_flow, ey_flow : X components of the spline's x and y axes.

    Returns
    -------
    (H, D) : (p, 3 n) matrices giving h and dh/dX from the station values
        (w_1..w_n, theta_x,1..theta_x,n, theta_y,1..theta_y,n) (m and rad).

    Examples
    --------
    A rigid pitch theta_y = 1 about the axis: h = -x, dh/dX = -e_x,X.

    >>> H, D = beam_axis_spline([0.0, 1.0], [0.5], [0.2], 1.0, 0.0)
    >>> (H @ [0, 0, 0, 0, 1, 1]).round(12).tolist(), (D @ [0, 0, 0, 0, 1, 1]).tolist()
    ([-0.2], [-1.0])
    """
    s_nodes = np.asarray(s_nodes, float)
    if s_nodes.ndim != 1 or s_nodes.size < 2 or np.any(np.diff(s_nodes) <= 0):
        raise ValueError("s_nodes must hold >= 2 strictly ascending stations")
    ps, px = np.asarray(points_s, float), np.asarray(points_x, float)
    n = s_nodes.size
    H, D = np.zeros((ps.size, 3 * n)), np.zeros((ps.size, 3 * n))
    for i, (s, x) in enumerate(zip(ps, px)):
        ww, wd, dw, dd, tt, td = _hermite_row(s_nodes, s)
        H[i] = np.r_[ww, wd, -x * tt]
        D[i] = np.r_[dw * ey_flow, dd * ey_flow, -x * td * ey_flow - tt * ex_flow]
    return H, D


def _check_spline2(s) -> bool:
    """SPLINE2 USAGE BOTH; True when DZ / DTHX / DTHY ask for smoothing (> 0: attachment
    flexibility), which :func:`_check_rigid_stations` then accepts only where it changes
    nothing."""
    smooth = False
    for name, v in (("DZ", s.dz), ("DTHX", s.dthx), ("DTHY", s.dthy)):
        if v not in (0, 0.0):
            if v is None or v < 0:
                raise BdfError(f"SPLINE2 {s.eid}: {name} = {v!r} is not supported (>= 0.0)")
            smooth = True
    if str(s.usage or "BOTH").upper() != "BOTH":
        raise BdfError(f"SPLINE2 {s.eid}: USAGE = {s.usage!r} is not supported (BOTH)")
    return smooth


def _check_rigid_stations(s, st: np.ndarray, q: np.ndarray) -> None:
    """A smoothing SPLINE2 (DZ, DTHX or DTHY > 0) is accepted where its grids move rigidly in
    every mode (w linear in s, theta_x = dw/ds and theta_y constant, to 1e-8): a beam spline
    fits such data with no strain energy and no attachment force, so smoothing and
    interpolating splines coincide (MSC Aeroelastic Analysis User's Guide, Sec. 2.3)."""
    n = st.size
    w, tx, ty = q[:n], q[n:2 * n], q[2 * n:]
    span = max(float(np.ptp(st)), 1e-12)
    A = np.c_[np.ones(n), st - st.mean()]
    coef = np.linalg.lstsq(A, w, rcond=None)[0]
    scale = np.abs(w).max(0) / span + np.abs(tx).max(0) + np.abs(ty).max(0) + 1e-300
    err = np.max(np.r_[np.abs(A @ coef - w) / span, np.abs(tx - coef[1]), np.abs(ty - ty[:1])]
                 / scale, axis=0)
    if n < 2 or np.max(err) > 1e-8:
        raise BdfError(f"SPLINE2 {s.eid}: DZ/DTHX/DTHY = {s.dz!r}/{s.dthx!r}/{s.dthy!r} "
                       f"(smoothing) is supported only where the SETG grids move rigidly; "
                       f"0.0 (attached) otherwise")


def _spline2_station_matrix(model, s, sm: StickModel, L: float, aero=None):
    """(3 n_g, 6 n_nodes) map from the model's DOFs to the spline stations' (w, theta_x,
    theta_y), the stations (sorted, m), the spline frame (rows e_x, e_y, e_z) and its origin;
    ``aero`` the ACSID axes (rows, basic), whose z the spline's z must be along."""
    c = model.coords[s.cid] if s.cid else None
    axes = np.asarray(c.beta(), float) if c is not None else np.eye(3)
    origin = (np.asarray(c.origin, float) if c is not None else np.zeros(3)) * L
    if abs(axes[2] @ (np.eye(3) if aero is None else aero)[2]) < 1 - 1e-6:
        raise BdfError(f"SPLINE2 {s.eid}: CID = {s.cid}: the spline's z axis must be normal "
                       f"to the boxes (the z axis of AERO ACSID)")
    grids = [int(g) for g in model.sets[s.setg].ids]
    idx = [int(np.flatnonzero(sm.node_ids == g)[0]) for g in grids]
    st = (sm.xyz[idx] - origin) @ axes[1]
    order = np.argsort(st)
    if np.any(np.diff(st[order]) <= 1e-9 * max(1.0, np.ptp(st))):
        raise BdfError(f"SPLINE2 {s.eid}: SETG {s.setg}: two grids at the same station")
    n, N = len(idx), sm.K.shape[0]
    S = np.zeros((3 * n, N))
    for r, k in enumerate(order):
        i = idx[k]
        Rt = sm.cd_axes[i].T                           # CD components -> basic
        d = NODE_DOF * i
        S[r, d:d + 3] = axes[2] @ Rt                    # w
        S[n + r, d + 3:d + 6] = axes[0] @ Rt            # theta_x (the slope)
        S[2 * n + r, d + 3:d + 6] = axes[1] @ Rt        # theta_y (the twist)
    return S, st[order], axes, origin


def spline2_box_modes(model, sm: StickModel, modes: StickModes, mesh, box_ids, L: float,
                      aero=None):
    """The modes on the boxes through the deck's SPLINE2 cards (each box on one spline):
    :func:`beam_axis_spline` at the control points (h, dh/dx) and load points (h).

    ``aero`` (rows: the ACSID's axes in basic, :func:`asekit.io.bdf.aero_axes`; default basic)
    is the frame of ``mesh``: a box point p_a is at basic p_a R, the flow X is R's first row
    (so the spline axes' X components are e_x . R_x, e_y . R_x) and h, dh/dX are along R's z:
    the spline's w (along its own z) times sign(e_z . R_z)."""
    from asekit.aero.spline import BoxModes
    R = np.eye(3) if aero is None else np.asarray(aero, float)
    n_b, n_m = len(box_ids), modes.shapes.shape[1]
    h_cp, d_cp, h_lp = np.zeros((n_b, n_m)), np.zeros((n_b, n_m)), np.zeros((n_b, n_m))
    done = np.zeros(n_b, bool)
    pos = {int(b): i for i, b in enumerate(box_ids)}
    for s in model.splines.values():
        if s.type != "SPLINE2":
            raise BdfError(f"{s.type} {s.eid}: a stick deck's splines must be SPLINE2")
        smooth = _check_spline2(s)
        rows = [pos[b] for b in range(int(s.box1), int(s.box2) + 1) if b in pos]
        S, st, axes, o = _spline2_station_matrix(model, s, sm, L, R)
        q = S @ modes.shapes
        if smooth:
            _check_rigid_stations(s, st, q)
        sz = float(np.sign(axes[2] @ R[2]))
        for pts, out, dout in ((mesh.control_point, h_cp, d_cp), (mesh.load_point, h_lp, None)):
            rel = pts[rows] @ R - o
            H, D = beam_axis_spline(st, rel @ axes[1], rel @ axes[0], axes[0] @ R[0],
                                    axes[1] @ R[0])
            out[rows] = sz * (H @ q)
            if dout is not None:
                dout[rows] = sz * (D @ q)
        done[rows] = True
    if not done.all():
        raise BdfError(f"boxes {[int(b) for b in np.asarray(box_ids)[~done][:10]]} are on no "
                       f"SPLINE2")
    return BoxModes(h_cp, d_cp, h_lp)


def requested_mode_count(model) -> int:
    """The number of eigenvectors a stick deck asks for: PARAM LMODES (> 0), else the ND of its
    first EIGR / EIGRL, else 6; never more than that ND when both are given.

    Nastran fills the LMODES modes beyond the ND eigenvectors with residual vectors (case
    control RESVEC, on by default in SOL 145: pyNastran's bah_plane_qhh.f06, "REAL EIGENVALUES
    (AFTER AUGMENTATION OF RESIDUAL VECTORS)", 8 eigenvectors + 4 residual vectors, of which
    LMODES 10 keeps 2, at 41.23 and 56.56 Hz); :func:`stick_flutter` adds them with
    :func:`residual_vector_modes` (:func:`lmodes_beyond_nd`). Taking further eigenvectors
    instead (24.3 and 32.1 Hz there) would be neither Nastran's basis nor the deck's ND.

    Examples
    --------
    >>> from types import SimpleNamespace as NS
    >>> requested_mode_count(NS(params={}, methods={10: NS(nd=4)}))
    4
    >>> requested_mode_count(NS(params={"LMODES": NS(values=[10])}, methods={1: NS(nd=8)}))
    8
    """
    nd = next((int(m.nd) for m in model.methods.values() if getattr(m, "nd", None)), None)
    p = model.params.get("LMODES")
    if p is not None and int(p.values[0]) > 0:
        return int(p.values[0]) if nd is None else min(int(p.values[0]), nd)
    return 6 if nd is None else nd


def _resvec_off(model) -> bool:
    """Case control RESVEC = NO (or NOINRL: no inertia-relief residual vectors)."""
    cc = getattr(model, "case_control_deck", None)
    for sc in ([] if cc is None else [cc.subcases.get(1), cc.subcases.get(0)]):
        try:
            value, options = sc.get_parameter("RESVEC")[:2]
        except (AttributeError, KeyError):          # no subcase, or no RESVEC in it
            continue
        words = " ".join(str(x) for x in [value, *(options or [])]).upper()
        return bool(set(words.replace(",", " ").replace("(", " ").replace(")", " ").split())
                    & {"NO", "NOINRL"})
    return False


def lmodes_beyond_nd(model) -> tuple[int, str | None]:
    """(LMODES, note) when a deck's PARAM LMODES exceeds its EIGR / EIGRL ND and residual
    vectors are not switched off (RESVEC = NO / NOINRL), else (the eigenvector count, None).

    Examples
    --------
    >>> from types import SimpleNamespace as NS
    >>> n, note = lmodes_beyond_nd(NS(params={"LMODES": NS(values=[10])}, methods={1: NS(nd=8)},
    ...                                case_control_deck=None))
    >>> n, note[:31]
    (10, 'PARAM LMODES 10 > EIGR/EIGRL ND')
    """
    p = model.params.get("LMODES")
    n = requested_mode_count(model)
    if p is None or int(p.values[0]) <= n or _resvec_off(model):
        return n, None
    lm = int(p.values[0])
    return lm, (f"PARAM LMODES {lm} > EIGR/EIGRL ND {n}: modes {n + 1}-{lm} are residual vectors "
                f"for inertia-relief loads (Nastran's RESVEC default, INRLOD)")


@dataclass(frozen=True)
class StickFlutter:
    """The flutter of a stick deck: ``modes`` (:class:`StickModes` used), ``results`` one
    :class:`asekit.io.bdf.DeckFlutter` per FLUTTER card (the case control's FMETHOD first),
    ``b_ref`` (m)."""

    modes: StickModes
    results: tuple
    b_ref: float


@dataclass(frozen=True)
class _Table:
    """The GAF tables by Mach, read as :func:`asekit.io.bdf.deck_flutter` reads a database."""

    gafs: dict

    def at(self, mach: float):
        if mach not in self.gafs:
            raise BdfError(f"Mach {mach:g} of a FLUTTER card is not on an MKAERO1 card")
        return self.gafs[mach]


def is_stick_deck(path) -> bool:
    """True when the deck's structure is bars (CBAR / CBEAM) and no shell: :func:`stick_flutter`'s
    deck, not :func:`asekit.io.bdf.read_bdf`'s."""
    model = need_pynastran()(debug=None)
    try:
        model.read_bdf(str(path), xref=False)
    except Exception:           # read_bdf reports the deck's error in its own words
        return False
    cc = model.card_count
    return any(c in cc for c in BAR_CARDS) and not any(c in cc for c in ("CQUAD4", "CTRIA3"))


def stick_flutter(path, units: str = "SI", ks=None) -> StickFlutter:
    """Run every FLUTTER card (K, KE, PK, PKNL as Nastran defines them,
    :mod:`asekit.aeroelastic.nastran`) of a CBAR stick deck with asekit's doublet lattice on
    the CAERO1 boxes and the SPLINE2 beam spline; PARAM LMODES (else EIGR/EIGRL ND) modes.

    Parameters
    ----------
    path : the deck; units : its unit system (:data:`asekit.io.bdf.UNITS`).
    ks : reduced frequencies of the aerodynamic table (default the MKAERO1 list, which the
        method interpolates as the FLUTTER card's IMETH says, as Nastran does; outside the
        list asekit holds the end values, :meth:`asekit.aero.gaf.TabulatedGaf.parts`).

    Returns
    -------
    StickFlutter
    """
    from asekit.aero.gaf import TabulatedGaf, gaf_from_box_modes
    from asekit.aeroelastic.statespace import modal_arrays

    sm = read_stick_deck(path, units)
    model = need_pynastran()(debug=None)
    model.read_bdf(str(path), xref=True)
    L, Mu, T = UNITS[units]
    deck = Deck(model, Path(path).name, L, Mu, T)
    if not model.caeros or not model.flutters:
        raise BdfError(f"{deck.name}: no CAERO1 or no FLUTTER card: nothing to run")
    b_ref, rho_ref, symmetric = read_aero_card(deck, rotated_acsid=True)  # the flow axis
    for c in model.caeros.values():
        check_caero1(deck, c)
    mesh, box_ids, aero = deck_boxes_aero(model, L)        # in ACSID's axes, nonplanar
    machs, table_ks = read_mkaero1(model, deck)
    requests = [read_flutter(model, f, rho_ref, deck) for f in model.flutters.values()]
    fm = case_value(model, "FMETHOD")
    requests.sort(key=lambda r: r.sid != fm)
    modes = stick_modes(sm, requested_mode_count(model))
    n_lmodes, note = lmodes_beyond_nd(model)
    if note:
        modes = residual_vector_modes(sm, modes, n_lmodes)
        modes = replace(modes, notes=modes.notes + (note,))
    bm = spline2_box_modes(model, sm, modes, mesh, box_ids, L, aero)
    w = 2 * np.pi * modes.frequencies_hz
    modal = modal_arrays(M=np.eye(w.size), K=np.diag(w ** 2))
    ks = np.asarray(table_ks if ks is None else ks, float)
    db = _Table({m: TabulatedGaf(ks, gaf_from_box_modes(bm, mesh, m, ks, b_ref, symmetric),
                                 b_ref, m) for m in machs})
    return StickFlutter(modes=modes, b_ref=b_ref,
                        results=tuple(solve_request(r, modal, db) for r in requests))


# ---------------------------------------------------------------------------------------------
# export of a [[beam]] (a StraightBeam) as a CBAR deck
# ---------------------------------------------------------------------------------------------
def _bar_mass(beam) -> np.ndarray:
    """The mass the deck's CBARs carry (PBAR NSM = m, PARAM COUPMASS 1), global frame."""
    n = NODE_DOF * beam.n_nodes
    M = np.zeros((n, n))
    x = beam.nodes
    for e, sec in enumerate(beam.sections):
        bar = BarSection(sec.ea, sec.gj, sec.ei_flap, sec.ei_chord, sec.mass)
        _, Me = global_bar_matrices(x[e], x[e + 1], beam.frame[2], bar, True)
        d = np.r_[NODE_DOF * e:NODE_DOF * e + 12]
        M[np.ix_(d, d)] += Me
    return M


def scalar_mass_pairs(R: np.ndarray, tol: float = 0.0) -> list[tuple[int, int, float]]:
    """A symmetric matrix as scalar masses (CMASS2): R = sum_{i<j} m_ij (e_i - e_j)(e_i -
    e_j)^T + sum_i m_i e_i e_i^T with m_ij = -R_ij and m_i = sum_j R_ij (the row sum).

    Returns
    -------
    list of (i, j, m): j = -1 for a grounded (one-DOF) mass; entries with |m| <= tol left out.

    Examples
    --------
    >>> R = np.array([[2.0, 1.0], [1.0, 2.0]])
    >>> scalar_mass_pairs(R)
    [(0, 1, -1.0), (0, -1, 3.0), (1, -1, 3.0)]
    """
    R = np.asarray(R, float)
    n = R.shape[0]
    out = [(i, j, -float(R[i, j])) for i in range(n) for j in range(i + 1, n)
           if abs(R[i, j]) > tol]
    out += [(i, -1, float(R[i].sum())) for i in range(n) if abs(R[i].sum()) > tol]
    return out


def _section_lines(element: str, pid: int, sec) -> list[str]:
    """PBAR, or the constant-section PBEAM (end A; C-F stress points 0; end B YESA; K1 = K2 =
    0.0), of a :class:`~asekit.structure.beam.BeamSection` with MAT1 E = G = 1."""
    if element == "CBAR":
        return [f"PBAR,{pid},1,{sec.ea!r},{sec.ei_flap!r},{sec.ei_chord!r},{sec.gj!r},"
                f"{sec.mass!r}"]
    return [f"PBEAM,{pid},1,{sec.ea!r},{sec.ei_flap!r},{sec.ei_chord!r},0.0,{sec.gj!r},"
            f"{sec.mass!r}", "," + ",".join(["0.0"] * 8), ",YESA,1.0", ",0.0,0.0"]


def write_beam_bdf(beam, path, element: str = "CBAR") -> Path:
    """Write a clamped :class:`~asekit.structure.beam.StraightBeam` (a case's ``[[beam]]``,
    :func:`asekit.case.pipeline.case_beam`) as an SI SOL 103 deck that
    :func:`read_stick_deck` reads back to the same matrices.

    GRID per node, CBAR per element (orientation vector the surface normal e3: plane 1 is the
    flap plane), PBAR with MAT1 E = G = 1 Pa (A = EA, I1 = EI_flap, I2 = EI_chord, J = GJ,
    NSM = m), PARAM COUPMASS 1 (the consistent bar mass), SPC1 123456 at the root. With
    ``element="CBEAM"`` the elements are CBEAM with a constant-section PBEAM holding the same
    values (end B "YESA", K1 = K2 = 0.0: no shear flexibility), the same Euler-Bernoulli bar.
    What a PBAR cannot hold -- the polar inertia, the mass offset's bending-torsion coupling and the point
    masses -- is the difference between the beam's consistent mass matrix
    (:func:`asekit.structure.beam.assemble`) and the bars' one, written exactly as CMASS2 scalar
    masses (:func:`scalar_mass_pairs`; some negative, as a consistent matrix's lumped form
    needs).

    Parameters
    ----------
    beam : StraightBeam.
    path : the deck to write (overwritten).
    element : ``"CBAR"`` (PBAR) or ``"CBEAM"`` (PBEAM).

    Returns
    -------
    Path
    """
    from asekit.structure.beam import assemble

    if element not in BAR_CARDS:
        raise ValueError(f"element must be one of {BAR_CARDS}, got {element!r}")
    path = Path(path)
    _, Mb = assemble(beam)
    R = Mb - _bar_mass(beam)
    free = slice(NODE_DOF, None)                  # the root node is clamped
    Rf = np.zeros_like(R)
    Rf[free, free] = R[free, free]
    lines = ["SOL 103", "CEND", "SPC = 1", "METHOD = 1", "BEGIN BULK",
             "$ written by asekit.io.bdf_beam.write_beam_bdf (SI)"]
    for i, x in enumerate(beam.nodes.tolist()):       # Python floats: repr without np.float64
        lines.append(f"GRID,{i + 1},,{x[0]!r},{x[1]!r},{x[2]!r}")
    v = np.asarray(beam.frame[2], float).tolist()
    for e, sec in enumerate(beam.sections):
        lines.append(f"{element},{e + 1},{e + 1},{e + 1},{e + 2},{v[0]!r},{v[1]!r},{v[2]!r}")
        lines += _section_lines(element, e + 1, sec)
    lines += ["MAT1,1,1.0,1.0", "SPC1,1,123456,1", "PARAM,COUPMASS,1",
              f"EIGRL,1,,,{min(6, NODE_DOF * (beam.n_nodes - 1))}"]
    tol = 1e-14 * float(np.abs(Mb).max())
    eid = 100000
    for i, j, m in scalar_mass_pairs(Rf, tol):
        g1, c1 = divmod(i, NODE_DOF)
        g2 = f"{j // NODE_DOF + 1},{j % NODE_DOF + 1}" if j >= 0 else ","
        eid += 1
        lines.append(f"CMASS2,{eid},{m!r},{g1 + 1},{c1 + 1},{g2}")
    lines.append("ENDDATA")
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text("\n".join(lines) + "\n")
    tmp.replace(path)
    return path
