"""Stick models: a 3-D Euler-Bernoulli beam element, a straight beam along a reference axis,
clamped at its root, and its normal modes.

The element (two nodes, six degrees of freedom each, 12 in all) carries axial extension,
St Venant torsion and bending in its two principal planes, each with its own stiffness
(EA, GJ, EI_flap, EI_chord). In the element's local frame (e1 along the axis from node 1 to
node 2, e3 the surface normal, e2 = e3 x e1) the node displacements are (u1, u2, u3) and
rotations (r1, r2, r3). The stiffness is Przemieniecki's, *Theory of Matrix Structural
Analysis* (McGraw-Hill 1968, Sec. 5.6, Eq. 5.116): the cubic Hermite functions for the
deflections,

    N1 = 1 - 3 s^2 + 2 s^3,  N2 = L (s - 2 s^2 + s^3),  N3 = 3 s^2 - 2 s^3,  N4 = L (s^3 - s^2)

(s = xi / L in [0, 1]; the deflection's values and slopes at the nodes), and linear functions
for the axial displacement and the twist. The slopes are rotations: du2/dxi = r3 and
du3/dxi = -r2 (right-hand rule about e3 and e2).

The consistent mass (Przemieniecki Eq. 11.41 for the translations and the torsion) has the mass
per length m, the polar mass moment of inertia per length about the elastic axis I_p, and the
offset d of the section's mass axis *aft* of the elastic axis (along -e2 = e1 x e3; for an
axis along +y that is +x, downstream). The mass axis moves by u3 - d r1 (a nose-up twist r1
about +e1 moves a mass aft of the axis down), so the kinetic energy

    T = 1/2 int [ m (u1'^2 + u2'^2 + u3'^2) - 2 m d u3' r1' + I_p r1'^2 ] dxi     (' = d/dt)

couples bending and torsion through S = -m d int N_w^T N_theta dxi (Hermite by linear). This
is the uniform-wing model of Goland, "The flutter of a uniform cantilever wing", J. Appl.
Mech. 12 (1945) A197-A208, Eqs. (1)-(2), discretised; rotary inertia of the bending and the
chordwise mass coupling of in-plane bending (r3 d) are neglected (Euler-Bernoulli).

:func:`straight_beam` lays the elements along a reference axis in the (x, y) plane (the
aerodynamic surface's plane) through given stations; :func:`beam_modes` solves
K phi = omega^2 M phi with the root node clamped (all six degrees of freedom). Everything SI.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from asekit.util.validate import finite, finite_array, in_range, integer, positive

#: degrees of freedom per node: ux, uy, uz, rx, ry, rz (global frame).
NODE_DOF = 6


@dataclass(frozen=True)
class BeamSection:
    """Properties of a beam's cross-section (SI), uniform along an element.

    Parameters
    ----------
    ea : axial stiffness E A (N), >= 0 (0 only for a beam solved with its in-plane motion
        fixed, :func:`beam_modes` ``in_plane_fixed``).
    gj : torsional stiffness G J (N m^2), > 0.
    ei_flap : bending stiffness out of the surface's plane, deflection along e3 (N m^2), > 0.
    ei_chord : bending stiffness in the surface's plane, deflection along e2 (N m^2), >= 0
        (0 as ``ea``).
    mass : mass per unit length m (kg/m), > 0.
    polar_inertia : polar mass moment of inertia per unit length about the elastic axis
        I_p (kg m^2/m = kg m), >= 0 (0: the torsional inertia only from point masses, as a
        Nastran CBAR's).
    mass_offset : distance of the mass axis aft of the elastic axis d (m), any sign
        (I_p >= m d^2 is required: the inertia about the mass axis is not negative).

    Examples
    --------
    >>> s = BeamSection(1e9, 0.987e6, 9.77e6, 1e8, 35.71, 8.64, 0.18288)
    >>> round(s.polar_inertia - s.mass * s.mass_offset ** 2, 3)   # about the mass axis
    7.446
    """

    ea: float
    gj: float
    ei_flap: float
    ei_chord: float
    mass: float
    polar_inertia: float
    mass_offset: float = 0.0

    def __post_init__(self):
        for name in ("gj", "ei_flap", "mass"):
            object.__setattr__(self, name, positive(name, getattr(self, name)))
        for name in ("ea", "ei_chord", "polar_inertia"):
            object.__setattr__(self, name, in_range(name, getattr(self, name), 0.0, True))
        d = finite("mass_offset", self.mass_offset)
        object.__setattr__(self, "mass_offset", d)
        if self.polar_inertia < self.mass * d * d * (1 - 1e-12):
            raise ValueError(f"polar_inertia must be >= mass * mass_offset^2 = "
                             f"{self.mass * d * d:g} kg m (the inertia about the mass axis "
                             f"cannot be negative), got {self.polar_inertia:g}")


def _hermite_bending(ei: float, length: float, mass: float, slope_sign: float):
    """Stiffness and consistent mass (4 x 4) of one bending plane, DOFs (w1, r1, w2, r2) with
    the rotation r = slope_sign * dw/dxi (Przemieniecki Eqs. 5.116, 11.41)."""
    L = length
    k = ei / L ** 3 * np.array([[12, 6 * L, -12, 6 * L], [6 * L, 4 * L * L, -6 * L, 2 * L * L],
                                [-12, -6 * L, 12, -6 * L], [6 * L, 2 * L * L, -6 * L, 4 * L * L]])
    m = mass * L / 420 * np.array([[156, 22 * L, 54, -13 * L], [22 * L, 4 * L * L, 13 * L, -3 * L * L],
                                   [54, 13 * L, 156, -22 * L],
                                   [-13 * L, -3 * L * L, -22 * L, 4 * L * L]])
    s = np.diag([1.0, slope_sign, 1.0, slope_sign])
    return s @ k @ s, s @ m @ s


def element_matrices(section: BeamSection, length: float) -> tuple[np.ndarray, np.ndarray]:
    """Local stiffness and consistent mass matrices (12 x 12) of a 3-D Euler-Bernoulli beam.

    DOF order per node (u1, u2, u3, r1, r2, r3) in the element frame (e1 along the element),
    node 1 then node 2.

    Parameters
    ----------
    section : :class:`BeamSection`.
    length : element length L (m), > 0.

    Returns
    -------
    (K, M) : (12, 12) symmetric arrays (N/m, N, N m units per DOF pair; kg, kg m, kg m^2).

    The blocks: axial EA/L [[1, -1], [-1, 1]] and m L/6 [[2, 1], [1, 2]]; torsion GJ/L and
    I_p L/6 [[2, 1], [1, 2]]; the two bending planes by Hermite cubics (u3, r2 with
    r2 = -du3/dxi; u2, r3 with r3 = du2/dxi); the bending-torsion coupling
    S_ij = -m d int_0^L N_w,i N_theta,j dxi (module docstring).

    Examples
    --------
    >>> K, M = element_matrices(BeamSection(1.0, 1.0, 1.0, 1.0, 2.0, 1.0), 0.5)
    >>> round(float(M[[0, 6]][:, [0, 6]].sum()), 12)       # total axial mass m L
    1.0
    """
    L = positive("length", length)
    s = section
    K = np.zeros((12, 12))
    M = np.zeros((12, 12))
    ax = np.array([0, 6])
    tw = np.array([3, 9])
    K[np.ix_(ax, ax)] = s.ea / L * np.array([[1, -1], [-1, 1]])
    M[np.ix_(ax, ax)] = s.mass * L / 6 * np.array([[2, 1], [1, 2]])
    K[np.ix_(tw, tw)] = s.gj / L * np.array([[1, -1], [-1, 1]])
    M[np.ix_(tw, tw)] = s.polar_inertia * L / 6 * np.array([[2, 1], [1, 2]])
    flap = np.array([2, 4, 8, 10])            # u3, r2 (r2 = -du3/dxi)
    chord = np.array([1, 5, 7, 11])           # u2, r3 (r3 = +du2/dxi)
    kf, mf = _hermite_bending(s.ei_flap, L, s.mass, -1.0)
    kc, mc = _hermite_bending(s.ei_chord, L, s.mass, 1.0)
    K[np.ix_(flap, flap)] = kf
    M[np.ix_(flap, flap)] = mf
    K[np.ix_(chord, chord)] = kc
    M[np.ix_(chord, chord)] = mc
    # int_0^L N_w,i N_theta,j dxi, N_w = Hermite (w1, w1', w2, w2'), N_theta = (1 - s, s)
    hw = L * np.array([[7 / 20, 3 / 20], [L / 20, L / 30], [3 / 20, 7 / 20], [-L / 30, -L / 20]])
    hw = np.diag([1.0, -1.0, 1.0, -1.0]) @ hw          # slopes as the rotation r2 = -w'
    coup = -s.mass * s.mass_offset * hw
    M[np.ix_(flap, tw)] += coup
    M[np.ix_(tw, flap)] += coup.T
    return K, M


@dataclass(frozen=True)
class PointMass:
    """A rigid mass attached to a beam node with an offset (MSC Nastran's CONM2 idea).

    Parameters
    ----------
    node : index of the beam node it is attached to (0 = root).
    mass : mass (kg), >= 0.
    offset : (3,) vector from the node to the mass's centre, global axes (m).
    inertia : (3, 3) symmetric positive semi-definite inertia tensor about the mass's own
        centre, global axes (kg m^2), or (3,) its diagonal; default zero.

    Its 6 x 6 mass matrix on the node's (u, r) is T^T diag(m, m, m) T + [[0, 0], [0, J]] with
    the rigid-link kinematics u_c = u + r x o = T (u, r), T = [I, -[o x]] (Przemieniecki,
    *Theory of Matrix Structural Analysis*, 1968, Sec. 11.7, offset masses).

    Examples
    --------
    >>> pm = PointMass(3, 2.0, (0.5, 0.0, 0.0))
    >>> m6 = pm.matrix()
    >>> float(m6[2, 4]), float(m6[4, 4])      # uz-ry coupling -m o_x, ry inertia m o_x^2
    (-1.0, 0.5)
    """

    node: int
    mass: float
    offset: tuple = (0.0, 0.0, 0.0)
    inertia: tuple = (0.0, 0.0, 0.0)

    def __post_init__(self):
        object.__setattr__(self, "node", integer("node", self.node, low=0))
        m = finite("mass", self.mass)
        if m < 0:
            raise ValueError(f"mass must be >= 0 kg, got {m}")
        object.__setattr__(self, "mass", m)
        o = finite_array("offset", self.offset).ravel()
        if o.size != 3:
            raise ValueError(f"offset must be a 3-vector (m), got {o.size} values")
        object.__setattr__(self, "offset", tuple(o.tolist()))
        j = finite_array("inertia", self.inertia)
        j = np.diag(j.ravel()) if j.size == 3 else j
        scale = 1e-12 * max(float(np.abs(j).max(initial=0.0)), 1.0)
        if (j.shape != (3, 3) or not np.allclose(j, j.T, rtol=0, atol=scale)
                or np.linalg.eigvalsh(j).min() < -scale):
            raise ValueError("inertia must be a (3,) diagonal or a symmetric positive "
                             "semi-definite (3, 3) tensor (kg m^2)")
        object.__setattr__(self, "inertia", tuple(map(tuple, j.tolist())))

    def matrix(self) -> np.ndarray:
        """The 6 x 6 mass matrix on the node's (ux, uy, uz, rx, ry, rz)."""
        o = np.asarray(self.offset)
        skew = np.array([[0.0, -o[2], o[1]], [o[2], 0.0, -o[0]], [-o[1], o[0], 0.0]])
        T = np.hstack([np.eye(3), -skew])
        out = self.mass * T.T @ T
        out[3:, 3:] += np.asarray(self.inertia)
        return out


@dataclass(frozen=True)
class StraightBeam:
    """A straight beam along a reference (elastic) axis in the (x, y) plane.

    Attributes
    ----------
    root : (3,) the axis's root point (m).
    direction : (3,) unit vector e1 along the axis (z component 0).
    stations : (n_nodes,) distances of the nodes from the root along the axis (m), ascending,
        the first 0.
    sections : tuple of :class:`BeamSection`, one per element (n_nodes - 1).
    point_masses : tuple of :class:`PointMass` on its nodes (default none).
    """

    root: np.ndarray
    direction: np.ndarray
    stations: np.ndarray
    sections: tuple
    point_masses: tuple = ()

    @property
    def n_nodes(self) -> int:
        return self.stations.size

    @property
    def frame(self) -> np.ndarray:
        """(3, 3) rows e1, e2, e3: the element frame (e3 = +z, e2 = e3 x e1)."""
        e1 = self.direction
        e3 = np.array([0.0, 0.0, 1.0])
        return np.array([e1, np.cross(e3, e1), e3])

    @property
    def nodes(self) -> np.ndarray:
        """(n_nodes, 3) node coordinates (m)."""
        return self.root[None, :] + self.stations[:, None] * self.direction[None, :]


def straight_beam(root, direction, stations, sections, point_masses=()) -> StraightBeam:
    """A straight beam along an axis in the surface's plane, nodes at ``stations``.

    Parameters
    ----------
    root : (x, y) or (x, y, z) of the axis's root point (m).
    direction : (dx, dy) direction of the axis in the (x, y) plane (any length > 0;
        e.g. (0, 1) for an unswept wing along +y, (sin L, cos L) swept by L).
    stations : ascending distances along the axis from the root (m), the first 0, >= 2.
    sections : one :class:`BeamSection` for the whole beam, or one per element.
    point_masses : :class:`PointMass` es on the nodes (their ``node`` < number of stations).

    Returns
    -------
    :class:`StraightBeam`.

    Examples
    --------
    >>> sec = BeamSection(1e9, 1e6, 1e7, 1e8, 35.0, 8.0, 0.1)
    >>> b = straight_beam((0.6, 0.0), (0.0, 1.0), np.linspace(0, 6, 7), sec)
    >>> b.nodes[-1].tolist(), len(b.sections)
    ([0.6, 6.0, 0.0], 6)
    """
    r = finite_array("root", root).ravel()
    if r.size not in (2, 3):
        raise ValueError(f"root must be (x, y) or (x, y, z), got {r.size} values")
    r = np.append(r, 0.0) if r.size == 2 else r
    d = finite_array("direction", direction).ravel()
    if d.size != 2 or np.hypot(*d) <= 0:
        raise ValueError(f"direction must be a non-zero (dx, dy) in the (x, y) plane, got {d}")
    e1 = np.array([d[0], d[1], 0.0]) / np.hypot(*d)
    st = finite_array("stations", stations).ravel()
    if st.size < 2 or st[0] != 0.0 or np.any(np.diff(st) <= 0):
        raise ValueError(f"stations must hold >= 2 strictly ascending distances from 0 (m), "
                         f"got {st.tolist()}")
    if isinstance(sections, BeamSection):
        secs = (sections,) * (st.size - 1)
    elif isinstance(sections, (list, tuple)):
        secs = tuple(sections)
    else:
        secs = None
    if secs is None or len(secs) != st.size - 1 or not all(isinstance(s, BeamSection)
                                                          for s in secs):
        got = type(sections).__name__ if secs is None else f"{len(secs)} items"
        raise ValueError(f"sections must be one BeamSection or a list of {st.size - 1} of them "
                         f"(one per element), got {got}")
    pms = tuple(point_masses)
    for i, pm in enumerate(pms):
        if not isinstance(pm, PointMass) or pm.node >= st.size:
            raise ValueError(f"point_masses[{i}] must be a PointMass on a node in "
                             f"[0, {st.size - 1}], got {pm!r}")
    return StraightBeam(r, e1, st, secs, pms)


def uniform_beam(root, direction, length: float, n_elements: int,
                 section: BeamSection) -> StraightBeam:
    """:func:`straight_beam` with ``n_elements`` equal elements over ``length`` (m).

    Examples
    --------
    >>> sec = BeamSection(1e9, 1e6, 1e7, 1e8, 35.0, 8.0)
    >>> uniform_beam((0, 0), (0, 1), 6.0, 4, sec).stations.tolist()
    [0.0, 1.5, 3.0, 4.5, 6.0]
    """
    n = integer("n_elements", n_elements, low=1)
    return straight_beam(root, direction, np.linspace(0.0, positive("length", length), n + 1),
                         section)


def assemble(beam: StraightBeam) -> tuple[np.ndarray, np.ndarray]:
    """Global stiffness and mass matrices (6 n_nodes square, dense), DOFs (ux, uy, uz, rx, ry,
    rz) per node in the global frame: K = sum T^T K_e T with T = blockdiag(R, R, R, R), R the
    frame's rows (e1, e2, e3); the point masses' 6 x 6 matrices (:meth:`PointMass.matrix`)
    added on their nodes.

    Examples
    --------
    >>> sec = BeamSection(1e9, 1e6, 1e7, 1e8, 35.0, 8.0)
    >>> K, M = assemble(uniform_beam((0, 0), (0, 1), 6.0, 3, sec))
    >>> K.shape, round(float(np.ones(4) @ M[2::6, 2::6] @ np.ones(4)), 9)   # m L in uz
    ((24, 24), 210.0)
    """
    n = beam.n_nodes
    K = np.zeros((NODE_DOF * n, NODE_DOF * n))
    M = np.zeros_like(K)
    T = np.kron(np.eye(4), beam.frame)
    for e, sec in enumerate(beam.sections):
        ke, me = element_matrices(sec, beam.stations[e + 1] - beam.stations[e])
        dofs = np.arange(NODE_DOF * e, NODE_DOF * (e + 2))
        K[np.ix_(dofs, dofs)] += T.T @ ke @ T
        M[np.ix_(dofs, dofs)] += T.T @ me @ T
    for pm in beam.point_masses:
        dofs = np.arange(NODE_DOF * pm.node, NODE_DOF * (pm.node + 1))
        M[np.ix_(dofs, dofs)] += pm.matrix()
    return K, M


@dataclass(frozen=True)
class BeamModes:
    """Normal modes of a beam clamped at its root node.

    Attributes
    ----------
    frequencies_hz : (n_modes,) ascending natural frequencies (Hz).
    shapes : (n_nodes, 6, n_modes) global (ux, uy, uz, rx, ry, rz) per node and unit modal
        coordinate, mass-normalised (phi^T M phi = I); the root node's rows are zero.
    beam : the :class:`StraightBeam` solved.
    """

    frequencies_hz: np.ndarray
    shapes: np.ndarray
    beam: StraightBeam

    @property
    def omega(self) -> np.ndarray:
        """Natural circular frequencies (rad/s)."""
        return 2 * math.pi * self.frequencies_hz

    def modal_matrices(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(M, K, C) of the modal model: I, diag(omega^2), 0 (no rigid mode)."""
        n = self.frequencies_hz.size
        return np.eye(n), np.diag(self.omega ** 2), np.zeros((n, n))


def out_of_plane_dofs(n_nodes: int) -> np.ndarray:
    """The out-of-plane DOFs (uz, rx, ry: 2, 3, 4 of each node's six) of nodes 1..n-1.

    For a beam in the (x, y) plane whose mass offsets lie in that plane these are decoupled
    from the in-plane ones (ux, uy, rz): K and M have no entry between the two sets (the
    element matrices are rotated about z only, Eq. 6.26 of Przemieniecki 1968), so fixing the
    in-plane motion (Nastran: PS 126 on a grid whose CD z is the plane's normal) leaves the
    out-of-plane modes unchanged.

    Examples
    --------
    >>> out_of_plane_dofs(3).tolist()
    [8, 9, 10, 14, 15, 16]
    """
    nodes = np.arange(1, int(n_nodes))
    return (NODE_DOF * nodes[:, None] + np.array([2, 3, 4])[None, :]).ravel()


def beam_modes(beam: StraightBeam, n_modes: int = 6, in_plane_fixed: bool = False) -> BeamModes:
    """The lowest ``n_modes`` natural modes of ``beam`` clamped at its root node (all six
    degrees of freedom fixed), K phi = omega^2 M phi solved densely (``scipy.linalg.eigh``).
    With ``in_plane_fixed`` only the out-of-plane DOFs (:func:`out_of_plane_dofs`) are free:
    the in-plane motion of every node is fixed (``ea`` and ``ei_chord`` may then be 0).

    Each mode's sign is fixed (its largest-magnitude entry positive), so the shapes are
    reproducible.

    Parameters
    ----------
    beam : :class:`StraightBeam`.
    n_modes : number of modes, 1 <= n_modes <= 6 (n_nodes - 1) (3 (n_nodes - 1) with
        ``in_plane_fixed``).
    in_plane_fixed : bool, fix ux, uy, rz of every node (default False).

    Returns
    -------
    :class:`BeamModes`.

    Examples
    --------
    >>> sec = BeamSection(1e9, 1e6, 1e4, 1e9, 1.0, 1.0)
    >>> f = beam_modes(uniform_beam((0, 0), (0, 1), 1.0, 20, sec), 1).frequencies_hz[0]
    >>> round(float(f) * 2 * math.pi / (1.8751041 ** 2 * math.sqrt(1e4)), 6)   # Euler-Bernoulli
    1.0
    """
    if in_plane_fixed:
        free = out_of_plane_dofs(beam.n_nodes)
    else:
        free = np.arange(NODE_DOF, NODE_DOF * beam.n_nodes)
        if any(s.ea == 0 or s.ei_chord == 0 for s in beam.sections):
            raise ValueError("a section with ea = 0 or ei_chord = 0 leaves the in-plane motion "
                             "without stiffness: solve with in_plane_fixed=True")
    n_free = free.size
    n_modes = integer("n_modes", n_modes, low=1, high=n_free)
    K, M = assemble(beam)
    K, M = K[np.ix_(free, free)], M[np.ix_(free, free)]
    # M phi = mu K phi, mu = 1 / omega^2: the lowest modes are the largest mu, accurate to
    # rounding relative to mu_max however stiff the axial and in-plane terms (EA, EI_chord)
    # make K; K phi = omega^2 M phi directly loses them to ||K|| ||M^-1|| on fine meshes.
    mu, phi = sla.eigh(M, K, subset_by_index=[n_free - n_modes, n_free - 1])
    w2 = 1.0 / mu[::-1]
    phi = phi[:, ::-1] / np.sqrt(mu[::-1])[None, :]       # mass-normalised: phi^T M phi = I
    full = np.zeros((NODE_DOF * beam.n_nodes, n_modes))
    full[free] = phi
    shapes = full.reshape(beam.n_nodes, NODE_DOF, n_modes)
    for j in range(n_modes):
        flat = shapes[:, :, j].ravel()
        i = int(np.argmax(np.abs(flat)))
        if flat[i] < 0:
            shapes[:, :, j] *= -1.0
    f = np.sqrt(np.clip(w2, 0.0, None)) / (2 * math.pi)
    return BeamModes(f, shapes, beam)
