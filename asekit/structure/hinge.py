"""A plate region released along a hinge line: the structure of an elastic control surface.

The surface is a set of elements of the plate mesh (``flap_elements``) lying aft of a hinge
line that runs along element edges. :func:`split_at_hinge` gives the surface its own copies of
the nodes it shares with the wing: the copies on the hinge line stay joined to the wing, the
copies on the surface's side edges are free (the gap between a flap and the wing beside it).

:func:`release_hinge` joins the hinge copies to their wing nodes by linear multi-point
constraints, eliminated by a master-slave transformation u = T q (Cook, Malkus, Plesha & Witt,
*Concepts and Applications of Finite Element Analysis*, 4th ed., 2002, Sec. 9.2, Eqs. 9.2-3 to
9.2-5: K_r = T^T K T, M_r = T^T M T). With the unit hinge axis s = (s_x, s_y) (outboard) in the
plate plane and the rotation vector (theta_x, theta_y) of the plate's convention
(theta_x = dw/dy, theta_y = -dw/dx, :mod:`asekit.structure.plate`), a hinge copy c of wing node
m is the slave

    w_c = w_m,      (theta_x, theta_y)_c = (theta_x, theta_y)_m + r s,

so the translation and the rotation about the in-plane normal to the hinge are tied, the
rotation about the hinge axis is released, and r is the relative rotation of the surface about
its hinge (rad, trailing edge down positive, as :mod:`asekit.aero.control_surface`).
``release = "single"``: one r for the whole hinge (a torque tube driven by one actuator);
``"distributed"``: one r_n per hinge node (a piano hinge), each on its share of the spring.
The hinge spring k_h (N m/rad) and damper c_h (N m s/rad) act on r: k_h on the single r, or
k_h w_n on r_n with w_n the node's share of the hinge length (trapezoidal, sum w_n = 1), so a
uniform relative rotation r meets the moment k_h r either way. The hinge rotation (the
length-weighted mean of the r_n) and the spring's hinge moment H = sum k_h w_n r_n (N m) are
outputs (:meth:`ReleasedHinge.hinge_rotation`, :meth:`ReleasedHinge.hinge_moment`).

Several surfaces side by side (inboard and outboard ailerons): :func:`split_at_hinges` splits
the mesh at every surface's hinge line and side edges at once, :func:`release_hinges` releases
each hinge to its own rotation r_k on its own spring and damper, and
:func:`hinge_constraint_modes` gives the n constraint modes of Craig & Bampton (1968, Eq. 5),
each surface's static rotation with the others held.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from asekit.structure.mesh import PlateMesh
from asekit.structure.plate import DOF_PER_NODE
from asekit.util.validate import in_range

#: the hinge releases of :func:`release_hinge`
RELEASES = ("single", "distributed")


@dataclass(frozen=True)
class HingeSplit:
    """A mesh whose surface elements have their own copies of the nodes shared with the wing.

    ``mesh`` the split mesh (the original nodes first, then the copies; the surface's elements
    renumbered to the copies); ``n_original`` the original node count; ``copy_of`` (n_c,) the
    original node of each copy; ``on_hinge`` (n_c,) True for a copy on the hinge line (tied by
    :func:`release_hinge`), False for one on a side edge (free); ``weight`` (n_c,) each hinge
    copy's share of the hinge length (0 on the side edges, sum 1); ``flap_elements`` (n_elem,)
    bool; ``hinge_axis`` (2,) the unit hinge direction; ``first_copy`` the position of this
    surface's first copy among the mesh's copies (0 for one surface; with several surfaces,
    :func:`split_at_hinges`, the copies are numbered surface after surface, so this surface's
    copy j is node ``n_original + first_copy + j`` of ``mesh``).
    """

    mesh: PlateMesh
    n_original: int
    copy_of: np.ndarray
    on_hinge: np.ndarray
    weight: np.ndarray
    flap_elements: np.ndarray
    hinge_axis: np.ndarray
    first_copy: int = 0

    @property
    def copy_nodes(self) -> np.ndarray:
        """(n_c,) the node numbers of this surface's copies in ``mesh``."""
        return self.n_original + self.first_copy + np.arange(self.copy_of.size)


def split_at_hinge(mesh: PlateMesh, flap_elements, hinge_point, hinge_axis) -> HingeSplit:
    """Copy the nodes that the surface's elements share with the wing (module docstring).

    Parameters
    ----------
    mesh : the plate mesh (:mod:`asekit.structure.mesh`).
    flap_elements : (n_elem,) bool, the elements of the surface (all aft of the hinge).
    hinge_point : (x, y) m, a point of the hinge line.
    hinge_axis : (s_x, s_y), its direction (normalised here; pointing outboard, s_y > 0).

    Returns
    -------
    HingeSplit

    Raises
    ------
    ValueError
        No surface element; an element of the surface ahead of the hinge; fewer than two
        shared nodes on the hinge line (the mesh has no element edge on the hinge).

    Examples
    --------
    A 2 x 2 mesh of a 1 m square, the aft column of elements a surface hinged at x = 0.5:

    >>> from asekit.geometry import Planform, Thickness
    >>> from asekit.structure.mesh import panels_mesh
    >>> pm = panels_mesh([Planform((0, 0), 1.0, (0, 1.0), 1.0)], Thickness(0.01, 0.01), 2, [2])
    >>> flap = pm.element_centroids()[:, 0] > 0.5
    >>> hs = split_at_hinge(pm, flap, (0.5, 0.0), (0.0, 1.0))
    >>> hs.copy_of.tolist(), hs.on_hinge.tolist(), hs.weight.tolist()
    ([1, 4, 7], [True, True, True], [0.25, 0.5, 0.25])
    """
    return split_at_hinges(mesh, [flap_elements], [hinge_point], [hinge_axis])[0]


def _surface_copies(mesh, flap, hinge_point, hinge_axis, wing_nodes, earlier_nodes, k):
    """Surface ``k``'s shared nodes (sorted), which of them lie on its hinge line, their
    shares of the hinge length and the unit hinge axis (:func:`split_at_hinges`)."""
    s = np.asarray(hinge_axis, float).reshape(2)
    s = s / np.hypot(*s)
    p0 = np.asarray(hinge_point, float).reshape(2)
    aft = np.array([s[1], -s[0]])
    d = (mesh.nodes - p0) @ aft                               # distance aft of the hinge (m)
    tol = 1e-9 * max(float(np.ptp(mesh.nodes[:, 0])), float(np.ptp(mesh.nodes[:, 1])), 1e-300)
    fn = np.unique(mesh.elements[flap])
    where = "" if k is None else f" (surface {k})"
    if np.any(d[fn] < -tol):
        raise ValueError(f"flap_elements must lie aft of the hinge line: an element of the "
                         f"surface{where} has a node ahead of it")
    shared = np.union1d(np.intersect1d(fn, wing_nodes), np.intersect1d(fn, earlier_nodes))
    on_hinge = (np.abs(d[shared]) <= tol) & np.isin(shared, wing_nodes)
    if on_hinge.sum() < 2:
        raise ValueError(f"the mesh has no element edge on the hinge line{where} (fewer than "
                         f"two shared nodes on it): place a row of nodes on the hinge")
    along = mesh.nodes[shared] @ s
    weight = np.zeros(shared.size)
    h = np.flatnonzero(on_hinge)
    order = h[np.argsort(along[h])]
    a = along[order]
    gaps = np.diff(a)
    w = np.zeros(a.size)
    w[:-1] += 0.5 * gaps
    w[1:] += 0.5 * gaps
    weight[order] = w / w.sum()
    return shared, on_hinge, weight, s


def split_at_hinges(mesh: PlateMesh, flap_elements, hinge_points, hinge_axes) -> tuple:
    """Split the mesh for several side-by-side surfaces at once (:func:`split_at_hinge`'s rule
    surface by surface).

    Surface k copies the nodes its elements share with the wing (the elements of no surface)
    and with the surfaces before it; a copy is tied at the hinge when it lies on surface k's
    hinge line and on a wing element, else it is free (a side edge, also the gap between two
    adjacent surfaces: the first of the two keeps the original node, the second gets a free
    copy, so no node is left without an element). Surfaces may not share an element (a tab
    nested in a flap is not a side-by-side surface).

    Parameters
    ----------
    mesh : the plate mesh.
    flap_elements : n_s arrays (n_elem,) of bool, one per surface, disjoint.
    hinge_points : n_s points (x, y) m, one on each hinge line.
    hinge_axes : n_s directions (s_x, s_y) (normalised here; outboard).

    Returns
    -------
    tuple of n_s :class:`HingeSplit`, all on the same split ``mesh`` (the original nodes, then
    surface 0's copies, then surface 1's, ...; ``first_copy`` tells where each begins).

    Raises
    ------
    ValueError
        As :func:`split_at_hinge`, naming the surface; two surfaces sharing an element.

    Examples
    --------
    The 2 x 2 mesh of :func:`split_at_hinge`, the aft column split into an inboard and an
    outboard surface: the node between them at the trailing edge (node 5) stays the inboard
    surface's, the outboard one gets a free copy of it.

    >>> from asekit.geometry import Planform, Thickness
    >>> from asekit.structure.mesh import panels_mesh
    >>> pm = panels_mesh([Planform((0, 0), 1.0, (0, 1.0), 1.0)], Thickness(0.01, 0.01), 2, [2])
    >>> c = pm.element_centroids()
    >>> a, b = split_at_hinges(pm, [(c[:, 0] > 0.5) & (c[:, 1] < 0.5),
    ...                             (c[:, 0] > 0.5) & (c[:, 1] > 0.5)],
    ...                        [(0.5, 0.0)] * 2, [(0.0, 1.0)] * 2)
    >>> a.copy_of.tolist(), a.on_hinge.tolist(), b.copy_of.tolist(), b.on_hinge.tolist()
    ([1, 4], [True, True], [4, 5, 7], [True, False, True])
    >>> a.mesh.n_nodes, b.first_copy
    (14, 2)
    """
    flaps = [np.asarray(f, bool).reshape(-1) for f in flap_elements]
    n_s = len(flaps)
    if n_s == 0 or len(hinge_points) != n_s or len(hinge_axes) != n_s:
        raise ValueError(f"flap_elements, hinge_points and hinge_axes must have one entry per "
                         f"surface (at least one), got {n_s}, {len(hinge_points)} and "
                         f"{len(hinge_axes)}")
    for f in flaps:
        if f.shape != (mesh.n_elements,) or not f.any():
            raise ValueError(f"flap_elements must be {mesh.n_elements} booleans with at least "
                             f"one True, got {f.size} with {int(f.sum())} True")
    count = np.sum(flaps, axis=0)
    if np.any(count > 1):
        raise ValueError("flap_elements: two surfaces share an element (a surface nested in "
                         "another is not supported)")
    wing_nodes = np.unique(mesh.elements[count == 0])
    n0 = mesh.n_nodes
    elements = mesh.elements.copy()
    parts, offset = [], 0
    for k, (flap, p, a) in enumerate(zip(flaps, hinge_points, hinge_axes)):
        earlier = (np.unique(mesh.elements[np.any(flaps[:k], axis=0)]) if k
                   else np.zeros(0, int))
        shared, on_hinge, weight, s = _surface_copies(mesh, flap, p, a, wing_nodes, earlier,
                                                      None if n_s == 1 else k)
        new = np.full(n0, -1)
        new[shared] = n0 + offset + np.arange(shared.size)
        sub = mesh.elements[flap]
        elements[flap] = np.where(new[sub] >= 0, new[sub], sub)
        parts.append((shared, on_hinge, weight, flap, s, offset))
        offset += shared.size
    copies = np.concatenate([q[0] for q in parts])
    split = replace(mesh, nodes=np.vstack([mesh.nodes, mesh.nodes[copies]]), elements=elements)
    return tuple(HingeSplit(split, n0, sh, oh, w, f, s, off) for sh, oh, w, f, s, off in parts)


@dataclass(frozen=True)
class ReleasedHinge:
    """The split structure with its hinge constraints eliminated (:func:`release_hinge`,
    :func:`release_hinges`).

    ``K``, ``M``, ``C`` (n_q, n_q) sparse reduced stiffness, mass and (hinge) damping;
    ``T`` (3 n_split_nodes, n_q) sparse, u = T q on the split mesh's DOFs; ``hinge_index``
    (n_r,) the positions in q of the relative rotations r; ``hinge_stiffness`` (n_r,) the
    spring on each (N m/rad); ``weight`` (n_r,) their shares of the hinge length; ``split``
    the (first) surface's :class:`HingeSplit`; ``splits`` all of them (one per surface, empty
    for :func:`release_hinge`'s one surface); ``surface`` (n_r,) the surface of each r (None:
    all the one surface's).
    """

    K: sp.csr_matrix
    M: sp.csr_matrix
    C: sp.csr_matrix
    T: sp.csr_matrix
    hinge_index: np.ndarray
    hinge_stiffness: np.ndarray
    weight: np.ndarray
    split: HingeSplit
    splits: tuple = ()
    surface: np.ndarray | None = None

    def _per_surface(self, coeff, q) -> np.ndarray:
        v = np.asarray(q)[self.hinge_index]
        if len(self.splits) <= 1:
            return coeff @ v
        return np.stack([coeff[self.surface == k] @ v[self.surface == k]
                         for k in range(len(self.splits))])

    def hinge_rotation(self, q) -> np.ndarray:
        """The hinge rotation (rad): the length-weighted mean relative rotation sum w_n r_n of
        the reduced vector(s) ``q`` (n_q, ...); (n_s, ...) one per surface for several."""
        return self._per_surface(self.weight, q)

    def hinge_moment(self, q) -> np.ndarray:
        """The hinge spring's moment H = sum k_n r_n (N m; the moment that holds the surface,
        positive when the surface is rotated trailing edge down) of ``q`` (n_q, ...); (n_s, ...)
        one per surface for several."""
        return self._per_surface(self.hinge_stiffness, q)


def release_hinge(split: HingeSplit, K, M, hinge_stiffness: float, hinge_damping: float = 0.0,
                  release: str = "single", support=None, support_stiffness=None,
                  support_mass=None) -> ReleasedHinge:
    """Tie the hinge copies to the wing with the rotation about the hinge released (module
    docstring): u = T q with q = [q_s, free side-edge copies' DOFs, r].

    Parameters
    ----------
    split : :func:`split_at_hinge`.
    K, M : (3 n, 3 n) stiffness and mass of ``split.mesh``
        (:func:`asekit.structure.assembly.assemble`), unsupported.
    hinge_stiffness : k_h (N m/rad), >= 0. hinge_damping : c_h (N m s/rad), >= 0.
    release : "single" or "distributed" (:data:`RELEASES`).
    support : optional (3 n_original, n_s) map of the supports on the original nodes (the
        ``T`` of :func:`asekit.structure.assembly.clamped_edge` on the unsplit mesh); default
        the identity (free-free).
    support_stiffness, support_mass : optional (n_s, n_s) stiffness and mass the support adds
        on its own coordinates beyond T^T K T (a shaft's spring, grounded springs: the
        supported system's K_s - T^T K_0 T), added to the q_s block.

    Returns
    -------
    ReleasedHinge

    Examples
    --------
    The split of :func:`split_at_hinge`'s example released about one hinge rotation: the
    hinge copies' 9 DOFs are replaced by 1.

    >>> from asekit.geometry import Material, Planform, Thickness
    >>> from asekit.structure.assembly import assemble
    >>> from asekit.structure.mesh import panels_mesh
    >>> pm = panels_mesh([Planform((0, 0), 1.0, (0, 1.0), 1.0)], Thickness(0.01, 0.01), 2, [2])
    >>> hs = split_at_hinge(pm, pm.element_centroids()[:, 0] > 0.5, (0.5, 0.0), (0.0, 1.0))
    >>> K, M = assemble(hs.mesh, Material(70e9, 0.3, 2700.0))
    >>> rh = release_hinge(hs, K, M, 10.0)
    >>> rh.T.shape, rh.hinge_index.tolist()
    ((36, 28), [27])
    """
    if release not in RELEASES:
        raise ValueError(f"release must be one of {RELEASES}, got {release!r}")
    k_h = in_range("hinge_stiffness", hinge_stiffness, 0.0, inclusive=True)
    c_h = in_range("hinge_damping", hinge_damping, 0.0, inclusive=True)
    return _release((split,), K, M, [k_h], [c_h], release, support, support_stiffness,
                    support_mass)


def release_hinges(splits, K, M, hinge_stiffness, hinge_damping=0.0, support=None,
                   support_stiffness=None, support_mass=None) -> ReleasedHinge:
    """Release several side-by-side surfaces (:func:`split_at_hinges`), each about its own
    hinge rotation r_k on its own spring k_h,k and damper c_h,k (a ``"single"`` release per
    surface, :func:`release_hinge`'s constraints surface by surface):
    q = [q_s, every surface's free copies' DOFs (surface by surface), r_0, ..., r_(n_s - 1)].

    Parameters
    ----------
    splits : the tuple of :func:`split_at_hinges`.
    K, M : (3 n, 3 n) stiffness and mass of the split mesh, unsupported.
    hinge_stiffness, hinge_damping : one value per surface or one for all (N m/rad, N m s/rad,
        >= 0).
    support, support_stiffness, support_mass : as :func:`release_hinge`.

    Returns
    -------
    ReleasedHinge (``hinge_index`` (n_s,), one rotation per surface, in the surfaces' order).

    Examples
    --------
    The two surfaces of :func:`split_at_hinges`' example: the 4 + 2 hinge copies' DOFs are
    replaced by two rotations, the outboard surface's free copy keeps its 3 DOFs.

    >>> from asekit.geometry import Material, Planform, Thickness
    >>> from asekit.structure.assembly import assemble
    >>> from asekit.structure.mesh import panels_mesh
    >>> pm = panels_mesh([Planform((0, 0), 1.0, (0, 1.0), 1.0)], Thickness(0.01, 0.01), 2, [2])
    >>> c = pm.element_centroids()
    >>> parts = split_at_hinges(pm, [(c[:, 0] > 0.5) & (c[:, 1] < 0.5),
    ...                              (c[:, 0] > 0.5) & (c[:, 1] > 0.5)],
    ...                         [(0.5, 0.0)] * 2, [(0.0, 1.0)] * 2)
    >>> K, M = assemble(parts[0].mesh, Material(70e9, 0.3, 2700.0))
    >>> rh = release_hinges(parts, K, M, [10.0, 20.0])
    >>> rh.T.shape, rh.hinge_index.tolist(), rh.hinge_stiffness.tolist()
    ((42, 32), [30, 31], [10.0, 20.0])
    """
    splits = tuple(splits)
    n = len(splits)
    k_h = np.broadcast_to(np.asarray(hinge_stiffness, float), (n,))
    c_h = np.broadcast_to(np.asarray(hinge_damping, float), (n,))
    k_h = [in_range("hinge_stiffness", x, 0.0, inclusive=True) for x in k_h]
    c_h = [in_range("hinge_damping", x, 0.0, inclusive=True) for x in c_h]
    return _release(splits, K, M, k_h, c_h, "single", support, support_stiffness,
                    support_mass)


def _release_map(splits, S, release):
    """T (u = T q) and the hinge rotations' positions in q (:func:`_release`)."""
    first = splits[0]
    n0, dof = first.n_original, DOF_PER_NODE
    n_s = S.shape[1]
    free = [sp_.copy_nodes[~sp_.on_hinge] for sp_ in splits]
    n_f = dof * sum(f.size for f in free)
    hinge = [np.flatnonzero(sp_.on_hinge) for sp_ in splits]
    n_r = [1 if release == "single" else h.size for h in hinge]
    n_q = n_s + n_f + sum(n_r)
    blocks = sp.lil_matrix((dof * first.mesh.n_nodes, n_q))
    blocks[: dof * n0, :n_s] = S
    for j, node in enumerate(np.concatenate(free)):
        for k in range(dof):
            blocks[dof * node + k, n_s + dof * j + k] = 1.0
    S = S.tolil()
    r0 = n_s + n_f
    for sp_, h, nr in zip(splits, hinge, n_r):
        s = sp_.hinge_axis
        for j, c in enumerate(h):
            m = sp_.copy_of[c]
            node = sp_.copy_nodes[c]
            r = r0 + (0 if nr == 1 else j)
            for k in range(dof):
                blocks[dof * node + k, :n_s] = S[dof * m + k, :]
            blocks[dof * node + 1, r] = s[0]
            blocks[dof * node + 2, r] = s[1]
        r0 += nr
    return blocks.tocsr(), n_s + n_f + np.arange(sum(n_r)), n_r


def _release(splits, K, M, k_h, c_h, release, support, support_stiffness, support_mass):
    """The reduced system of :func:`release_hinge` / :func:`release_hinges` (K_r = T^T K T +
    the springs, M_r = T^T M T, Cook et al. 2002, Eqs. 9.2-3 to 9.2-5)."""
    n0, dof = splits[0].n_original, DOF_PER_NODE
    S = sp.identity(dof * n0, format="csr") if support is None else sp.csr_matrix(support)
    if S.shape[0] != dof * n0:
        raise ValueError(f"support must have {dof * n0} rows (the original nodes' DOFs), got "
                         f"{S.shape[0]}")
    n_s = S.shape[1]
    T, idx, n_r = _release_map(splits, S, release)
    n_q = T.shape[1]
    surface = np.repeat(np.arange(len(splits)), n_r)
    if release == "single":
        weight = np.ones(len(splits))
    else:
        weight = splits[0].weight[splits[0].on_hinge]
    k_n = np.asarray(k_h, float)[surface] * weight
    c_n = np.asarray(c_h, float)[surface] * weight
    spring = sp.csr_matrix((k_n, (idx, idx)), shape=(n_q, n_q))
    damper = sp.csr_matrix((c_n, (idx, idx)), shape=(n_q, n_q))
    Kr = (T.T @ K @ T).tocsr() + spring
    Mr = (T.T @ M @ T).tocsr()
    pad = sp.eye(n_q, n_s, format="csr")                     # q_s block of q
    for name, extra in (("support_stiffness", support_stiffness), ("support_mass", support_mass)):
        if extra is None:
            continue
        if extra.shape != (n_s, n_s):
            raise ValueError(f"{name} must be ({n_s}, {n_s}), got {extra.shape}")
        if name == "support_stiffness":
            Kr = Kr + pad @ sp.csr_matrix(extra) @ pad.T
        else:
            Mr = Mr + pad @ sp.csr_matrix(extra) @ pad.T
    several = len(splits) > 1
    return ReleasedHinge(K=(0.5 * (Kr + Kr.T)).tocsr(), M=(0.5 * (Mr + Mr.T)).tocsr(),
                         C=damper, T=T, hinge_index=idx, hinge_stiffness=k_n, weight=weight,
                         split=splits[0], splits=splits if several else (),
                         surface=surface if several else None)


def released_modes(released: ReleasedHinge, n_modes: int, shift: float = -1.0):
    """The lowest ``n_modes`` modes of the released structure, K v = omega^2 M v.

    Dense symmetric eigen-solution (:func:`scipy.linalg.eigh`, the reduced models are a few
    thousand DOFs at most) when n_q <= 3000, else shift-invert Lanczos about ``shift``
    (rad^2/s^2, below zero so rigid modes are found).

    Returns
    -------
    (f_hz (n_modes,), q (n_q, n_modes)) natural frequencies (Hz, sqrt of max(lambda, 0) / 2 pi)
    and mass-normalised vectors in the reduced coordinates.

    Examples
    --------
    The free-free 2 x 2 plate of :func:`release_hinge` with a zero hinge spring: four
    rigid-body modes (plunge, two rotations, the surface's rotation about the hinge).

    >>> from asekit.geometry import Material, Planform, Thickness
    >>> from asekit.structure.assembly import assemble
    >>> from asekit.structure.mesh import panels_mesh
    >>> pm = panels_mesh([Planform((0, 0), 1.0, (0, 1.0), 1.0)], Thickness(0.01, 0.01), 2, [2])
    >>> hs = split_at_hinge(pm, pm.element_centroids()[:, 0] > 0.5, (0.5, 0.0), (0.0, 1.0))
    >>> K, M = assemble(hs.mesh, Material(70e9, 0.3, 2700.0))
    >>> f, _ = released_modes(release_hinge(hs, K, M, 0.0), 5)
    >>> int((f < 1e-3 * f[-1]).sum())
    4
    """
    import scipy.linalg as sla
    import scipy.sparse.linalg as spla

    if released.K.shape[0] <= 3000:
        lam, v = sla.eigh(released.K.toarray(), released.M.toarray(),
                          subset_by_index=[0, n_modes - 1])
    else:
        lam, v = spla.eigsh(released.K, k=n_modes, M=released.M, sigma=shift, which="LM")
        order = np.argsort(lam)
        lam, v = lam[order], v[:, order]
    return np.sqrt(np.maximum(lam, 0.0)) / (2.0 * np.pi), v


def hinge_constraint_mode(released: ReleasedHinge) -> np.ndarray:
    """The static shape of a unit hinge rotation (rad) of a ``"single"`` release, the other
    coordinates unloaded: q_o = -K_oo^-1 K_or (the constraint mode of Craig & Bampton, "Coupling
    of substructures for dynamic analyses", AIAA J. 6(7), 1968, Eq. 5). On a supported wing it
    is the surface's rigid rotation about the hinge (no strain), computed, not assumed.

    Returns
    -------
    (n_q,) reduced vector with q[hinge_index] = 1.

    Examples
    --------
    >>> from asekit.geometry import Material, Planform, Thickness
    >>> from asekit.structure.assembly import assemble, clamped_edge
    >>> from asekit.structure.mesh import panels_mesh
    >>> pm = panels_mesh([Planform((0, 0), 1.0, (0, 1.0), 1.0)], Thickness(0.01, 0.01), 2, [2])
    >>> c = pm.element_centroids()                       # the outboard aft element's surface
    >>> hs = split_at_hinge(pm, (c[:, 0] > 0.5) & (c[:, 1] > 0.5), (0.5, 0.5), (0.0, 1.0))
    >>> K, M = assemble(hs.mesh, Material(70e9, 0.3, 2700.0))
    >>> K0, M0 = assemble(pm, Material(70e9, 0.3, 2700.0))
    >>> rh = release_hinge(hs, K, M, 1.0, support=clamped_edge(pm, K0, M0).T)
    >>> u = rh.T @ hinge_constraint_mode(rh)
    >>> round(float(u[3 * 8]), 9)                      # w of the trailing-edge tip node: -0.5 m
    -0.5
    """
    if released.hinge_index.size != 1:
        raise ValueError("hinge_constraint_mode needs a 'single' release (one hinge rotation)")
    return hinge_constraint_modes(released)[:, 0]


def hinge_constraint_modes(released: ReleasedHinge) -> np.ndarray:
    """The constraint modes of all the hinge rotations r (Craig & Bampton 1968, Eq. 5, the
    interface coordinates being the r): column k is the static shape of r_k = 1 with the other
    rotations held at 0 and the rest of q unloaded, Psi_o = -K_oo^-1 K_oR (one sparse
    factorisation of K_oo for all columns). With several surfaces
    (:func:`release_hinges`) each column is one surface's rotation about its own hinge, the
    others held.

    Returns
    -------
    (n_q, n_r) reduced vectors, Psi[hinge_index] = identity.

    Examples
    --------
    Two side-by-side surfaces on the two outboard aft elements of a clamped 2 x 3 plate
    (1 m x 1.5 m): each mode moves the trailing edge of its own surface only (w = -0.5 m at
    nodes 8, (1, 1), and 11, (1, 1.5)).

    >>> from asekit.geometry import Material, Planform, Thickness
    >>> from asekit.structure.assembly import assemble, clamped_edge
    >>> from asekit.structure.mesh import panels_mesh
    >>> pm = panels_mesh([Planform((0, 0), 1.0, (0, 1.5), 1.0)], Thickness(0.01, 0.01), 2, [3])
    >>> c = pm.element_centroids()
    >>> parts = split_at_hinges(pm, [(c[:, 0] > 0.5) & (abs(c[:, 1] - 0.75) < 0.1),
    ...                              (c[:, 0] > 0.5) & (c[:, 1] > 1.0)],
    ...                         [(0.5, 0.0)] * 2, [(0.0, 1.0)] * 2)
    >>> K, M = assemble(parts[0].mesh, Material(70e9, 0.3, 2700.0))
    >>> K0, M0 = assemble(pm, Material(70e9, 0.3, 2700.0))
    >>> rh = release_hinges(parts, K, M, 1.0, support=clamped_edge(pm, K0, M0).T)
    >>> u = rh.T @ hinge_constraint_modes(rh)
    >>> (np.round(u[3 * np.array([8, 11])], 9) + 0.0).tolist()
    [[-0.5, 0.0], [0.0, -0.5]]
    """
    import scipy.sparse.linalg as spla

    R = np.asarray(released.hinge_index)
    other = np.setdiff1d(np.arange(released.K.shape[0]), R)
    K = released.K.tocsc()
    psi = np.zeros((K.shape[0], R.size))
    psi[R, np.arange(R.size)] = 1.0
    rhs = K[other][:, R].toarray()
    sol = spla.splu(K[other][:, other].tocsc()).solve(rhs)
    psi[other] = -sol
    return psi


def hinge_balance_mass(split: HingeSplit, position, distance_aft: float, mass: float):
    """Mass matrix (3 n, 3 n) of a balance mass carried by the surface on a rigid arm from its
    hinge line, on the split mesh's degrees of freedom (w, theta_x, theta_y per node).

    The mass m sits at ``distance_aft`` d (m; < 0 ahead of the hinge, the usual mass balance)
    from the hinge line and is attached to the surface's hinge copy c nearest to it along the
    hinge. A rigid arm moves it by w_b = w_c - d (s_x theta_x,c + s_y theta_y,c), the surface's
    rotation about the hinge axis s at c times the lever -d (a rigid link, Cook, Malkus,
    Plesha & Witt 2002, Sec. 9.2), so its mass matrix is m g g^T with g = (1, -d s_x, -d s_y)
    on c's degrees of freedom. Under a rigid hinge rotation r it adds m d to the surface's
    static unbalance and m d^2 to its inertia about the hinge, as a balance mass of the rigid
    kind (:func:`asekit.aeroelastic.control_surface.flap_modal_model`). The mass is placed at
    c's station along the hinge (its own is snapped to the nearest hinge node).

    Parameters
    ----------
    split : :class:`HingeSplit` of the surface.
    position : (x, y) m, the balance mass's position in the plate plane.
    distance_aft : d (m), its distance aft of the hinge line (negative ahead of it).
    mass : m (kg), >= 0.

    Returns
    -------
    scipy.sparse.csr_matrix (3 n_nodes, 3 n_nodes) of ``split.mesh``.

    Examples
    --------
    The 2 x 2 mesh of :func:`split_at_hinge`: 0.1 kg, 0.2 m ahead of the hinge at y = 0.4 sits
    on the middle hinge copy (node 10, y = 0.5); a unit hinge rotation of that copy moves it
    by -d = 0.2 m (up, the trailing edge going down), so w^T M_b u = 0.02: a static unbalance
    m d = -0.02 kg m (ahead of the hinge), and m d^2 = 0.004 kg m^2 of inertia.

    >>> from asekit.geometry import Planform, Thickness
    >>> from asekit.structure.mesh import panels_mesh
    >>> pm = panels_mesh([Planform((0, 0), 1.0, (0, 1.0), 1.0)], Thickness(0.01, 0.01), 2, [2])
    >>> hs = split_at_hinge(pm, pm.element_centroids()[:, 0] > 0.5, (0.5, 0.0), (0.0, 1.0))
    >>> Mb = hinge_balance_mass(hs, (0.3, 0.4), -0.2, 0.1)
    >>> u = np.zeros(Mb.shape[0]); u[3 * 10 + 2] = 1.0          # theta about the hinge axis
    >>> w = np.zeros(Mb.shape[0]); w[0::3] = 1.0
    >>> round(float(w @ (Mb @ u)), 6), round(float(u @ (Mb @ u)), 6)
    (0.02, 0.004)
    """
    in_range("mass", mass, 0.0, inclusive=True)
    d = float(distance_aft)
    if not np.isfinite(d):
        raise ValueError(f"distance_aft must be finite, got {distance_aft!r}")
    p = np.asarray(position, float).reshape(2)
    s = np.asarray(split.hinge_axis, float)
    copies = split.copy_nodes[split.on_hinge]
    nodes = split.mesh.nodes[copies]
    c = copies[int(np.argmin(np.abs((nodes - p) @ s)))]
    dofs = DOF_PER_NODE * c + np.arange(3)
    g = np.array([1.0, -d * s[0], -d * s[1]])
    n = DOF_PER_NODE * split.mesh.n_nodes
    rows, cols = np.meshgrid(dofs, dofs, indexing="ij")
    return sp.csr_matrix((mass * np.outer(g, g).ravel(), (rows.ravel(), cols.ravel())),
                         shape=(n, n))
