"""The ASE loop's gain and phase margins and their design derivatives for a case (issue 28).

The chain of :mod:`asekit.case.design` (plate matrices and their derivatives, the elastic modes
of the shaft-supported fin with the transmission held, FN1, and Nelson's mode-shape derivatives)
is extended by the rigid pitch mode r (unit nose-up rotation about the shaft, the FN2 model's
first mode, independent of thickness, material and masses) to the modal basis [r, Phi] of the
aeroservoelastic model:

    M_a = [r, Phi]^T M [r, Phi],   K_a = diag(0, Lambda),                                  (1)

(the rigid rotation strains neither plate nor shaft spring; the elastic modes are
mass-normalised, Phi^T M Phi = I). Its derivatives follow from Nelson's dPhi, dLambda
(:func:`asekit.aeroelastic.sensitivity.modal_matrix_derivative`, dr = 0), the GAF derivatives
dQ from the extended mode table [r, Phi, 0, dPhi_j] through the case's boxes and the DLM
operators at the actuator's Mach (:func:`asekit.aeroelastic.sensitivity.gaf_derivative`), the
Roger coefficients' derivatives dA_j = fit(dQ) (:func:`asekit.rfa.roger.roger_fit_derivative`)
and the AEM1 loop's dF and margins (:mod:`asekit.ase.loop_sensitivity`).

This modal basis is the "held-transmission elastic modes + rigid attachment mode" form of the
thesis's Eq. (2.60); the case pipeline's FN2 model (fictitious-mass method) gives elastic modes
that differ from these by O(J_fin / I_f) (:mod:`asekit.case.design`), so the margins here agree
with :func:`asekit.case.pipeline.ase`'s to that order, not to round-off. Undamped structures
(no ``[damping]``), shaft supports with a rigid mode (FN2, ``modes.keep_rigid``), Roger fits.
"""

from __future__ import annotations

import types
import warnings
from dataclasses import dataclass

import numpy as np

from asekit.aero.methods import AERO_METHODS, resolve_method
from asekit.aeroelastic.sensitivity import extended_shapes, gaf_derivative, modal_matrix_derivative
from asekit.ase.loop_sensitivity import aem1_margin_sensitivity
from asekit.atmosphere import standard_atmosphere
from asekit.case import design as D
from asekit.case import pipeline as P
from asekit.case.schema import Case, CaseError
from asekit.rfa.roger import roger_fit, roger_fit_derivative
from asekit.structure.sensitivity import element_parts, mode_shape_derivatives, reduce

__all__ = ["AseMargins", "ase_margins"]


@dataclass(frozen=True)
class AseMargins:
    """The AEM1 loop's margins at a design and their derivatives per design variable.

    Attributes
    ----------
    paths : the design variables' case-key paths.
    values : (n_var,) their values.
    phase_margin_deg : the smallest phase margin (deg); d_phase_margin_deg : (n_var,) its
        derivative (deg per unit of each variable).
    gain_crossover_hz : where it is read (Hz).
    gain_margin_db : gain margin at the first phase crossover (dB; inf without one);
        d_gain_margin_db : (n_var,) its derivative (zero without one).
    sensitivity : the full :class:`asekit.ase.margin_sensitivity.MarginSensitivity`.
    """

    paths: tuple
    values: np.ndarray
    phase_margin_deg: float
    d_phase_margin_deg: np.ndarray
    gain_crossover_hz: float
    gain_margin_db: float
    d_gain_margin_db: np.ndarray
    sensitivity: object


def _modal(case: Case, paths, n_elastic: int, rigid: np.ndarray):
    """M_a, K_a (Eq. 1), their derivatives, and the mode tables [r, Phi] and derivatives."""
    mesh = P.structural_mesh(case)
    K, M = P.mass_and_stiffness(case)
    parts = element_parts(mesh, case.material)
    ev = types.SimpleNamespace(paths=tuple(paths))
    dK, dM, _, _ = D._matrix_derivatives(ev, case, mesh, parts, K, M)
    system = D._system(case, mesh, K, M)
    lam, q = D._elastic_modes(system, M, n_elastic)
    dKr = [reduce(system.T, a) for a in dK]
    for j, path in enumerate(paths):
        extra = D._support_derivative(system, path)
        if extra is not None:
            dKr[j] = dKr[j] + extra
    dlam, dq = mode_shape_derivatives(system.K, system.M, lam, q, dKr,
                                      [reduce(system.T, a) for a in dM])
    n = lam.size
    shapes = np.concatenate([rigid[:, :, None], (system.T @ q).reshape(mesh.n_nodes, 3, n)], 2)
    dshapes = np.array([np.concatenate([np.zeros_like(rigid)[:, :, None],
                                        (system.T @ d).reshape(mesh.n_nodes, 3, n)], 2)
                        for d in dq])
    Phi = shapes.reshape(-1, n + 1)
    dPhi = dshapes.reshape(len(dq), -1, n + 1)
    Ma = Phi.T @ (M @ Phi)
    dMa = modal_matrix_derivative(Phi, M, dPhi, dM)
    Ka = np.zeros((n + 1, n + 1))
    Ka[1:, 1:] = np.diag(lam)
    dKa = np.zeros((len(dq), n + 1, n + 1))
    for j, d in enumerate(dlam):
        dKa[j, 1:, 1:] = np.diag(d)
    return mesh, Ma, Ka, dMa, dKa, shapes, dshapes


def _operators(case: Case, mach: float):
    a = case.aero
    spec = AERO_METHODS[resolve_method(a.method, mach)]
    if spec.operators is None or not spec.structure_independent:
        raise CaseError(f"aero.method = {a.method!r} at M {mach:g}: the margin derivatives "
                        "need a structure-independent aerodynamic operator (dlm, supersonic, "
                        "piston)")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return spec.operators(P.box_mesh(case), mach, P.reduced_frequencies(case),
                              a.reference_semichord, a.symmetry == "wall",
                              a.kernel if a.method == "dlm" else "quartic")


def ase_margins(case: Case, paths, values=None, operators=None) -> AseMargins:
    """AEM1 gain and phase margins of ``case`` (at ``[actuator.condition]``) with the design
    variables ``paths`` set to ``values``, and their analytic derivatives (module docstring).

    Parameters
    ----------
    case : Case
        A case with ``[actuator]``, a shaft support with a rigid mode (FN2, ``modes.keep_rigid``)
        and no ``[damping]``.
    paths : sequence of str
        Design-variable case-key paths (those of :mod:`asekit.case.design`).
    values : sequence of float, optional
        Their values (default: the case's).
    operators : optional
        The aerodynamic operators at the actuator's Mach (formed once and reused across calls:
        the boxes do not change with the design); default: formed here.

    Returns
    -------
    :class:`AseMargins`.

    Raises
    ------
    CaseError
        No ``[actuator]``, no rigid mode, damping, or a structure-dependent aero method.
    """
    if case.actuator is None:
        raise CaseError("the case has no [actuator]: no ASE loop to differentiate")
    if case.damping is not None and (case.damping.modal_damping_ratio or case.damping.structural_g):
        raise CaseError("[damping]: the margin derivatives need an undamped structure")
    base = P.modal_model(case)
    if base.n_rigid != 1:
        raise CaseError("support.model / modes.keep_rigid: the ASE loop needs the rigid pitch "
                        "mode (FN2 with modes.keep_rigid = true)")
    paths = tuple(paths)
    if values is not None:
        case = D.with_values(case, paths, values)
    values = np.array([D.case_value(case, p) for p in paths])
    act, ctl, _ = P.actuator_setup(case)
    a = case.actuator
    ops = _operators(case, a.mach) if operators is None else operators
    n_el = base.frequencies_hz.size - 1
    rigid = np.asarray(base.shapes)[:, :, 0]        # unit pitch about the shaft, (n_nodes, 3)
    mesh, Ma, Ka, dMa, dKa, shapes, dshapes = _modal(case, paths, n_el, rigid)
    n = n_el + 1
    Q = D._gafs(types.SimpleNamespace(case=case, operators=ops), mesh,
                extended_shapes(shapes, dshapes))
    dQ = gaf_derivative(Q, n)
    k, b = P.reduced_frequencies(case), case.aero.reference_semichord
    fit = roger_fit(k, Q[:, :n, :n], b, n_lags=case.flutter.lags, mach=a.mach)
    dA = [roger_fit_derivative(fit, d) for d in dQ]
    atm = standard_atmosphere(a.altitude)
    rho, U = float(atm.density), a.mach * float(atm.speed_of_sound)
    s = aem1_margin_sensitivity(Ma, Ka, np.zeros_like(Ma), fit, rho, U, act, ctl,
                                dM=list(dMa), dK=list(dKa), dA=dA)
    i = int(np.argmin(s.phase_margins_deg)) if s.phase_margins_deg.size else None
    pm = float(s.phase_margins_deg[i]) if i is not None else float("inf")
    dpm = s.d_phase_margins_deg[:, i] if i is not None else np.zeros(len(paths))
    wc = float(s.gain_crossovers_rad_s[i]) / (2 * np.pi) if i is not None else float("nan")
    gm = float(s.gain_margins_db[0]) if s.gain_margins_db.size else float("inf")
    dgm = s.d_gain_margins_db[:, 0] if s.gain_margins_db.size else np.zeros(len(paths))
    return AseMargins(paths, values, pm, np.asarray(dpm), wc, gm, np.asarray(dgm), s)
