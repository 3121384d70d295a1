"""The aeroservoelastic loop with the servo-actuator on a control surface's hinge (issue 25):
thesis Ch. 5's AEM1/AEM2 loops (:mod:`asekit.ase.loop`) with the actuated degree of freedom the
hinge rotation delta of a flap, aileron or tab instead of an all-movable fin's shaft.

Model. The wing's modal model with one hinge coordinate per surface
(:func:`asekit.aeroelastic.control_surface.flap_modal_model`: M, K, C with the surfaces' rigid
rotations U_f appended to the wing's modes, Rodden & Johnson 1994 Sec. 3.5) is reordered so the
actuated surface's hinge coordinate comes first and is declared the one "rigid" (prescribed)
coordinate of thesis Eq. (2.63): the actuator's transmission output theta *is* delta (a stiff
linkage), so the hinge spring k_h of that surface is removed (the motor through the gear
replaces it, K[0, 0] = 0), its hinge damper c_h stays (bearing friction, part of the hinge
moment). The wing's elastic modes and the other surfaces (free on their own springs) are the
elastic coordinates. The GAFs of the same ordered modes (the wing's and the deflections' box
modes, :func:`reorder_modes`) are fitted by the case's RFA, and
:func:`asekit.ase.loop.build_model` joins actuator and aeroelastic model through the hinge
moment (Eqs. 2.68-2.71), the algebraic loop removed exactly as for the fin: the actuator's load
inertia is the surface's effective inertia

    J_eff = M_bar_dd - M_bar_dw M_bar_ww^-1 M_bar_wd,   M_bar = M - rho b^2 / 2 A2,

which for a locked wing and no air is the surface's inertia about its hinge I_h.

Topologies (thesis Section 5.1, Figs 60-61, transposed to the surface): ``"AEM1"`` feeds back
the transmission angle (the motor encoder: here the hinge angle delta itself); ``"AEM2"`` feeds
back the surface's angle about its hinge axis in the air (a sensor on the surface), delta plus
the wing's own rotation about the hinge axis at the hinge line's mid-span point,

    theta_s = delta + sum_j (theta_x,j s_x + theta_y,j s_y) zeta_j,

(s the hinge's unit axis; theta_x, theta_y the wing mode's rotations, the sense of
:func:`asekit.aeroelastic.control_surface.flap_rotation_vector`). For a locked wing the two
topologies are the same loop. The output carrying theta_s keeps :mod:`asekit.ase.loop`'s name
``fin_root_pitch`` so every function of that module (closed loop, OPLOOP/FWTF, crossovers,
simulations) applies unchanged.

All quantities SI (rad, rad/s, N m, kg m^2).
"""

from __future__ import annotations

import math

import numpy as np

from asekit.aeroelastic.statespace import ModalArrays
from asekit.ase.loop import FIN_ROOT, AeroservoelasticModel, build_model
from asekit.util.validate import integer


def actuated_order(n_wing: int, n_surfaces: int, surface: int) -> np.ndarray:
    """The mode order that puts the actuated surface's hinge coordinate first: ``[n_wing +
    surface, 0 .. n_wing - 1, the other surfaces]`` (indices into the flap modal model's
    coordinates, wing modes then one per surface).

    Examples
    --------
    >>> actuated_order(3, 2, 1).tolist()
    [4, 0, 1, 2, 3]
    """
    n_wing = integer("n_wing", n_wing, low=0)
    n_surfaces = integer("n_surfaces", n_surfaces, low=1)
    surface = integer("surface", surface, low=0, high=n_surfaces - 1)
    others = [n_wing + i for i in range(n_surfaces) if i != surface]
    return np.array([n_wing + surface] + list(range(n_wing)) + others, dtype=int)


def reorder_modes(a: np.ndarray, order) -> np.ndarray:
    """``a[..., order][..., order, :]`` on the last two axes: a (n, n) matrix or a (n_k, n, n)
    stack of GAFs in the new mode ``order``.

    Examples
    --------
    >>> reorder_modes(np.arange(4.0).reshape(2, 2), [1, 0]).tolist()
    [[3.0, 2.0], [1.0, 0.0]]
    """
    o = np.asarray(order, dtype=int)
    a = np.asarray(a)
    if a.shape[-1] != o.size or a.shape[-2] != o.size:
        raise ValueError(f"the matrix is {a.shape[-2:]}, the order has {o.size} modes")
    return a[..., o, :][..., :, o]


def hinge_actuated_modal(fm, surface: int) -> tuple[ModalArrays, np.ndarray]:
    """The flap modal model with surface ``surface``'s hinge coordinate first as the one
    prescribed (actuator) coordinate, its hinge spring removed (module docstring).

    Parameters
    ----------
    fm : :class:`asekit.aeroelastic.control_surface.FlapModel` of a wing without rigid modes
        (a clamped or otherwise fixed wing: ``fm.modal.n_rigid == 0``).
    surface : index of the actuated surface, in [0, number of surfaces - 1].

    Returns
    -------
    (ModalArrays with n_rigid = 1, order) : the reordered M, K, C and the order
        (:func:`actuated_order`) to apply to the GAFs and output rows.

    Examples
    --------
    >>> from asekit.aero.boxes import TrapezoidSurface
    >>> from asekit.aero.control_surface import ControlSurface, hinged_mesh
    >>> from asekit.aeroelastic.control_surface import flap_modal_model
    >>> from asekit.geometry import Material, Planform, Thickness
    >>> from asekit.structure.assembly import assemble, clamped_edge
    >>> from asekit.structure.mesh import panels_mesh
    >>> from asekit.structure.modes import fixed_modal_model
    >>> pm = panels_mesh([Planform((0, 0), 0.3, (0, 1.2), 0.3)], Thickness(0.002, 0.002), 8, [16])
    >>> K, M = assemble(pm, Material(70e9, 0.3, 2700.0))
    >>> model = fixed_modal_model(clamped_edge(pm, K, M), M, n_modes=2)
    >>> hm = hinged_mesh(TrapezoidSurface((0, 0), 0.3, (0, 1.2), 0.3, 8, 16),
    ...                  ControlSurface("aileron", 0.75, 0.75, 0.5, 1.0))
    >>> m, order = hinge_actuated_modal(flap_modal_model(model, M, hm, 0.5), 0)
    >>> order.tolist(), m.n_rigid, float(m.K[0, 0]), round(1e3 * float(m.M[0, 0]), 3)
    ([2, 0, 1], 1, 0.0, 0.475)
    """
    n_rigid = int(fm.modal.n_rigid)
    if n_rigid != 0:
        raise ValueError(f"the actuator on a control surface needs a wing without rigid modes "
                         f"(n_rigid = 0; a clamped wing), got n_rigid = {n_rigid}")
    order = actuated_order(fm.n_wing, len(fm.names), surface)
    M, K, C = (reorder_modes(np.asarray(x, float), order) for x in (fm.modal.M, fm.modal.K,
                                                                      fm.modal.C))
    K = K.copy()
    K[0, :] = 0.0              # the actuator replaces the hinge spring (K is block diagonal)
    K[:, 0] = 0.0
    return ModalArrays(M, K, C, 1), order


def surface_angle_row(wing_model, hm, surface: int, order) -> np.ndarray:
    """Output row (n_modes,) of the actuated surface's angle about its hinge axis in the air,
    theta_s = delta + sum_j (theta_x,j s_x + theta_y,j s_y) zeta_j (module docstring), in the
    mode ``order`` of :func:`hinge_actuated_modal`. The wing's rotation is read at the
    finite-element node nearest to the hinge line's mid-span point.

    Parameters
    ----------
    wing_model : the wing's :class:`asekit.structure.modes.ModalModel` (``nodes`` (n, 2) m,
        ``shapes`` with (w, theta_x, theta_y) per node).
    hm : :class:`asekit.aero.control_surface.HingedMesh` of the surfaces.
    surface : the actuated surface's index.
    order : the mode order of :func:`hinge_actuated_modal`.

    Returns
    -------
    (n_modes,) row: 1 for the hinge (first), the wing modes' rotations about the hinge axis.

    Examples
    --------
    The clamped plate wing of :func:`hinge_actuated_modal`: its first bending mode barely
    rotates the aileron about its (spanwise) hinge, its first torsion mode does.

    >>> from asekit.aero.boxes import TrapezoidSurface
    >>> from asekit.aero.control_surface import ControlSurface, hinged_mesh
    >>> from asekit.geometry import Material, Planform, Thickness
    >>> from asekit.structure.assembly import assemble, clamped_edge
    >>> from asekit.structure.mesh import panels_mesh
    >>> from asekit.structure.modes import fixed_modal_model
    >>> pm = panels_mesh([Planform((0, 0), 0.3, (0, 1.2), 0.3)], Thickness(0.002, 0.002), 8, [16])
    >>> K, M = assemble(pm, Material(70e9, 0.3, 2700.0))
    >>> model = fixed_modal_model(clamped_edge(pm, K, M), M, n_modes=3)
    >>> hm = hinged_mesh(TrapezoidSurface((0, 0), 0.3, (0, 1.2), 0.3, 8, 16),
    ...                  ControlSurface("aileron", 0.75, 0.75, 0.5, 1.0))
    >>> row = surface_angle_row(model, hm, 0, actuated_order(3, 1, 0))
    >>> float(row[0]), bool(abs(row[1]) < 0.1 * max(abs(row[2:])))
    (1.0, True)
    """
    from asekit.aeroelastic.control_surface import _hinge_length

    nodes = np.asarray(wing_model.nodes, float)
    phi = np.asarray(wing_model.shapes, float).reshape(3 * len(nodes), -1)
    n_wing = phi.shape[1]
    s = np.asarray(hm.hinge_axis[surface], float)
    s = s / math.hypot(s[0], s[1])
    mid = hm.hinge_point[surface] + 0.5 * _hinge_length(hm, surface) * hm.hinge_axis[surface]
    j = int(np.argmin(np.hypot(nodes[:, 0] - mid[0], nodes[:, 1] - mid[1])))
    row = np.zeros(len(order))
    row[:n_wing] = s[0] * phi[3 * j + 1] + s[1] * phi[3 * j + 2]
    row[n_wing + surface] = 1.0
    return reorder_modes(np.diag(row), order).diagonal().copy()


def flap_ase_model(modal: ModalArrays, rfa, density: float, velocity: float,
                   surface_row: np.ndarray, actuator=None, mach: float | None = None,
                   point_outputs: dict | None = None) -> AeroservoelasticModel:
    """The actuator on the hinge and the aeroelastic wing at (density, velocity): the model of
    :func:`asekit.ase.loop.build_model` with the hinge as the actuated coordinate.

    Parameters
    ----------
    modal : the reordered model of :func:`hinge_actuated_modal`.
    rfa : rational fit (:class:`asekit.rfa.RogerFit` or minimum state) of the GAFs in the
        same mode order (:func:`reorder_modes` on the GAF stack before fitting).
    density : air density (kg/m^3), > 0. velocity : airspeed (m/s), > 0.
    surface_row : (n_modes,) the surface angle's row (:func:`surface_angle_row`), carried as
        the ``fin_root_pitch`` output (the AEM2 feedback).
    actuator : :class:`asekit.servo.actuator.ActuatorParameters` (default the thesis's); its
        load inertia becomes the surface's effective inertia J_eff.
    mach : the RFA's Mach number (informational).
    point_outputs : further ``{name: row}`` outputs.

    Returns
    -------
    AeroservoelasticModel
        ``effective_fin_inertia`` is the surface's J_eff (kg m^2).

    Examples
    --------
    A surface of 0.5 g m^2 about its hinge on a locked wing, the air off (a zero fit): the
    actuator's load inertia is that of the surface.

    >>> from asekit.rfa.roger import roger_fit
    >>> modal = ModalArrays(np.array([[5e-4]]), np.zeros((1, 1)), np.zeros((1, 1)), 1)
    >>> rfa = roger_fit(np.array([0.0, 0.5, 1.0]), np.zeros((3, 1, 1), complex), 0.15, n_lags=1)
    >>> m = flap_ase_model(modal, rfa, 1.225, 20.0, np.array([1.0]))
    >>> round(m.effective_fin_inertia, 6), m.actuator.fin_inertia == m.effective_fin_inertia
    (0.0005, True)
    """
    row = np.asarray(surface_row, float).ravel()
    if row.size != modal.n_modes or abs(row[0] - 1.0) > 1e-12:
        raise ValueError(f"surface_row must have {modal.n_modes} entries with 1 for the hinge "
                         f"(first), got {row.size} entries")
    outputs = {FIN_ROOT: row}
    outputs.update(point_outputs or {})
    return build_model(modal, rfa, density, velocity, outputs, actuator=actuator, mach=mach)
