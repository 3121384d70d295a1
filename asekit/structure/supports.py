"""Edge supports of plate meshes: clamped, simply supported, sliding or free edges (for panel
flutter and other plate problems), by the same transformation u = T q as
:mod:`asekit.structure.assembly`.

Degrees of freedom per node are (w, theta_x, theta_y) with the Kirchhoff limits
theta_x = dw/dy, theta_y = -dw/dx (:mod:`asekit.structure.plate`). On an edge of the mesh's
bounding rectangle:

- ``"clamped"``: w = theta_x = theta_y = 0;
- ``"simply_supported"``: w = 0 and the rotation about the edge normal (the slope along the
  edge) = 0, the "hard" simple support of Reissner-Mindlin plates (e.g. Bathe, *Finite Element
  Procedures*, 1996, Section 5.4): theta_x = 0 on an edge x = const, theta_y = 0 on y = const;
- ``"sliding"``: the slope normal to the edge = 0, w free (a symmetry line; two sliding side
  edges make a plate strip bend cylindrically, the 2-D panel): theta_y = 0 on x = const,
  theta_x = 0 on y = const;
- ``"free"``: nothing.

Edges are named ``x0`` (x = x_min, the leading edge for flow along +x), ``x1`` (x = x_max),
``y0`` (y = y_min) and ``y1`` (y = y_max).

The case file's ``"partial"`` kind (:func:`partial_support_nodes`) holds only some nodes, as a
Nastran SPC1 on chosen grids: the nodes nearest to listed points and those on parts of the
named edges, clamped, pinned (w only) or on grounded springs; a support that leaves a rigid-body
motion free is refused (:func:`rigid_restraint`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp

from asekit.structure.assembly import SupportedSystem, clamped_edge, shaft_support
from asekit.structure.mesh import PlateMesh
from asekit.structure.modes import fictitious_mass_modal_model, fixed_modal_model
from asekit.structure.plate import DOF_PER_NODE

EDGE_TYPES = ("free", "simply_supported", "clamped", "sliding")
EDGES = ("x0", "x1", "y0", "y1")

# fixed local DOFs (0 w, 1 theta_x, 2 theta_y) per edge type and edge orientation
_FIXED = {
    ("clamped", "x"): (0, 1, 2), ("clamped", "y"): (0, 1, 2),
    ("simply_supported", "x"): (0, 1), ("simply_supported", "y"): (0, 2),
    ("sliding", "x"): (2,), ("sliding", "y"): (1,),
    ("free", "x"): (), ("free", "y"): (),
}


def edge_nodes(mesh: PlateMesh, edge: str, tol: float = 1e-9) -> np.ndarray:
    """Nodes on one edge of the mesh's bounding rectangle (``x0``, ``x1``, ``y0``, ``y1``)."""
    if edge not in EDGES:
        raise ValueError(f"edge must be one of {EDGES}, got {edge!r}")
    axis = 0 if edge[0] == "x" else 1
    c = mesh.nodes[:, axis]
    target = c.min() if edge[1] == "0" else c.max()
    scale = float(np.ptp(mesh.nodes, axis=0).max())
    return np.flatnonzero(np.abs(c - target) <= tol * scale)


def edge_supports(mesh: PlateMesh, K, M, x0: str = "simply_supported",
                  x1: str = "simply_supported", y0: str = "simply_supported",
                  y1: str = "simply_supported") -> SupportedSystem:
    """Apply edge conditions (module docstring) to the assembled plate ``K``, ``M`` (3 n_nodes
    square, :func:`asekit.structure.assembly.assemble`) and return the reduced system.

    Corners shared by two edges get the union of both edges' conditions. Raises ValueError for
    an unknown edge type. Rigid-body freedom is not checked (an all-free plate keeps its
    zero-frequency modes)."""
    kinds = {"x0": x0, "x1": x1, "y0": y0, "y1": y1}
    fixed = set()
    for edge, kind in kinds.items():
        if kind not in EDGE_TYPES:
            raise ValueError(f"{edge} must be one of {EDGE_TYPES}, got {kind!r}")
        for node in edge_nodes(mesh, edge):
            for d in _FIXED[(kind, edge[0])]:
                fixed.add(DOF_PER_NODE * int(node) + d)
    n = K.shape[0]
    if n != DOF_PER_NODE * mesh.n_nodes or M.shape != K.shape:
        raise ValueError(f"K and M must be {DOF_PER_NODE * mesh.n_nodes} square, got {K.shape}, "
                         f"{M.shape}")
    free = np.setdiff1d(np.arange(n), np.fromiter(fixed, int, len(fixed)))
    T = sp.csr_matrix((np.ones(free.size), (free, np.arange(free.size))), shape=(n, free.size))
    K = sp.csr_matrix(K)
    M = sp.csr_matrix(M)
    label = "plate " + ", ".join(f"{e} {k}" for e, k in kinds.items())
    return SupportedSystem(K=(T.T @ K @ T).tocsr(), M=(T.T @ M @ T).tocsr(), T=T,
                           shaft_index=None, ground_index=None, fictitious_inertia=0.0,
                           shaft_nodes=np.array([], dtype=np.int64), mesh=mesh, label=label)


#: Named edges of a structured surface mesh (nodes ``j (n_chord + 1) + i``): the root and tip
#: stations and the leading and trailing edges of all panels.
PLANFORM_EDGES = ("root", "tip", "leading_edge", "trailing_edge")


def planform_edge_nodes(mesh: PlateMesh, edge: str) -> np.ndarray:
    """Nodes on a named edge (:data:`PLANFORM_EDGES`) of a structured mesh
    (:func:`asekit.structure.mesh.structured_mesh` or ``panels_mesh``)."""
    if edge not in PLANFORM_EDGES:
        raise ValueError(f"edge must be one of {PLANFORM_EDGES}, got {edge!r}")
    nc, ns = mesh.n_chord, mesh.n_span
    if nc < 1 or ns < 1 or mesh.n_nodes != (nc + 1) * (ns + 1):
        raise ValueError("planform edges need a structured mesh (n_chord x n_span elements)")
    grid = np.arange(mesh.n_nodes).reshape(ns + 1, nc + 1)
    return {"root": grid[0], "tip": grid[-1], "leading_edge": grid[:, 0],
            "trailing_edge": grid[:, -1]}[edge]


def planform_edge_supports(mesh: PlateMesh, K, M, root: str = "clamped", tip: str = "free",
                           leading_edge: str = "free",
                           trailing_edge: str = "free") -> SupportedSystem:
    """Edge conditions on the named edges of a structured surface mesh (a plate wing's root and
    tip stations, its leading and trailing edges; see the module docstring for the kinds).

    Root and tip run along x (y = const). A leading or trailing edge at constant x takes the
    "hard" simple support as :func:`edge_supports`; on a swept (or tapered) edge the slope along
    the edge mixes theta_x and theta_y and cannot be removed by eliminating degrees of freedom,
    so ``"simply_supported"`` there holds w only (the "soft" simple support; Bathe 1996,
    Sec. 5.4) and ``"sliding"`` is refused.
    """
    kinds = {"root": root, "tip": tip, "leading_edge": leading_edge,
             "trailing_edge": trailing_edge}
    fixed = set()
    scale = float(np.ptp(mesh.nodes, axis=0).max())
    for edge, kind in kinds.items():
        if kind not in EDGE_TYPES:
            raise ValueError(f"{edge} must be one of {EDGE_TYPES}, got {kind!r}")
        nodes = planform_edge_nodes(mesh, edge)
        if edge in ("root", "tip"):
            dofs = _FIXED[(kind, "y")]
        elif np.ptp(mesh.nodes[nodes, 0]) <= 1e-9 * scale:          # an edge x = const
            dofs = _FIXED[(kind, "x")]
        elif kind == "sliding":
            raise ValueError(f"{edge}: a sliding condition needs an edge at constant x "
                             "(this one is swept or tapered)")
        else:
            dofs = (0,) if kind == "simply_supported" else _FIXED[(kind, "x")]
        for node in nodes:
            for d in dofs:
                fixed.add(DOF_PER_NODE * int(node) + d)
    n = K.shape[0]
    free = np.setdiff1d(np.arange(n), np.fromiter(fixed, int, len(fixed)))
    T = sp.csr_matrix((np.ones(free.size), (free, np.arange(free.size))), shape=(n, free.size))
    K, M = sp.csr_matrix(K), sp.csr_matrix(M)
    label = "plate " + ", ".join(f"{e} {k}" for e, k in kinds.items())
    return SupportedSystem(K=(T.T @ K @ T).tocsr(), M=(T.T @ M @ T).tocsr(), T=T,
                           shaft_index=None, ground_index=None, fictitious_inertia=0.0,
                           shaft_nodes=np.array([], dtype=np.int64), mesh=mesh, label=label)


# ---------------------------------------------------------------------------------------------
# the support kinds of a case file (registry read by asekit.case.schema and asekit.case.pipeline)
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SupportKind:
    """How one kind of support is read from a case file and turned into a structure.

    Attributes
    ----------
    name : the ``support.kind`` value.
    description : one line for error messages and documentation.
    parse : ``parse(table, root_planform) -> dict`` of the kind's values from the ``[support]``
        table, read with its typed getters (``number``, ``numbers``, ``string``, ``raw``; they
        name the key path) and closed with ``done()``; other bad input raises ValueError naming
        ``support.<key>``. A key that is a field of :class:`asekit.case.SupportSpec` sets the
        field; any other goes to ``spec.options`` (read it with ``spec.option(key)``; values
        hashable), so a new kind needs no new field.
    system : ``system(mesh, K, M, spec) -> SupportedSystem``, the supported structure (the
        FN1 or FN2 shaft system as ``spec.model`` says).
    modal_model : ``modal_model(mesh, K, M, spec, f_max_hz, n_modes, keep_rigid)``
        -> ModalModel (thesis Eqs. 2.45-2.46): the elastic modes kept below ``f_max_hz`` (Hz) or
        the first ``n_modes``, with the rigid pitch mode first when the kind has one and
        ``keep_rigid``.
    has_rigid_mode : ``has_rigid_mode(spec) -> bool``, whether the model can keep a rigid
        mode (needed by the ASE loop's actuator).

    Adding a support kind: write its functions here and add it to :data:`SUPPORTS` (and its
    keys to ``docs/case-format.md``); the schema and the pipeline read it from there.
    """

    name: str
    description: str
    parse: Callable
    system: Callable
    modal_model: Callable
    has_rigid_mode: Callable = field(default=lambda spec: False)


def _parse_clamped_root(t, root) -> dict:
    t.done()
    return {}


def _parse_edges(t, root) -> dict:
    defaults = {"root": "clamped", "tip": "free", "leading_edge": "free",
                "trailing_edge": "free"}
    edges = tuple((e, t.string(e, EDGE_TYPES, default=defaults[e])) for e in PLANFORM_EDGES)
    t.done()
    if all(k == "free" for _, k in edges):
        raise ValueError("support: all four edges free leaves rigid-body modes; hold at "
                         "least one edge (support.root = \"clamped\", ...)")
    return {"edges": edges}


def _parse_shaft(t, root) -> dict:
    axis = t.numbers("axis_point", required=True, length=2, unit="m")
    k = t.number("torsional_stiffness", required=True, low=0.0, high=1e12, unit="N m/rad")
    kb = t.number("bending_stiffness", low=0.0, high=1e12, unit="N m/rad")
    model = t.string("model", ("FN1", "FN2"), default="FN2")
    region = t.raw("region", "single_node")
    fif = t.number("fictitious_inertia_factor", default=1.0e6, low=1.0, high=1e12)
    fit = t.string("region_fit", REGION_FITS, default="nodes")
    t.done()
    if region == "single_node":
        radius = None
    elif (isinstance(region, (int, float)) and not isinstance(region, bool)
          and np.isfinite(region) and 0.0 < region <= 1e3):
        radius = float(region)
    else:
        raise ValueError(f"support.region must be \"single_node\" or a shaft radius in "
                         f"(0, 1000] m, got {region!r}")
    if abs(axis[1] - root.root_le[1]) > 1e-9 * max(root.span, 1.0) or not (
            root.root_le[0] <= axis[0] <= root.root_le[0] + root.root_chord):
        raise ValueError(f"support.axis_point {list(axis)} must lie on the root chord "
                         f"(y = {root.root_le[1]:g} m, x in [{root.root_le[0]:g}, "
                         f"{root.root_le[0] + root.root_chord:g}] m)")
    if fit != "nodes" and radius is None:
        raise ValueError(f"support.region_fit = {fit!r} needs a rigid shaft region "
                         f"(support.region a radius in m), got region = \"single_node\"")
    out = {"axis_point": axis, "torsional_stiffness": k, "bending_stiffness": kb,
           "model": model, "radius": radius, "fictitious_inertia_factor": fif}
    return out if fit == "nodes" else {**out, "region_fit": fit}     # options: only if not default


#: How a rigid shaft region meets the mesh (``support.region_fit``): ``"nodes"`` every node
#: within the radius as the mesh has it (a staircase of the circle), ``"snap"`` the mesh's nodes
#: fitted to the circle first (:func:`asekit.structure.mesh.snap_to_circle`, applied by the
#: case pipeline's structural mesh).
REGION_FITS = ("nodes", "snap")


def _shaft_region(spec) -> tuple[str, float]:
    """(region, radius) of a shaft spec: the single node (radius None) or a rigid region."""
    return ("single_node", 0.0) if spec.radius is None else ("distributed", float(spec.radius))


def _shaft_system(mesh, K, M, spec) -> SupportedSystem:
    region, radius = _shaft_region(spec)
    return shaft_support(mesh, K, M, spec.axis_point, spec.torsional_stiffness, spec.model,
                         region, radius, fictitious_inertia_factor=spec.fictitious_inertia_factor,
                         bending_stiffness=spec.bending_stiffness)


def _shaft_modal_model(mesh, K, M, spec, f_max_hz, n_modes, keep_rigid):
    region, radius = _shaft_region(spec)
    if spec.model == "FN2" and keep_rigid:
        return fictitious_mass_modal_model(
            mesh, K, M, spec.axis_point, spec.torsional_stiffness, region=region, radius=radius,
            fictitious_inertia_factor=spec.fictitious_inertia_factor,
            bending_stiffness=spec.bending_stiffness, f_max_hz=f_max_hz, n_modes=n_modes)
    fn1 = _shaft_system(mesh, K, M, replace(spec, model="FN1"))
    return fixed_modal_model(fn1, M, f_max_hz, n_modes, axis_x=spec.axis_point[0])


def _clamped_system(mesh, K, M, spec) -> SupportedSystem:
    return clamped_edge(mesh, K, M)


def _edges_system(mesh, K, M, spec) -> SupportedSystem:
    return planform_edge_supports(mesh, K, M, **dict(spec.edges))


def _fixed_modal_model(system):
    """A modal_model function of a kind with no rigid mode: the modes of ``system``."""
    def modal_model(mesh, K, M, spec, f_max_hz, n_modes, keep_rigid):
        return fixed_modal_model(system(mesh, K, M, spec), M, f_max_hz, n_modes)
    return modal_model


# ---------------------------------------------------------------------------------------------
# "partial": nodes at listed points and on parts of the named edges (Nastran SPC1 on some grids)
# ---------------------------------------------------------------------------------------------
#: Conditions of the ``"partial"`` kind and the local DOFs (0 w, 1 theta_x, 2 theta_y) they fix:
#: ``"clamped"`` every DOF (Nastran SPC1 123456 on a plate grid: the in-plane and drilling
#: freedoms asekit's bending plate does not have are held anyway), ``"pinned"`` the deflection
#: w only (SPC1 3: the grid held, free to rotate).
PARTIAL_CONDITIONS = {"clamped": (0, 1, 2), "pinned": (0,)}
#: ``condition = "springs"``: each held node gets grounded springs ``springs = [k_w, k_theta_x,
#: k_theta_y]`` (N/m, N m/rad, N m/rad; Nastran CELAS2 to ground on DOFs 3, 4, 5) instead.
PARTIAL_SPRINGS = "springs"


def _point_list(key: str, value) -> tuple[tuple[float, float], ...]:
    """``value`` as ((x, y), ...) m; ValueError naming ``key`` otherwise."""
    ok = isinstance(value, list) and len(value) > 0
    pts = []
    for i, p in enumerate(value if ok else ()):
        if not (isinstance(p, list) and len(p) == 2 and all(
                isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v)
                and abs(v) <= 1e4 for v in p)):
            raise ValueError(f"{key}[{i}] must be a point [x, y] of two finite numbers in m "
                             f"(|value| <= 1e4), got {p!r}")
        pts.append((float(p[0]), float(p[1])))
    if not ok:
        raise ValueError(f"{key} must be a non-empty list of points [[x, y], ...] in m, "
                         f"got {value!r}")
    return tuple(pts)


def _fraction_range(key: str, value) -> tuple[float, float]:
    """``value`` as a (start, end) pair of fractions 0 <= start <= end <= 1."""
    if not (isinstance(value, list) and len(value) == 2 and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
            and 0.0 <= value[0] <= value[1] <= 1.0):
        raise ValueError(f"{key} must be a range [start, end] of fractions with "
                         f"0 <= start <= end <= 1, got {value!r}")
    return float(value[0]), float(value[1])


def _parse_partial(t, root) -> dict:
    condition = t.string("condition", (*PARTIAL_CONDITIONS, PARTIAL_SPRINGS), default="clamped")
    points = t.raw("points")
    out = {"condition": condition}
    springs = t.numbers("springs", length=3, low=0.0, high=1e15, low_open=False,
                        unit="N/m, N m/rad, N m/rad")
    if (springs is None) != (condition != PARTIAL_SPRINGS):
        raise ValueError(f"{t.key('springs')} = [k_w, k_theta_x, k_theta_y] (N/m, N m/rad, "
                         f"N m/rad) is needed with, and only with, {t.key('condition')} = "
                         f"\"springs\" (got condition = {condition!r})")
    if springs is not None:
        if max(springs) <= 0.0:
            raise ValueError(f"{t.key('springs')} must have one stiffness > 0, got "
                             f"{list(springs)}")
        out["springs"] = tuple(springs)
    if points is not None:
        out["points"] = _point_list(t.key("points"), points)
    for edge in PLANFORM_EDGES:
        r = t.raw(edge)
        if r is not None:
            out[edge] = _fraction_range(t.key(edge), r)
    t.done()
    if len(out) == 1:
        raise ValueError(f"support.kind = \"partial\" needs {t.key('points')} and/or a range of "
                         f"one of the edges ({', '.join(t.key(e) for e in PLANFORM_EDGES)})")
    return out


def partial_support_nodes(mesh: PlateMesh, points=(), ranges=(), tol: float = 1e-9,
                          ) -> np.ndarray:
    """Nodes held by a ``"partial"`` support: the node nearest to each of ``points``
    ((x, y) m, Euclidean distance; ties go to the lower node number) and the nodes of the named
    edges (:data:`PLANFORM_EDGES`) whose fraction along the edge lies in a range.

    Parameters
    ----------
    mesh : a structured mesh (:func:`asekit.structure.mesh.structured_mesh` or ``panels_mesh``).
    points : iterable of (x, y) m.
    ranges : iterable of (edge, (start, end)): along ``root`` and ``tip`` the fraction is the
        chord fraction (x - x_le) / c of the edge's nodes, along ``leading_edge`` and
        ``trailing_edge`` the span fraction (y - y_min) / (y_max - y_min); ``tol`` widens each
        range (relative).

    Returns
    -------
    Sorted unique node indices. ValueError naming ``support.<edge>`` when a range holds no
    node.

    Examples
    --------
    >>> from asekit.geometry import Planform
    >>> from asekit.structure.mesh import structured_mesh
    >>> from asekit.geometry import Thickness
    >>> m = structured_mesh(Planform((0.0, 0.0), 1.0, (0.0, 1.0), 1.0), Thickness(0.01, 0.01),
    ...                     4, 2)
    >>> partial_support_nodes(m, points=[(0.26, 0.0)], ranges=[("root", (0.5, 1.0))]).tolist()
    [1, 2, 3, 4]
    """
    held = [int(np.argmin(np.hypot(*(mesh.nodes - np.asarray(p, float)).T))) for p in points]
    y = mesh.nodes[:, 1]
    for edge, (a, b) in ranges:
        nodes = planform_edge_nodes(mesh, edge)
        if edge in ("root", "tip"):
            x = mesh.nodes[nodes, 0]
            frac = (x - x.min()) / np.ptp(x)
        else:
            frac = (y[nodes] - y.min()) / np.ptp(y)
        sel = nodes[(frac >= a - tol) & (frac <= b + tol)]
        if sel.size == 0:
            raise ValueError(f"support.{edge} = [{a:g}, {b:g}] holds no node of the mesh (its "
                             f"nodes there are at fractions "
                             f"{np.array2string(np.sort(frac), precision=4)}); widen the range")
        held.extend(int(n) for n in sel)
    return np.unique(np.asarray(held, dtype=np.int64))


def rigid_restraint(nodes_xy: np.ndarray, k_w, k_theta_x, k_theta_y) -> np.ndarray:
    """The 3 x 3 stiffness that grounded springs at nodes (x, y) m give the plate's rigid-body
    motions w = a + b x + c y (so theta_x = dw/dy = c, theta_y = -dw/dx = -b):

        R = sum_n k_w [1, x, y]^T [1, x, y] + k_theta_x e_c e_c^T + k_theta_y e_b e_b^T,

    in (a, b, c). The plate keeps a rigid-body mode exactly when R is singular (a clamped node
    is the limit of infinite springs). ``k_*`` are scalars or per-node arrays.

    Examples
    --------
    >>> bool(np.linalg.eigvalsh(rigid_restraint(np.array([[0.0, 0], [1, 0]]), 1.0, 0, 0))[0]
    ...      < 1e-12)        # two pinned nodes: rotation about their line is free
    True
    """
    xy = np.asarray(nodes_xy, float).reshape(-1, 2)
    k_w, k_tx, k_ty = (np.broadcast_to(np.asarray(k, float), (xy.shape[0],))
                       for k in (k_w, k_theta_x, k_theta_y))
    a = np.column_stack([np.ones(xy.shape[0]), xy])
    R = (a * k_w[:, None]).T @ a
    R[2, 2] += k_tx.sum()
    R[1, 1] += k_ty.sum()
    return R


def _check_rigid_restraint(mesh, nodes, k, condition) -> None:
    """Refuse held nodes that leave a rigid-body mode (``R`` of :func:`rigid_restraint`
    singular, relative to the mesh's size)."""
    xy = mesh.nodes[nodes] - mesh.nodes.mean(axis=0)
    L = float(np.ptp(mesh.nodes, axis=0).max())
    scale = np.diag([1.0, 1.0 / L, 1.0 / L])             # a, b L, c L: same units
    R = scale @ rigid_restraint(xy, *k) @ scale
    ev = np.linalg.eigvalsh(R)
    if ev[0] <= 1e-9 * max(ev[-1], 1e-300):
        raise ValueError(f"support.condition = \"{condition}\" at nodes {nodes.tolist()} leaves a "
                         f"rigid-body motion of the plate free (e.g. a rotation about the line "
                         f"of pinned nodes); hold at least three nodes not on a line, clamp, or "
                         f"add rotational springs")


def _partial_system(mesh, K, M, spec) -> SupportedSystem:
    ranges = [(e, spec.option(e)) for e in PLANFORM_EDGES if spec.option(e) is not None]
    nodes = partial_support_nodes(mesh, spec.option("points", ()), ranges)
    condition = spec.option("condition", "clamped")
    n = K.shape[0]
    K, M = sp.csr_matrix(K), sp.csr_matrix(M)
    if condition == PARTIAL_SPRINGS:                  # grounded springs: K + sum k e e^T
        k = np.asarray(spec.option("springs"), float)
        _check_rigid_restraint(mesh, nodes, k, condition)
        dofs = (DOF_PER_NODE * nodes[:, None] + np.arange(DOF_PER_NODE)).ravel()
        K = (K + sp.csr_matrix((np.tile(k, nodes.size), (dofs, dofs)), shape=K.shape)).tocsr()
        T = sp.identity(n, format="csr")
        label = f"plate on springs {k.tolist()} at nodes {nodes.tolist()}"
    else:
        if condition == "pinned":
            _check_rigid_restraint(mesh, nodes, (1.0, 0.0, 0.0), condition)
        fixed = (DOF_PER_NODE * nodes[:, None] + np.asarray(PARTIAL_CONDITIONS[condition])).ravel()
        free = np.setdiff1d(np.arange(n), fixed)
        T = sp.csr_matrix((np.ones(free.size), (free, np.arange(free.size))),
                          shape=(n, free.size))
        label = f"plate {condition} at nodes {nodes.tolist()}"
    return SupportedSystem(K=(T.T @ K @ T).tocsr(), M=(T.T @ M @ T).tocsr(), T=T,
                           shaft_index=None, ground_index=None, fictitious_inertia=0.0,
                           shaft_nodes=np.array([], dtype=np.int64), mesh=mesh, label=label)


#: The support kinds of a case file, by ``support.kind``.
SUPPORTS: dict[str, SupportKind] = {s.name: s for s in (
    SupportKind("clamped_root", "every degree of freedom of the root-chord nodes fixed",
                _parse_clamped_root, _clamped_system, _fixed_modal_model(_clamped_system)),
    SupportKind("edges", "clamped, simply supported, sliding or free root, tip, leading and "
                "trailing edges", _parse_edges, _edges_system, _fixed_modal_model(_edges_system)),
    SupportKind("shaft", "the thesis's pitch shaft (FN2: rigid pitch mode + elastic modes; "
                "FN1: spring to ground)", _parse_shaft, _shaft_system, _shaft_modal_model,
                has_rigid_mode=lambda spec: spec.model == "FN2"),
    SupportKind("partial", "clamped, pinned or spring-supported nodes nearest to listed points "
                "and on parts of the root, tip, leading and trailing edges", _parse_partial, _partial_system,
                _fixed_modal_model(_partial_system)),
)}


def support_kind(kind: str) -> SupportKind:
    """The :class:`SupportKind` of ``kind``; ValueError naming ``support.kind`` and the known
    kinds otherwise."""
    try:
        return SUPPORTS[kind]
    except (KeyError, TypeError):
        raise ValueError(f"support.kind must be one of {', '.join(map(repr, SUPPORTS))}, "
                         f"got {kind!r}") from None
