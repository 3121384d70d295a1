"""A Nastran stick-model deck (CBAR / CBEAM) as a ``[[beam]]`` case file (issue 24).

:func:`stick_case_dict` reads a deck with :func:`asekit.io.bdf_beam.read_stick_deck` (every
card check of the stick reader applies) and writes what the case format can express:

- the structure: one straight beam in the plane z = 0, clamped at the one GRID whose six
  components are all constrained (SPC / SPC1 / GRID PS), its bars joining consecutive GRIDs
  along the axis; each bar's section (PBAR / PBEAM / PBARL with MAT1, SI) as one segment of
  ``[[beam]]`` (``stations`` at the GRIDs, ``n_elements = 1``; one uniform segment when every
  bar is equal), plane 1 (I1) the flap plane when the orientation vector is normal to the
  plane, the chord plane when it lies in the plane; PARAM COUPMASS > 0 (the consistent bar
  mass, which is the beam element's; asekit.structure.frame and asekit.structure.beam agree);
- the in-plane motion: free, or ``in_plane = "fixed"`` when every other GRID has exactly its
  in-plane components constrained (two translations in the plane and the rotation about its
  normal, e.g. PS 126 in a CD system whose z is the normal: PT145); the out-of-plane modes
  are then solved alone (:func:`asekit.structure.beam.out_of_plane_dofs`);
- the masses: a CONM2 (CID 0) as a ``point_masses`` entry (mass, offset and principal
  inertia along the beam's axes; products of inertia in those axes refused), a one-grid
  CMASS2 on a rotation about one of the beam's axes as that inertia;
- the spline: every spline a SPLINE2 over all the GRIDs along the beam's axis (its CID's y
  axis through the CID's origin), which is the case's beam spline extended straight beyond
  the end grids (``spline_extension = true``);
- the aerodynamics: each CAERO1 (uniform NSPAN x NCHORD, in the plane z = 0) as a ``[[panel]]``
  with its ``aero.boxes``, AERO REFC / 2 as ``reference_semichord``, SYMXZ = 1 as
  ``symmetry = "wall"``, the MKAERO1 Machs and reduced frequencies;
- the flight: the densities of every FLUTTER card (FLFACT DENS x RHOREF) and the velocities
  of its PK / PKNL cards; for K / KE cards (reduced frequencies, no velocities) the sweep
  from 2 pi f_1 b / k_max to 2 pi f_n b / k_min over the kept modes' frequencies f (the
  speeds at which the K method's listed k meet the modes), in 100 steps. asekit's p-k runs
  the case (its own method, docs/nastran-flutter.md explains the damping definitions; the
  flutter crossing at g = 0 is the same equation as the K method's);
- ``modes.count``: PARAM LMODES, else EIGR / EIGRL ND, else 6.

Anything else is refused in one line naming the card, its id and the field: rigid elements
(RBE2 / RBAR / RBE3), a lumped bar mass, GRIDs off one straight line in z = 0, an axis pointing
inboard, an oblique orientation vector, other constraints, a translational or two-grid
CMASS2 (so a deck from :func:`asekit.io.bdf_beam.write_beam_bdf`, whose CMASS2 pairs carry a
consistent polar inertia, is refused), SPLINE1 / SPLINE4 or a SPLINE2 off the axis or on a
subset of the GRIDs, CAERO1 with AEFACT divisions.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from asekit.io.bdf import (
    UNITS,
    BdfError,
    Deck,
    check_caero1,
    need_pynastran,
    read_aero_card,
    read_flutter,
    read_mkaero1,
)
from asekit.io.bdf_beam import (
    BAR_CARDS,
    StickModel,
    bar_orientation,
    bar_section,
    card_ids,
    deck_param,
    read_stick_deck,
    requested_mode_count,
    stick_modes,
)

#: velocity steps of the sweep written for a K / KE deck.
KE_SWEEP_STEPS = 100


def _axis(sm: StickModel, name: str):
    """(root index, e1 (3,), order of the nodes along the axis, stations (m))."""
    fixed = set(sm.fixed)
    roots = [i for i in range(len(sm.node_ids)) if all(6 * i + c in fixed for c in range(6))]
    if len(roots) != 1:
        raise BdfError(f"{name}: the case's beam is clamped at one GRID; the deck has "
                       f"{len(roots)} GRIDs with all six components constrained")
    r = roots[0]
    x = sm.xyz
    scale = max(float(np.abs(x).max()), 1e-30)
    off = np.flatnonzero(np.abs(x[:, 2]) > 1e-9 * scale)
    if off.size:
        raise BdfError(f"{name}: GRID {sm.node_ids[off[0]]} z = {x[off[0], 2]:g} m: the case's "
                       f"beam lies in the plane z = 0")
    d = x - x[r]
    far = int(np.argmax(np.linalg.norm(d, axis=1)))
    e1 = d[far] / np.linalg.norm(d[far])
    s = d @ e1
    lateral = np.linalg.norm(d - s[:, None] * e1[None, :], axis=1)
    bad = np.flatnonzero(lateral > 1e-9 * s.max())
    if bad.size:
        raise BdfError(f"{name}: GRID {sm.node_ids[bad[0]]} is {lateral[bad[0]]:g} m off the "
                       f"line from GRID {sm.node_ids[r]} to GRID {sm.node_ids[far]}: the case's "
                       f"beam is straight")
    if e1[1] <= 0 or math.degrees(math.atan2(abs(e1[0]), e1[1])) > 85.0:
        raise BdfError(f"{name}: the axis from GRID {sm.node_ids[r]} to GRID "
                       f"{sm.node_ids[far]} must point outboard (+y) and be swept by at most "
                       f"85 deg, as a case's [[beam]]")
    order = np.argsort(s)
    if order[0] != r or np.any(np.diff(s[order]) <= 1e-12 * s.max()):
        raise BdfError(f"{name}: the clamped GRID {sm.node_ids[r]} must be the root (one end "
                       f"of the axis) and no two GRIDs may coincide")
    return r, e1, order, s[order]


def _in_plane(sm: StickModel, order, name: str) -> str:
    """"free" or "fixed" from the constraints of the GRIDs other than the root."""
    fixed = set(sm.fixed)
    kinds = set()
    for i in order[1:]:
        comps = [c for c in range(6) if 6 * i + c in fixed]
        if not comps:
            kinds.add("free")
            continue
        axes = sm.cd_axes[i]
        trans = [axes[c] for c in comps if c < 3]
        rots = [axes[c - 3] for c in comps if c >= 3]
        ok = (len(trans) == 2 and len(rots) == 1 and all(abs(t[2]) < 1e-9 for t in trans)
              and abs(abs(rots[0][2]) - 1) < 1e-9)
        if not ok:
            raise BdfError(f"{name}: GRID {sm.node_ids[i]} constrains components "
                           f"{''.join(str(c + 1) for c in comps)} (in its CD system): a case's "
                           f"beam fixes none or exactly the in-plane motion (two translations in "
                           f"the plane z = 0 and the rotation about z)")
        kinds.add("fixed")
    if len(kinds) > 1:
        raise BdfError(f"{name}: some GRIDs have their in-plane motion constrained and some "
                       f"not: a case's beam fixes it everywhere or nowhere ([[beam]] in_plane)")
    return kinds.pop()


def _sections(model, sm: StickModel, index, order, e1, deck_units, name: str) -> list:
    """One (ea, gj, ei_flap, ei_chord, mass, 0, 0) tuple per bar, root to tip."""
    pos = {int(order[k]): k for k in range(len(order))}
    out = [None] * (len(order) - 1)
    for eid in [i for c in BAR_CARDS for i in card_ids(model, c)]:
        e = model.elements[eid]
        a, b = sorted((pos[index[e.ga]], pos[index[e.gb]]))
        if b != a + 1 or out[a] is not None:
            raise BdfError(f"{e.type} {eid}: joins GRIDs {e.ga} and {e.gb}, not the next "
                           f"free GRID along the axis: a case's beam is one chain of bars")
        v = bar_orientation(model, e, lambda g: sm.cd_axes[index[g]], lambda g: sm.xyz[index[g]])
        p = v - (v @ e1) * e1
        p = p / np.linalg.norm(p)
        sec = bar_section(model, e.pid, eid, deck_units, e.type)
        if math.isfinite(sec.gas1) or math.isfinite(sec.gas2):
            raise BdfError(f"{model.properties[e.pid].type} {e.pid} (of {e.type} {eid}): K1 / "
                           f"K2 give shear flexibility, which a case's Euler-Bernoulli [[beam]] "
                           f"cannot express")
        if abs(abs(p[2]) - 1) < 1e-9:
            flap, chord = sec.ei1, sec.ei2
        elif abs(p[2]) < 1e-9:
            flap, chord = sec.ei2, sec.ei1
        else:
            raise BdfError(f"{e.type} {eid}: orientation vector X1-X3 / G0 is oblique to the "
                           f"plane z = 0: plane 1 must be the flap or the chord plane")
        out[a] = (sec.ea, sec.gj, flap, chord, sec.mass, sec.polar, 0.0)
    if any(x is None for x in out):
        raise BdfError(f"{name}: GRIDs without a bar between them: a case's beam is one chain")
    return out


def _beam_frame(e1) -> np.ndarray:
    """Rows (axis e1, aft e1 x e3, up e3): the case's point-mass axes."""
    e3 = np.array([0.0, 0.0, 1.0])
    return np.array([e1, np.cross(e1, e3), e3])


def _principal(R, tensor, what: str) -> list[float]:
    """The diagonal of ``tensor`` (basic) in the beam axes ``R``; off-diagonals refused."""
    t = R @ tensor @ R.T
    off = t - np.diag(np.diag(t))
    if np.abs(off).max(initial=0.0) > 1e-9 * max(np.abs(t).max(initial=0.0), 1e-300):
        raise BdfError(f"{what}: products of inertia in the beam's axes (axis, aft, up) are not "
                       f"expressible in a case (point_masses inertia is principal)")
    return _clean(np.diag(t))


def _clean(v) -> list[float]:
    """Components below 1e-12 of the largest (rotation round-off) as 0."""
    v = np.asarray(v, float)
    big = float(np.abs(v).max(initial=0.0))
    return [0.0 if abs(x) <= 1e-12 * big else float(x) for x in v]


def _point_masses(model, sm, index, e1, stations_of, deck_units, name) -> list[dict]:
    """CONM2 and one-grid rotational CMASS2 as [[beam]] point_masses entries."""
    L, Mu, T, wt = deck_units
    R = _beam_frame(e1)
    out = []
    for eid in card_ids(model, "CONM2"):
        m = model.masses[eid]
        o = _clean(R @ (np.asarray(m.X, float) * L))
        inertia = _principal(R, np.asarray(m.Inertia(), float) * wt * Mu * L * L,
                             f"CONM2 {eid}")
        out.append({"s": stations_of(m.nid), "mass": float(m.mass * wt * Mu),
                    "offset": [float(x) for x in o], "inertia": inertia})
    for eid in card_ids(model, "CMASS2"):
        c = model.masses[eid]
        g2 = c.nodes[1] if len(c.nodes) > 1 else None
        if g2 or not c.nodes[0] or int(c.c1) <= 3:
            raise BdfError(f"CMASS2 {eid}: a case's point mass is a rigid mass; only a one-grid "
                           f"CMASS2 on a rotation (C1 = 4, 5 or 6) is expressible, got G1 = "
                           f"{c.nodes[0]}, C1 = {c.c1}, G2 = {g2}")
        axis = sm.cd_axes[index[c.nodes[0]]][int(c.c1) - 4]
        inertia = _principal(R, c.mass * wt * Mu * L * L * np.outer(axis, axis),
                             f"CMASS2 {eid}")
        out.append({"s": stations_of(c.nodes[0]), "mass": 0.0, "inertia": inertia})
    return out


def _structure(path, units: str, name: str):
    """(model, [[beam]] table, in_plane, kept-mode frequencies) of a stick deck."""
    sm = read_stick_deck(path, units)
    model = need_pynastran()(debug=None)
    model.read_bdf(str(path), xref=True)
    for card in ("RBE2", "RBAR", "RBE3"):
        if card_ids(model, card):
            raise BdfError(f"{card} {card_ids(model, card)[0]}: a case's [[beam]] has no rigid "
                           f"links")
    if not sm.coupled:
        raise BdfError(f"{name}: PARAM COUPMASS is not > 0 (the lumped bar mass); a case's "
                       f"beam has the consistent mass: set PARAM COUPMASS 1")
    L, Mu, T = UNITS[units]
    deck_units = (L, Mu, T, float(deck_param(model, "WTMASS", 1.0)))
    index = {int(g): i for i, g in enumerate(sm.node_ids)}
    r, e1, order, st = _axis(sm, name)
    in_plane = _in_plane(sm, order, name)
    secs = _sections(model, sm, index, order, e1, deck_units, name)
    spos = {int(order[k]): float(st[k]) for k in range(len(order))}
    masses = _point_masses(model, sm, index, e1, lambda g: spos[index[int(g)]], deck_units,
                           name)
    length = float(st[-1])
    lengths = np.diff(st)
    uniform = all(s == secs[0] for s in secs) and np.allclose(lengths, lengths[0], rtol=1e-12)
    beam = {"root": [float(sm.xyz[r, 0]), float(sm.xyz[r, 1])],
            "tip": [float(sm.xyz[order[-1], 0]), float(sm.xyz[order[-1], 1])]}
    if uniform:
        beam["n_elements"] = len(secs)
    else:
        beam["stations"] = [float(x / length) for x in st]
        beam["stations"][-1] = 1.0
        beam["n_elements"] = 1
    keys = ("ea", "gj", "ei_flap", "ei_chord", "mass_per_length", "polar_inertia")
    for j, k in enumerate(keys):
        col = [float(s[j]) for s in secs]
        beam[k] = col[0] if uniform else col
    if in_plane == "fixed":
        beam["in_plane"] = "fixed"
    if masses:
        beam["point_masses"] = masses
    beam["spline_extension"] = True        # SPLINE2: straight beyond the end stations
    _check_splines(model, sm, r, e1, L)
    n = requested_mode_count(model)
    f = stick_modes(sm, n).frequencies_hz
    return model, beam, (L, Mu, T), f


def _check_splines(model, sm: StickModel, root: int, e1, L: float) -> None:
    """Every spline a SPLINE2 on all the GRIDs whose axis (its CID's y axis through the CID's
    origin) is the beam's: the case's beam spline is then the deck's (a different axis or a
    subset of grids is a different interpolation, refused)."""
    for sid in sorted(model.splines):
        sp = model.splines[sid]
        if sp.type != "SPLINE2":
            raise BdfError(f"{sp.type} {sid}: a case's beam is splined as SPLINE2 (the beam "
                           f"spline); only SPLINE2 is expressible")
        c = model.coords[sp.cid] if sp.cid else None
        axes = np.asarray(c.beta(), float) if c is not None else np.eye(3)
        origin = (np.asarray(c.origin, float) if c is not None else np.zeros(3)) * L
        d = origin - sm.xyz[root]
        off = np.linalg.norm(d - (d @ e1) * e1)
        if abs(abs(axes[1] @ e1) - 1) > 1e-9 or off > 1e-9 * max(1.0, float(np.ptp(sm.xyz))):
            raise BdfError(f"SPLINE2 {sid}: CID = {sp.cid}: its y axis is not the beam's axis "
                           f"(the case's beam spline runs along the beam)")
        grids = {int(g) for g in model.sets[sp.setg].ids}
        if grids != {int(g) for g in sm.node_ids}:
            raise BdfError(f"SPLINE2 {sid}: SETG = {sp.setg} holds {len(grids)} of the "
                           f"{len(sm.node_ids)} GRIDs; the case's beam spline uses them all")


def _panels(model, L: float) -> tuple[list, list]:
    """[[panel]] tables and aero.boxes of the CAERO1 cards (uniform divisions, z = 0)."""
    panels, boxes = [], []
    for cid in sorted(model.caeros):
        c = model.caeros[cid]
        if c.type != "CAERO1":
            raise BdfError(f"{c.type} {cid} is not supported (CAERO1)")
        if not (c.nspan and c.nchord):
            raise BdfError(f"CAERO1 {cid}: LSPAN / LCHORD (AEFACT divisions) are not "
                           f"expressible in a case (uniform boxes only): give NSPAN and NCHORD")
        p1, _, _, p4 = (np.asarray(p, float) * L for p in c.get_points())
        if abs(p1[2]) > 1e-9 * L or abs(p4[2]) > 1e-9 * L:
            raise BdfError(f"CAERO1 {cid}: P1 / P4 off the plane z = 0 (the case's planform)")
        (r, cr), (t, ct) = sorted([(p1, c.x12 * L), (p4, c.x43 * L)], key=lambda q: q[0][1])
        panels.append({"root_leading_edge": [float(r[0]), float(r[1])],
                       "root_chord": float(cr), "tip_leading_edge": [float(t[0]), float(t[1])],
                       "tip_chord": float(ct)})
        boxes.append({"n_chord": int(c.nchord), "n_span": int(c.nspan)})
    return panels, boxes


def _flight(requests, f_hz, b_ref: float) -> dict:
    """[flight]: every card's densities; PK / PKNL velocities, else the K / KE sweep."""
    dens = sorted({float(d) for r in requests for d in r.densities})
    vel = sorted({float(v) for r in requests if r.method in ("PK", "PKNL") for v in r.velocities})
    if not vel:
        ks = [k for r in requests for k in r.reduced_frequencies if k > 0]
        w = 2 * math.pi * np.asarray(f_hz, float)
        lo, hi = float(w.min() * b_ref / max(ks)), float(w.max() * b_ref / min(ks))
        return {"densities": dens, "velocities": {"min": lo, "max": hi,
                                                  "step": (hi - lo) / KE_SWEEP_STEPS}}
    return {"densities": dens, "velocities": vel}


def stick_case_dict(path, units: str = "SI", name: str | None = None) -> dict:
    """A stick-model deck as the dictionary of a ``[[beam]]`` case file (module docstring).

    Parameters
    ----------
    path : the deck (CBAR / CBEAM structure, CAERO1 + SPLINE2 aerodynamics, FLUTTER).
    units : its unit system, a key of :data:`asekit.io.bdf.UNITS`.
    name : ``case.name`` (default: the deck's stem).

    Returns
    -------
    dict
        TOML-able (``asekit.case.toml_writer.dumps``), SI, loadable with
        :func:`asekit.case.case_from_dict`.

    Raises
    ------
    BdfError
        What a case cannot express, in one line naming the card, its id and the field.

    Examples
    --------
    >>> from asekit.util.paths import DATA_DIR                       # doctest: +SKIP
    >>> d = stick_case_dict(DATA_DIR / "benchmarks/pt145/pt145.bdf", "in-lbf-s")  # doctest: +SKIP
    >>> d["beam"][0]["in_plane"], d["modes"]["count"]                # doctest: +SKIP
    ('fixed', 3)
    """
    if units not in UNITS:
        raise ValueError(f"units must be one of {sorted(UNITS)}, got {units!r}")
    path = Path(path)
    model, beam, (L, Mu, T), f = _structure(path, units, path.name)
    if not model.caeros or not model.flutters:
        raise BdfError(f"{path.name}: no CAERO1 or no FLUTTER card: a case needs the "
                       f"aerodynamic planform and a flight sweep")
    deck = Deck(model, path.name, L, Mu, T)
    b_ref, rho_ref, symmetric = read_aero_card(deck)
    for c in model.caeros.values():
        check_caero1(deck, c)
    panels, boxes = _panels(model, L)
    machs, ks = read_mkaero1(model, deck)
    requests = [read_flutter(model, fl, rho_ref, deck) for fl in model.flutters.values()]
    return {"case": {"name": name or path.stem,
                     "reference": f"converted from the Nastran deck {path.name} "
                                  f"(asekit.io.stick_case, units {units})"},
            "beam": [beam], "panel": panels, "modes": {"count": len(f)},
            "aero": {"machs": list(machs), "reference_semichord": b_ref,
                     "reduced_frequencies": list(ks), "boxes": boxes,
                     "symmetry": "wall" if symmetric else "none"},
            "flight": _flight(requests, f, b_ref)}


def write_stick_case(deck, case_path, units: str = "SI", name: str | None = None) -> Path:
    """Write :func:`stick_case_dict` of ``deck`` as a TOML case file (atomically: a temporary
    file renamed); the case is loaded back first, so that a file that would not load is
    never written.

    Returns
    -------
    Path
        ``case_path``.
    """
    from asekit.case import case_from_dict
    from asekit.case.toml_writer import dumps

    d = stick_case_dict(deck, units, name)
    case_from_dict(d)
    out = Path(case_path)
    tmp = out.with_name(out.name + ".tmp")
    tmp.write_text("# written by asekit convert (asekit.io.stick_case)\n" + dumps(d))
    tmp.replace(out)
    return out
