"""Design optimisation of a case with analytic sensitivities (issue 28): the lightest surface
that keeps its flutter margin over the case's envelope.

A design file (TOML, docs/design-format.md) names the variables by case-key path with bounds,
the objective and the flutter-margin constraint::

    [design]
    objective = "mass"            # minimise the structural mass (plate + point masses)
    flutter_margin = 0.15         # U_f >= (1 + 0.15) U_envelope at every envelope altitude
    max_iterations = 40

    [[design.variable]]
    path = "thickness.root"       # m
    lower = 0.002
    upper = 0.008

The constraint is the case's own margin (:func:`asekit.case.pipeline.flutter`'s ``margins``):
at every analysed altitude inside ``flight.envelope.altitude``, the flutter speed at the
envelope's top Mach (one of ``aero.machs``), U_f / (M a) - 1 >= ``flutter_margin``.

Each evaluation runs the chain of the physics layer with its derivatives:
plate matrices and their thickness / point-mass derivatives
(:mod:`asekit.structure.sensitivity`), the elastic modes of the shaft-supported plate (FN1: the
elastic modes of the case's FN2 model to O(J_fin / I_f)) and Nelson's mode-shape derivatives,
the GAFs of the extended mode set through the case's factored aerodynamic operators (formed
once), the p-k flutter point and dU_f (:mod:`asekit.aeroelastic.sensitivity`). The optimiser is
:func:`scipy.optimize.minimize` (SLSQP) with these gradients, on variables scaled by their
baseline values.

Supported variables: ``thickness.root``, ``thickness.tip`` (flat chordwise profile),
``material.youngs_modulus`` (Pa; isotropic, nu fixed, so dK/dE = K / E),
``material.density`` (kg/m^3; dM/drho = M_plate / rho, d(mass)/drho = plate mass / rho),
for an orthotropic material ``material.e1``, ``e2``, ``g12``, ``g13``, ``g23`` (Pa) and
``material.fibre_angle_deg`` (deg): K is linear in the constitutive matrices Q and G, so dK is
the stiffness assembled with dQ, dG (:func:`asekit.structure.sensitivity.\
orthotropic_derivative`; nu12 held fixed; a written g12 keeps g13 and g23 where they were),
``support.torsional_stiffness`` and ``support.bending_stiffness`` (N m/rad; a shaft support,
the latter only where the case has the bending spring: each adds k e e^T to the supported
system's stiffness on the shaft's pitch / bending coordinate, so dK_r = e e^T there, no mass),
``point_mass[i].mass`` (kg), ``point_mass[i].position[0]`` and ``point_mass[i].position[1]``
(its x, chordwise, and y, spanwise, m: dM/dx = m (N_x N^T + N N_x^T) through the shape
functions of the element holding it, :func:`asekit.structure.sensitivity.\
point_mass_position_derivative`; exact inside an element, one-sided where the mass crosses an
element edge, as the bilinear N is only C0 there) and, for a tabulated thickness field (``[thickness] kind = "table"``),
``thickness.values_m[i][j]`` (one table value) or ``thickness.values_m`` (the whole table,
expanded to one variable per value, all with the given bounds). A table value enters the
element matrices through the bilinear weights: dh_g / dvalues[i][j] = H_i(eta_g) H_j(xi_g) at
every integration point g (:meth:`asekit.geometry.ThicknessTable.weights`), then the exact
thickness derivatives of :mod:`asekit.structure.sensitivity`. ``design.table_max_step_m``
bounds the difference of adjacent table values (a linear smoothness constraint,
|v[i][j] - v[i+1][j]| and |v[i][j] - v[i][j+1]| <= the step, m) for manufacturability. Supported structures: a ``shaft`` support (FN1 or FN2) or
``clamped_root``, undamped (no ``[damping]``). ``design.divergence_margin`` adds the divergence
of the elastic modes at the top Mach as a constraint, U_D >= (1 + margin) M a per envelope
altitude, written 1 - q_a mu >= 0 with mu = 1 / q_D and its analytic derivative
(:func:`asekit.aeroelastic.sensitivity.divergence_sensitivity`). ``design.frequency_separation``
(with ``design.frequency_separation_modes`` = n, default 2) asks f_{i+1} / f_i - 1 >= the value
for the first n elastic modes (:func:`separation_constraint`, Fox-Kapoor eigenvalue
derivatives). ``design.phase_margin_deg`` and ``design.gain_margin_db`` (deg, dB; > 0) bound
the AEM1 loop's smallest phase margin and its gain margin at ``[actuator.condition]`` from
below (:func:`ase_margin_constraints`; the margins and their gradients of
:func:`ase_margins`, on the aerodynamic operators at the actuator's
Mach, formed once); they need ``[actuator]`` and a shaft support with ``modes.keep_rigid``.
The servo requirements of Table 2 are not constraints yet.
"""

from __future__ import annotations

import dataclasses
import math
import time
import types
import warnings
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from asekit.aero.gaf import TabulatedGaf
from asekit.aero.methods import AERO_METHODS, resolve_method
from asekit.aero.spline import fe_spline, modal_forces
from asekit.aeroelastic.flutter import pk_flutter, pk_instabilities
from asekit.aeroelastic.sensitivity import (
    divergence_sensitivity,
    extended_shapes,
    flutter_point,
    flutter_speed_sensitivity,
    gaf_derivative,
    modal_matrix_derivative,
)
from asekit.aeroelastic.statespace import modal_arrays
from asekit.ase.loop_sensitivity import aem1_margin_sensitivity
from asekit.atmosphere import standard_atmosphere
from asekit.case import pipeline as P
from asekit.case.schema import Case, CaseError
from asekit.rfa.roger import roger_fit, roger_fit_derivative
from asekit.structure.assembly import clamped_edge, rigid_pitch_vector, shaft_support
from asekit.structure.modes import ModalModel, normal_modes, select_modes
from asekit.structure.sensitivity import (
    density_derivative,
    element_parts,
    mode_shape_derivatives,
    orthotropic_stiffness_derivative,
    point_mass_derivative,
    point_mass_position_derivative,
    reduce,
    scatter,
    thickness_derivatives,
    youngs_modulus_derivative,
)
from asekit.util.validate import read_toml

OBJECTIVES = ("mass", "flutter_speed")
#: A constraint counts as active at the optimum where its normalised row g (the value the
#: optimiser keeps >= 0: e.g. U_f / ((1 + margin)(1 + slack) M a) - 1, or (step - |dv|) / step
#: for the smoothness of a thickness table) is at most this.
ACTIVE_TOL = 1e-3
#: The optimiser asks for U_f >= (1 + margin) M a (1 + CONSTRAINT_SLACK): the re-analysis by the
#: case pipeline (FN2 modes, its own GAF database) differs from the optimiser's chain (FN1 modes,
#: the same boxes) by ~1e-7 relative, and SLSQP meets an active constraint only to its tolerance.
CONSTRAINT_SLACK = 1e-4
#: The p-k sweep that locates the first crossing uses at most this many of the case's velocities
#: (evenly strided, the last one kept; the solver's step control inserts sub-steps where roots
#: move fast); the crossing is then converged by Newton's method to 1e-12 relative. A root that
#: crosses and re-crosses between two of these points is missed by the optimiser but not by the
#: re-analysis of ``asekit optimise``, which runs the case's own sweep.
SWEEP_POINTS = 40
_THICKNESS = ("thickness.root", "thickness.tip")
#: isotropic material keys: dK/dE = K / E (nu fixed), dM/drho = M_plate / rho
_MATERIAL = ("material.youngs_modulus", "material.density")
#: orthotropic material keys (Pa; the fibre angle in degrees as in the case file): dK from the
#: derivatives of the constitutive matrices (:func:`asekit.structure.sensitivity.\
#: orthotropic_stiffness_derivative`); ``material.density`` serves both kinds
_ORTHO = ("material.e1", "material.e2", "material.g12", "material.g13", "material.g23",
          "material.fibre_angle_deg")
#: shaft springs: they enter only the supported system's K (d K_r = e e^T on the shaft's pitch or
#: bending coordinate)
_SUPPORT = ("support.torsional_stiffness", "support.bending_stiffness")
_TABLE = "thickness.values_m"
_TABLE_ENTRY = r"thickness\.values_m\[(\d+)\]\[(\d+)\]"
_POINT_MASS = r"point_mass\[(\d+)\]\.(mass|position\[([01])\])"


class DesignError(ValueError):
    """A design file or design problem the optimiser refuses (the message names the key)."""


@dataclass(frozen=True)
class DesignVariable:
    """A case key varied by the optimiser: ``path`` (e.g. ``thickness.root``), ``lower`` and
    ``upper`` bounds in the key's unit."""

    path: str
    lower: float
    upper: float


@dataclass(frozen=True)
class DesignProblem:
    """A parsed design file: ``variables``, ``objective`` ("mass"), ``flutter_margin`` (a
    fraction), ``max_iterations``, ``source`` (the file), ``table_max_step_m`` (m, the largest
    difference of adjacent thickness-table values, None: unconstrained), ``gradient_step``
    (the central differences' relative step of the gradient check), ``divergence_margin`` (a
    fraction: U_D >= (1 + margin) M a at every envelope altitude; None: divergence is reported,
    not constrained), ``frequency_separation`` (a fraction: f_{i+1} / f_i - 1 >= it for the
    first ``frequency_separation_modes`` elastic modes; None: not constrained)."""

    variables: tuple[DesignVariable, ...]
    objective: str = "mass"
    flutter_margin: float = 0.15
    max_iterations: int = 40
    source: str = ""
    table_max_step_m: float | None = None
    gradient_step: float = 1e-4
    divergence_margin: float | None = None
    frequency_separation: float | None = None
    frequency_separation_modes: int = 2
    # issue 28, ASE margins (:func:`ase_margins`): the AEM1 loop's smallest phase margin
    # (deg) and its gain margin (dB) at [actuator.condition] must be >= these; None: not
    # constrained
    phase_margin_deg: float | None = None
    gain_margin_db: float | None = None


def _number(d: dict, key: str, where: str, low=-math.inf, high=math.inf, default=None):
    v = d.get(key, default)
    if v is None:
        raise DesignError(f"{where}.{key} is required")
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
            or not low <= v <= high:
        raise DesignError(f"{where}.{key} must be a number in [{low:g}, {high:g}], got {v!r}")
    return float(v)


def _variable_path(path, where: str) -> str:
    import re
    if isinstance(path, str) and (path in _THICKNESS or path == _TABLE or path in _MATERIAL
                                  or path in _SUPPORT or path in _ORTHO
                                  or re.fullmatch(_TABLE_ENTRY, path)
                                  or re.fullmatch(_POINT_MASS, path)):
        return path
    raise DesignError(f"{where}.path must be one of "
                      f"{list(_THICKNESS + _MATERIAL + _ORTHO + _SUPPORT)}, "
                      f"{_TABLE}, {_TABLE}[i][j], point_mass[i].mass or "
                      f"point_mass[i].position[k] (k = 0: x, 1: y), got {path!r}")


def design_from_dict(d: dict, source: str = "") -> DesignProblem:
    """The :class:`DesignProblem` of a design file's dict; DesignError naming the key.

    Examples
    --------
    >>> p = design_from_dict({"design": {"variable": [{"path": "thickness.tip",
    ...                                                "lower": 0.001, "upper": 0.004}]}})
    >>> p.variables[0].path, p.flutter_margin
    ('thickness.tip', 0.15)
    """
    if not isinstance(d, dict) or not isinstance(d.get("design"), dict):
        raise DesignError("a design file needs a [design] table")
    t = d["design"]
    unknown = set(t) - {"objective", "flutter_margin", "max_iterations", "variable",
                        "table_max_step_m", "gradient_step", "divergence_margin",
                        "frequency_separation", "frequency_separation_modes",
                        "phase_margin_deg", "gain_margin_db"}
    if unknown:
        raise DesignError(f"design: unknown keys {sorted(unknown)} (known: divergence_margin, "
                          f"objective, flutter_margin, frequency_separation, "
                          f"frequency_separation_modes, gain_margin_db, gradient_step, "
                          f"max_iterations, phase_margin_deg, table_max_step_m, variable)")
    objective = t.get("objective", "mass")
    if objective not in OBJECTIVES:
        raise DesignError(f"design.objective must be one of {list(OBJECTIVES)}, got {objective!r}")
    raw = t.get("variable")
    if not isinstance(raw, list) or not raw:
        raise DesignError("design.variable must hold at least one [[design.variable]] table")
    out, seen = [], set()
    for i, v in enumerate(raw):
        where = f"design.variable[{i}]"
        if not isinstance(v, dict) or set(v) - {"path", "lower", "upper"}:
            raise DesignError(f"{where} must be a table with the keys path, lower, upper")
        path = _variable_path(v.get("path"), where)
        if path in seen:
            raise DesignError(f"{where}.path {path!r} is given twice")
        seen.add(path)
        low = -360.0 if path == "material.fibre_angle_deg" else 0.0      # deg; else >= 0
        lo, hi = _number(v, "lower", where, low), _number(v, "upper", where, low)
        if not lo < hi:
            raise DesignError(f"{where}: lower ({lo:g}) must be below upper ({hi:g})")
        out.append(DesignVariable(path, lo, hi))
    margin = _number(t, "flutter_margin", "design", 0.0, 10.0, 0.15)
    iters = _number(t, "max_iterations", "design", 1, 10000, 40)
    if iters != int(iters):
        raise DesignError(f"design.max_iterations must be an integer, got {iters!r}")
    step = (None if "table_max_step_m" not in t
            else _number(t, "table_max_step_m", "design", 0.0, 100.0))
    gstep = _number(t, "gradient_step", "design", 1e-8, 0.1, 1e-4)
    div = (None if "divergence_margin" not in t
           else _number(t, "divergence_margin", "design", 0.0, 10.0))
    sep, n_sep = _separation(t)
    pm, gm = _ase_bounds(t)
    return DesignProblem(tuple(out), objective, margin, int(iters), source, step, gstep, div,
                         sep, n_sep, pm, gm)


def _ase_bounds(t: dict) -> tuple[float | None, float | None]:
    """``design.phase_margin_deg`` (deg, in (0, 180]) and ``design.gain_margin_db`` (dB, in
    (0, 100]), each absent (None) or a lower bound on the AEM1 loop's margin."""
    out = []
    for key, hi in (("phase_margin_deg", 180.0), ("gain_margin_db", 100.0)):
        v = None if key not in t else _number(t, key, "design", 0.0, hi)
        if v is not None and v <= 0.0:
            raise DesignError(f"design.{key} must be a number in (0, {hi:g}], got {v!r}")
        out.append(v)
    return out[0], out[1]


def _separation(t: dict) -> tuple[float | None, int]:
    """``design.frequency_separation`` (a fraction in [0, 10] or absent) and
    ``design.frequency_separation_modes`` (an integer in [2, 50], default 2)."""
    sep = (None if "frequency_separation" not in t
           else _number(t, "frequency_separation", "design", 0.0, 10.0))
    n = _number(t, "frequency_separation_modes", "design", 2, 50, 2)
    if n != int(n):
        raise DesignError(f"design.frequency_separation_modes must be an integer, got {n!r}")
    if sep is None and "frequency_separation_modes" in t:
        raise DesignError("design.frequency_separation_modes needs design.frequency_separation")
    return sep, int(n)


def table_index(path: str) -> tuple[int, int] | None:
    """(i, j) of a ``thickness.values_m[i][j]`` path, None for any other path."""
    import re
    m = re.fullmatch(_TABLE_ENTRY, path)
    return None if m is None else (int(m.group(1)), int(m.group(2)))


def expand_variables(problem: DesignProblem, case: Case) -> DesignProblem:
    """The problem with a whole-table variable ``thickness.values_m`` replaced by one variable
    per table value (same bounds), row by row; DesignError when the case has no table, a
    value is named twice or lies outside the table.

    Examples
    --------
    >>> from asekit.case import load_case
    >>> from asekit.util.paths import FIN_FILE
    >>> import dataclasses
    >>> from asekit.geometry import ThicknessTable
    >>> t = ThicknessTable((0.0, 1.0), (0.0, 0.5, 1.0), ((4e-3,) * 2, (3e-3,) * 2, (2e-3,) * 2))
    >>> case = dataclasses.replace(load_case(FIN_FILE), thickness=t)
    >>> p = design_from_dict({"design": {"variable": [{"path": "thickness.values_m",
    ...                                                "lower": 0.001, "upper": 0.008}]}})
    >>> [v.path for v in expand_variables(p, case).variables][:3]
    ['thickness.values_m[0][0]', 'thickness.values_m[0][1]', 'thickness.values_m[1][0]']
    """
    table = case.thickness if getattr(case.thickness, "is_table", False) else None
    out = []
    for k, v in enumerate(problem.variables):
        if v.path != _TABLE and table_index(v.path) is None:
            out.append(v)
            continue
        if table is None:
            raise DesignError(f"design.variable[{k}].path {v.path!r} needs a thickness table "
                              f"in the case ([thickness] kind = \"table\")")
        n_eta, n_xc = table.shape
        if v.path == _TABLE:
            out += [DesignVariable(f"{_TABLE}[{i}][{j}]", v.lower, v.upper)
                    for i in range(n_eta) for j in range(n_xc)]
            continue
        i, j = table_index(v.path)
        if i >= n_eta or j >= n_xc:
            raise DesignError(f"design.variable[{k}].path {v.path!r}: the case's table has "
                              f"{n_eta} x {n_xc} values (indices from 0)")
        out.append(v)
    paths = [v.path for v in out]
    twice = sorted({p for p in paths if paths.count(p) > 1})
    if twice:
        raise DesignError(f"design.variable: {twice[0]} is named twice (a whole-table variable "
                          f"and one of its values?)")
    return dataclasses.replace(problem, variables=tuple(out))


def load_design(path) -> DesignProblem:
    """Read and check a design file (TOML); DesignError naming the key."""
    return design_from_dict(read_toml(path, DesignError), str(path))


# ---------------------------------------------------------------------------------------------
# the case's values and the case with new values
# ---------------------------------------------------------------------------------------------
def _point_index(path: str) -> int:
    return int(path[path.index("[") + 1:path.index("]")])


def position_axis(path: str) -> int | None:
    """0 (x) or 1 (y) of a ``point_mass[i].position[k]`` path, None for any other path."""
    import re
    m = re.fullmatch(_POINT_MASS, path)
    return None if m is None or m.group(3) is None else int(m.group(3))


def case_value(case: Case, path: str) -> float:
    """The current value of a design variable's key in ``case``."""
    if path == "thickness.root":
        return float(case.thickness.root)
    if path == "thickness.tip":
        return float(case.thickness.tip)
    if path in _MATERIAL or path in _SUPPORT or path in _ORTHO:
        return _section_value(case, path)
    ij = table_index(path)
    if ij is not None:
        return float(case.thickness.values[ij[0]][ij[1]])
    i = _point_index(path)
    if i >= len(case.point_masses):
        raise DesignError(f"{path}: the case has {len(case.point_masses)} point masses")
    axis = position_axis(path)
    pm = case.point_masses[i]
    return float(pm.mass if axis is None else pm.position[axis])


def _section_value(case: Case, path: str) -> float:
    """A material or support key's value; DesignError where the case has no such number."""
    section, key = path.split(".")
    obj = getattr(case, section)
    v = getattr(obj, key, None)
    iso = hasattr(obj, "youngs_modulus")
    if path == "material.youngs_modulus" and not iso:
        raise DesignError(f"{path}: needs an isotropic material (material.kind = 'isotropic'; "
                          f"an orthotropic one varies material.e1, e2, g12, g13, g23, "
                          f"fibre_angle_deg)")
    if path in _ORTHO and iso:
        raise DesignError(f"{path}: needs an orthotropic material (material.kind = "
                          f"'orthotropic'; an isotropic one varies material.youngs_modulus)")
    if path == "material.fibre_angle_deg":
        return math.degrees(float(obj.fibre_angle))
    if section == "support" and obj.kind != "shaft":
        raise DesignError(f"{path}: needs a shaft support (support.kind = 'shaft'), got "
                          f"{obj.kind!r}")
    if v is None:
        raise DesignError(f"{path}: the case has no {path} to vary (add it to the case file)")
    return float(v)


def with_values(case: Case, paths, values) -> Case:
    """The case with the design variables' keys set to ``values``."""
    th = case.thickness
    pms = list(case.point_masses)
    table = [list(r) for r in th.values] if getattr(th, "is_table", False) else None
    for path, v in zip(paths, values):
        if path in _MATERIAL or path in _SUPPORT or path in _ORTHO:
            section, key = path.split(".")
            key, v = (("fibre_angle", math.radians(v)) if key == "fibre_angle_deg"
                      else (key, v))
            case = dataclasses.replace(case, **{section: dataclasses.replace(
                getattr(case, section), **{key: float(v)})})
        elif table_index(path) is not None:
            i, j = table_index(path)
            table[i][j] = float(v)
        elif path == "thickness.root":
            th = dataclasses.replace(th, root=float(v))
        elif path == "thickness.tip":
            th = dataclasses.replace(th, tip=float(v))
        else:
            i, axis = _point_index(path), position_axis(path)
            if axis is None:
                pms[i] = dataclasses.replace(pms[i], mass=float(v))
            else:
                pos = list(pms[i].position)
                pos[axis] = float(v)
                pms[i] = dataclasses.replace(pms[i], position=tuple(pos))
    if table is not None:
        th = dataclasses.replace(th, values=tuple(tuple(r) for r in table))
    return dataclasses.replace(case, thickness=th, point_masses=tuple(pms))


def set_case_values(raw: dict, paths, values) -> dict:
    """The case file's dict (as read) with the design keys set, for writing the optimised case."""
    import copy
    out = copy.deepcopy(raw)
    for path, v in zip(paths, values):
        if table_index(path) is not None:
            i, j = table_index(path)
            out["thickness"]["values_m"][i][j] = float(v)
        elif path.split(".")[0] in ("thickness", "material", "support"):
            section, key = path.split(".")
            if path == "material.g12":
                # g13 and g23 default to g12 in the case format: keep them where they were
                for k in ("g13", "g23"):
                    out["material"].setdefault(k, out["material"]["g12"])
            out.setdefault(section, {})[key] = float(v)
        else:
            pm, axis = out["point_mass"][_point_index(path)], position_axis(path)
            if axis is None:
                pm["mass"] = float(v)
            else:
                pm["position"] = list(pm["position"])
                pm["position"][axis] = float(v)
    return out


def check_case(case: Case, problem: DesignProblem) -> None:
    """Refuse, before any work, a case the optimiser does not handle (one line naming the key)."""
    if case.structure is not None:
        raise DesignError("design: an imported structure (a Nastran deck) has no case keys to "
                          "vary; optimise a case file")
    if case.support.kind not in ("shaft", "clamped_root"):
        raise DesignError(f"support.kind = {case.support.kind!r}: the optimiser handles "
                          f"'shaft' and 'clamped_root'")
    d = case.damping
    if d.modal_damping_ratio is not None or d.structural_g is not None:
        raise DesignError("damping: the optimiser's flutter derivatives are for an undamped "
                          "structure; remove [damping]")
    table = getattr(case.thickness, "is_table", False)
    if not table and not case.thickness.profile.is_flat:
        raise DesignError("thickness.profile must be 'flat' for the thickness variables")
    for i, v in enumerate(problem.variables):
        if table and v.path in _THICKNESS:
            raise DesignError(f"design.variable[{i}].path {v.path!r}: the case's thickness is a "
                              f"table; vary {_TABLE} or {_TABLE}[i][j]")
    if case.aero is None or case.flight is None or case.flight.envelope_mach is None \
            or case.flight.altitudes is None:
        raise DesignError("the case needs [aero], [flight] altitudes and [flight.envelope] "
                          "for the flutter-margin constraint")
    top = float(case.flight.envelope_mach[1])
    if not any(abs(top - m) < 1e-12 for m in case.aero.machs):
        raise DesignError(f"flight.envelope.mach top {top:g} must be one of aero.machs "
                          f"{list(case.aero.machs)} (the margin is computed there)")
    for i, v in enumerate(problem.variables):
        x0 = case_value(case, v.path)
        if not v.lower <= x0 <= v.upper:
            raise DesignError(f"design.variable[{i}] {v.path} = {x0:g} in the case lies outside "
                              f"its bounds [{v.lower:g}, {v.upper:g}]")
    _check_positions(case, problem)


def _check_positions(case: Case, problem: DesignProblem) -> None:
    """Every point-mass position the bounds allow must lie on the plate: the corners of each
    moved mass's box of positions (the panel is convex, so the box is then on it)."""
    from asekit.structure.plate import locate_points
    boxes: dict = {}
    for i, v in enumerate(problem.variables):
        axis = position_axis(v.path)
        if axis is not None:
            k = _point_index(v.path)
            box = boxes.setdefault(k, [[p, p] for p in case.point_masses[k].position] + [[]])
            box[axis] = [v.lower, v.upper]
            box[2].append(i)
    if not boxes:
        return
    mesh = P.structural_mesh(case)
    for k, (xs, ys, idx) in boxes.items():
        for corner in [(x, y) for x in xs for y in ys]:
            try:
                locate_points(mesh.nodes, mesh.elements, np.array([corner]))
            except ValueError:
                names = ", ".join(f"design.variable[{i}]" for i in idx)
                raise DesignError(f"{names}: point_mass[{k}] at ({corner[0]:g}, {corner[1]:g}) m "
                                  f"(a corner of its bounds) is off the plate; narrow the "
                                  f"bounds to the planform") from None


def envelope_conditions(case: Case) -> list:
    """The analysed flight conditions inside ``flight.envelope.altitude``."""
    lo, hi = case.flight.envelope_altitude or (-math.inf, math.inf)
    return [c for c in P.flight_conditions(case) if lo <= c.altitude <= hi]


# ---------------------------------------------------------------------------------------------
# one evaluation of the chain with its derivatives
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Evaluation:
    """Mass (kg), flutter speeds and margins with their gradients at one design.

    values : (n_var,) the design; mass_kg, d_mass (n_var,); speeds_ms (n_cond,) U_f per envelope
    altitude (NaN: no flutter in the velocity sweep); d_speeds (n_cond, n_var); envelope_ms
    (n_cond,) M a; margins (n_cond,) U_f / (M a) - 1; frequencies_hz (n_cond,) at flutter;
    densities (n_cond,) kg/m^3; eigenvalues (n,) omega_i^2 (rad^2/s^2) of the elastic modes and
    d_eigenvalues (n_var, n) (Fox-Kapoor); divergence_mu : 1 / q_D (1/Pa) of the elastic modes at the top
    Mach (:func:`asekit.aeroelastic.sensitivity.divergence_sensitivity`; <= 0: no divergence,
    NaN: no real eigenvalue), d_divergence_mu (n_var,).
    """

    values: np.ndarray
    mass_kg: float
    d_mass: np.ndarray
    speeds_ms: np.ndarray
    d_speeds: np.ndarray
    envelope_ms: np.ndarray
    frequencies_hz: np.ndarray
    densities: np.ndarray = field(default_factory=lambda: np.zeros(0))
    divergence_mu: float = math.nan
    d_divergence_mu: np.ndarray = field(default_factory=lambda: np.zeros(0))
    eigenvalues: np.ndarray = field(default_factory=lambda: np.zeros(0))
    d_eigenvalues: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    #: the AEM1 margins and their gradients (:class:`AseMargins`) when
    #: the problem constrains them, else None
    ase: object = None
    #: the fin's pitch inertia about the shaft axis (kg m^2, plate and point masses: r^T M r
    #: with the rigid pitch vector r; NaN without a shaft) and its gradient (n_var,)
    pitch_inertia_kgm2: float = math.nan
    d_pitch_inertia: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def elastic_frequencies_hz(self) -> np.ndarray:
        """f_i = sqrt(lambda_i) / 2 pi of the elastic modes (Hz)."""
        return np.sqrt(np.maximum(self.eigenvalues, 0.0)) / (2 * math.pi)

    @property
    def margins(self) -> np.ndarray:
        return self.speeds_ms / self.envelope_ms - 1.0

    @property
    def divergence_speeds_ms(self) -> np.ndarray:
        """U_D = sqrt(2 / (rho mu)) per envelope altitude (m/s; inf: no divergence)."""
        mu = self.divergence_mu
        if not mu > 0:
            return np.full(self.densities.shape, math.inf)
        return np.sqrt(2.0 / (self.densities * mu))


@dataclass
class Evaluator:
    """The design chain of one case and design problem (module docstring); evaluations are
    memoised on the design vector. ``operators``: the factored aerodynamic operators of the
    envelope's top Mach (formed once: the boxes do not change)."""

    case: Case
    problem: DesignProblem
    n_elastic: int = 0
    operators: tuple = ()
    calls: int = 0
    ase_operators: tuple = ()
    _memo: dict = field(default_factory=dict)

    def __post_init__(self):
        self.problem = expand_variables(self.problem, self.case)
        check_case(self.case, self.problem)
        if _has_ase(self.problem):
            _check_ase_case(self.case, self.problem)
        base = P.modal_model(self.case)
        self.n_elastic = base.frequencies_hz.size - base.n_rigid
        n_sep = self.problem.frequency_separation_modes
        if self.problem.frequency_separation is not None and n_sep > self.n_elastic:
            raise DesignError(f"design.frequency_separation_modes = {n_sep}: the case has "
                              f"{self.n_elastic} elastic modes (modes.count / modes.f_max)")
        a = self.case.aero
        mach = self.mach
        spec = AERO_METHODS[resolve_method(a.method, mach)]
        if spec.operators is None or not spec.structure_independent:
            raise DesignError(f"aero.method = {a.method!r} at M {mach:g}: the optimiser needs a "
                              f"structure-independent aerodynamic operator (dlm, supersonic, piston)")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            self.operators = spec.operators(P.box_mesh(self.case), mach,
                                            P.reduced_frequencies(self.case),
                                            a.reference_semichord, a.symmetry == "wall",
                                            a.kernel if a.method == "dlm" else "quartic")
        if _has_ase(self.problem):
            self.ase_operators = _ase_operators(self.case, self.problem)

    @property
    def mach(self) -> float:
        return float(self.case.flight.envelope_mach[1])

    @property
    def paths(self) -> tuple[str, ...]:
        return tuple(v.path for v in self.problem.variables)

    def __call__(self, values) -> Evaluation:
        key = tuple(float(v) for v in values)
        if key not in self._memo:
            self.calls += 1
            self._memo[key] = evaluate(self, np.array(key))
        return self._memo[key]


def _has_ase(problem: DesignProblem) -> bool:
    return problem.phase_margin_deg is not None or problem.gain_margin_db is not None


def _ase_key(problem: DesignProblem) -> str:
    return "phase_margin_deg" if problem.phase_margin_deg is not None else "gain_margin_db"


def _check_ase_case(case: Case, problem: DesignProblem) -> None:
    """DesignError naming the design key when the case has no ASE loop to constrain."""
    key = _ase_key(problem)
    if case.actuator is None:
        raise DesignError(f"design.{key}: the case has no [actuator] (no ASE loop)")
    if case.support.kind != "shaft" or not case.modes.keep_rigid:
        raise DesignError(f"design.{key}: the ASE loop needs a shaft support with "
                          "modes.keep_rigid = true (the rigid pitch mode)")


def _ase_operators(case: Case, problem: DesignProblem):
    """The aerodynamic operators at the actuator's Mach for the margin constraints; a
    DesignError naming the design key when the case cannot have them."""
    key = _ase_key(problem)
    try:
        return _ase_aero_operators(case, case.actuator.mach)
    except CaseError as exc:
        raise DesignError(f"design.{key}: {exc}") from None


def _system(case: Case, mesh, K, M):
    s = case.support
    if s.kind == "clamped_root":
        return clamped_edge(mesh, K, M)
    return shaft_support(mesh, K, M, s.axis_point, s.torsional_stiffness, model="FN1",
                         region="single_node" if s.radius is None else "distributed",
                         radius=s.radius or 0.0, bending_stiffness=s.bending_stiffness)


def _elastic_modes(system, M, n_elastic: int):
    """(lam, q) of the first ``n_elastic`` out-of-plane modes of the FN1 / clamped system."""
    n = min(system.K.shape[0], 2 * n_elastic + 4)
    modes = normal_modes(system, n, M_fin=M)
    keep = np.flatnonzero(select_modes(modes.frequencies_hz, modes.out_of_plane, 1e300))
    if keep.size < n_elastic:
        raise CaseError(f"the design has {keep.size} out-of-plane modes below the search, "
                        f"{n_elastic} needed")
    keep = keep[:n_elastic]
    return modes.eigenvalues[keep], modes.q[:, keep]


def _thickness_dh(mesh, parts, path: str):
    """dh/d(thickness.root or .tip) at the stiffness and mass points: 1 - eta or eta."""
    out = []
    for xy in (parts.xy_k, parts.xy_m):
        eta = (xy[..., 1] - mesh.y_root) / mesh.span
        out.append(1.0 - eta if path == "thickness.root" else eta)
    return out


def _table_dh(mesh, parts, ij):
    """dh/d(values_m[i][j]) at the stiffness and mass points: the bilinear weight
    H_i(eta) H_j(xi) of the table value (:meth:`asekit.geometry.ThicknessTable.weights`)."""
    field = mesh.thickness_field
    out = []
    for xy in (parts.xy_k, parts.xy_m):
        xi, eta = field.fractions(xy[..., 0], xy[..., 1])
        out.append(field.thickness.weights(xi, eta)[..., ij[0], ij[1]])
    return out


def _matrix_derivatives(ev: Evaluator, case: Case, mesh, parts, K, M):
    """Global dK, dM (fin DOFs) and d(mass) per design variable (a shaft spring's are zero
    here: it acts on the supported system only, :func:`_support_derivative`)."""
    dK, dM, dm = [], [], []
    w_mass = parts.Mt[:, :, 0::3, 0::3].sum(axis=(2, 3))         # (ne, ng): rho w det per point
    plate_mass = float(np.sum(w_mass * parts.h_m))
    zero = 0 * M
    for path in ev.paths:
        if path in _THICKNESS or table_index(path) is not None:
            dh_k, dh_m = (_thickness_dh(mesh, parts, path) if path in _THICKNESS
                          else _table_dh(mesh, parts, table_index(path)))
            k, m = thickness_derivatives(mesh, parts, dh_k[None], dh_m[None])
            dK.append(k[0])
            dM.append(m[0])
            dm.append(float(np.sum(w_mass * dh_m)))
        elif path == "material.youngs_modulus":
            dK.append(youngs_modulus_derivative(K, case.material))
            dM.append(zero)
            dm.append(0.0)
        elif path == "material.density":
            dK.append(zero)
            dM.append(density_derivative(scatter(mesh, parts.mass()), case.material))
            dm.append(plate_mass / float(case.material.density))
        elif path in _ORTHO:
            name = path.split(".")[1]
            unit = math.pi / 180.0 if name == "fibre_angle_deg" else 1.0      # per degree
            dK.append(unit * orthotropic_stiffness_derivative(
                mesh, case.material, "fibre_angle" if name == "fibre_angle_deg" else name))
            dM.append(zero)
            dm.append(0.0)
        elif path in _SUPPORT:
            dK.append(zero)
            dM.append(zero)
            dm.append(0.0)
        elif position_axis(path) is None:
            pm = case.point_masses[_point_index(path)]
            dM.append(point_mass_derivative(mesh, pm.position))
            dK.append(0 * dM[-1])
            dm.append(1.0)
        else:
            pm = case.point_masses[_point_index(path)]
            dM.append(point_mass_position_derivative(mesh, pm.position, pm.mass, pm.inertia,
                                                     position_axis(path)))
            dK.append(0 * dM[-1])
            dm.append(0.0)                  # moving a mass does not change the total
    mass = plate_mass + sum(p.mass for p in case.point_masses)
    return dK, dM, mass, np.array(dm)


def _support_derivative(system, path: str):
    """dK_r of a shaft spring in the FN1 system's coordinates: e_s e_s^T on the shaft's pitch
    coordinate (``support.torsional_stiffness``; :func:`asekit.structure.assembly.shaft_support`
    adds k there) or on the bending coordinate, the last one (``support.bending_stiffness``);
    None for any other variable. The springs carry no mass."""
    if path not in _SUPPORT:
        return None
    n = system.K.shape[0]
    i = system.shaft_index if path == "support.torsional_stiffness" else n - 1
    return sp.csr_matrix(([1.0], ([i], [i])), shape=(n, n))


def _gafs(ev: Evaluator, mesh, shapes: np.ndarray) -> np.ndarray:
    """Q (n_k, N, N) of the (extended) mode table on the boxes through the factored operators."""
    model = ModalModel(frequencies_hz=np.zeros(shapes.shape[2]), M=None, K=None, C=None,
                       n_rigid=0, J_fin=0.0, nodes=mesh.nodes, shapes=shapes,
                       elements=mesh.elements, label="")
    boxes = P.box_mesh(ev.case)
    bm = fe_spline(model, boxes)
    ks, b = P.reduced_frequencies(ev.case), ev.case.aero.reference_semichord
    out = np.empty((ks.size, shapes.shape[2], shapes.shape[2]), complex)
    for ik, kk in enumerate(ks):
        out[ik] = modal_forces(bm, ev.operators[ik].pressures(bm.normalwash(kk, b)), boxes.area)
    return out


def _sweep(velocities) -> np.ndarray:
    """At most :data:`SWEEP_POINTS` of the velocities, the first and last included."""
    v = np.asarray(velocities, float)
    stride = max(1, math.ceil((v.size - 1) / (SWEEP_POINTS - 1)))
    return np.unique(np.append(v[::stride], v[-1]))


def _flutter(ev: Evaluator, mats: dict, gaf: TabulatedGaf, density: float):
    """(U_f, f_f, dU_f) of the first flutter crossing in the case's velocity sweep (NaN and a
    zero gradient when there is none)."""
    n_var = mats["dK"].shape[0]
    modal = modal_arrays(M=mats["M"], K=mats["K"], C=mats["C"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = pk_flutter(modal, gaf, density, _sweep(ev.case.flight.velocities))
        flut = [i for i in pk_instabilities(res, modal, gaf)
                if i.kind == "flutter" and not i.at_first_point]
    if not flut:
        return math.nan, math.nan, np.zeros(n_var)
    f = min(flut, key=lambda i: i.speed)
    col = list(res.modes).index(f.mode)
    iu = max(int(np.searchsorted(res.velocities, f.speed)) - 1, 0)
    U, p, _ = flutter_point(mats["M"], mats["K"], mats["C"], gaf, density, f.speed,
                            res.p[iu, col], res.vectors[iu, col])
    s = flutter_speed_sensitivity(mats["M"], mats["K"], mats["C"], gaf, density, U, p,
                                  mats["dM"], mats["dK"], mats["dC"], mats["dQ"])
    return U, s.frequency_hz, s.d_speed


def _pitch_inertia(case: Case, mesh, M, dM) -> tuple[float, np.ndarray]:
    """The fin's pitch inertia about the shaft axis, J = r^T M r, and dJ_j = r^T dM_j r, with
    the rigid pitch vector r (:func:`asekit.structure.assembly.rigid_pitch_vector`; M and dM
    on the fin's DOFs, point masses included). (NaN, NaN...) without a shaft support."""
    if case.support.kind != "shaft":
        return math.nan, np.full(len(dM), math.nan)
    r = rigid_pitch_vector(mesh, case.support.axis_point[0])
    return float(r @ (M @ r)), np.array([float(r @ (d @ r)) for d in dM])


def evaluate(ev: Evaluator, values: np.ndarray) -> Evaluation:
    """One evaluation of the chain (module docstring) at the design ``values``."""
    case = with_values(ev.case, ev.paths, values)
    mesh = P.structural_mesh(case)
    K, M = P.mass_and_stiffness(case)
    parts = element_parts(mesh, case.material)
    dK, dM, mass, d_mass = _matrix_derivatives(ev, case, mesh, parts, K, M)
    system = _system(case, mesh, K, M)
    lam, q = _elastic_modes(system, M, ev.n_elastic)
    dKr = [reduce(system.T, a) for a in dK]
    for j, path in enumerate(ev.paths):
        extra = _support_derivative(system, path)
        if extra is not None:
            dKr[j] = dKr[j] + extra
    dMr = [reduce(system.T, a) for a in dM]
    dlam, dq = mode_shape_derivatives(system.K, system.M, lam, q, dKr, dMr)
    n = lam.size
    shapes = (system.T @ q).reshape(mesh.n_nodes, 3, n)
    dshapes = np.array([(system.T @ d).reshape(mesh.n_nodes, 3, n) for d in dq])
    Q = _gafs(ev, mesh, extended_shapes(shapes, dshapes))
    gaf = TabulatedGaf(P.reduced_frequencies(case), Q[:, :n, :n],
                       case.aero.reference_semichord, ev.mach)
    n_var = len(dK)
    mats = {"M": np.eye(n), "K": np.diag(lam), "C": np.zeros((n, n)),
            "dM": np.zeros((n_var, n, n)), "dK": np.array([np.diag(d) for d in dlam]),
            "dC": np.zeros((n_var, n, n)), "dQ": gaf_derivative(Q, n)}
    conds = envelope_conditions(case)
    out = [_flutter(ev, mats, gaf, c.density) for c in conds]
    div = divergence_sensitivity(mats["K"], Q[0, :n, :n], mats["dK"], mats["dQ"][:, 0])
    J, dJ = _pitch_inertia(case, mesh, M, dM)
    ase = None
    if _has_ase(ev.problem):
        ase = ase_margins(ev.case, ev.paths, values, operators=ev.ase_operators)
    return Evaluation(values=values, mass_kg=mass, d_mass=d_mass,
                      speeds_ms=np.array([o[0] for o in out]),
                      d_speeds=np.array([o[2] for o in out]),
                      envelope_ms=np.array([ev.mach * c.speed_of_sound for c in conds]),
                      frequencies_hz=np.array([o[1] for o in out]),
                      densities=np.array([c.density for c in conds]),
                      divergence_mu=div.mu, d_divergence_mu=div.d_mu,
                      eigenvalues=np.asarray(lam, float), d_eigenvalues=np.asarray(dlam, float),
                      ase=ase, pitch_inertia_kgm2=J, d_pitch_inertia=dJ)


# ---------------------------------------------------------------------------------------------
# the optimiser
# ---------------------------------------------------------------------------------------------
def _constraint(ev: Evaluator, e: Evaluation):
    """g_a = U_f / ((1 + margin) (1 + slack) M a) - 1 >= 0 per envelope altitude and its gradient; no
    flutter in the sweep counts as U_f = the sweep's last speed (a lower bound), gradient 0."""
    u = np.where(np.isnan(e.speeds_ms), ev.case.flight.velocities[-1], e.speeds_ms)
    scale = (1.0 + ev.problem.flutter_margin) * (1.0 + CONSTRAINT_SLACK) * e.envelope_ms
    g, dg = u / scale - 1.0, e.d_speeds / scale[:, None]
    if ev.problem.divergence_margin is not None:
        gd, dgd = _divergence_constraint(ev.problem.divergence_margin, e)
        g, dg = np.concatenate([g, gd]), np.vstack([dg, dgd])
    if ev.problem.frequency_separation is not None:
        gs, dgs = separation_constraint(ev.problem.frequency_separation,
                                        ev.problem.frequency_separation_modes, e)
        g, dg = np.concatenate([g, gs]), np.vstack([dg, dgs])
    if _has_ase(ev.problem):
        ga, dga = ase_margin_constraints(ev.problem, e)
        g, dg = np.concatenate([g, ga]), np.vstack([dg, dga])
    return g, dg


def ase_margin_constraints(problem: DesignProblem, e: Evaluation):
    """g = PM / (PM_req (1 + slack)) - 1 >= 0 and g = GM / (GM_req (1 + slack)) - 1 >= 0 for
    the AEM1 loop's smallest phase margin (deg) and its gain margin (dB)
    (``design.phase_margin_deg``, ``design.gain_margin_db``, the rows that are set, in that
    order), with the gradients of :func:`ase_margins`. No phase crossover (GM = inf)
    counts as g = 1, gradient 0; likewise no gain crossover for the phase margin."""
    a, n_var = e.ase, e.d_mass.size
    g, dg = [], []
    for req, val, dval in ((problem.phase_margin_deg, a.phase_margin_deg, a.d_phase_margin_deg),
                           (problem.gain_margin_db, a.gain_margin_db, a.d_gain_margin_db)):
        if req is None:
            continue
        s = req * (1.0 + CONSTRAINT_SLACK)
        finite_val = math.isfinite(val)
        g.append(val / s - 1.0 if finite_val else 1.0)
        dg.append(np.asarray(dval) / s if finite_val else np.zeros(n_var))
    return np.array(g), np.array(dg).reshape(len(g), n_var)


def separation_constraint(separation: float, n_modes: int, e: Evaluation):
    """g_i = sqrt(lambda_{i+1} / lambda_i) / ((1 + s)(1 + slack)) - 1 >= 0, i = 0 .. n - 2:
    f_{i+1} / f_i - 1 >= s for the first ``n_modes`` elastic modes (in ascending order), and
    its gradient from the eigenvalue derivatives (Fox & Kapoor 1968, Eq. 8):
    dg_i = r_i / (2 (1 + s)(1 + slack)) (dlambda_{i+1} / lambda_{i+1} - dlambda_i / lambda_i),
    r_i = f_{i+1} / f_i. Smooth while the modes stay distinct (at a crossing the ascending
    order swaps, and the separation is zero there anyway).

    Examples
    --------
    >>> e = Evaluation(values=np.zeros(1), mass_kg=1.0, d_mass=np.zeros(1), speeds_ms=np.zeros(0),
    ...                d_speeds=np.zeros((0, 1)), envelope_ms=np.zeros(0),
    ...                frequencies_hz=np.zeros(0), eigenvalues=np.array([1.0, 4.0]),
    ...                d_eigenvalues=np.array([[1.0, 0.0]]))
    >>> g, dg = separation_constraint(0.5, 2, e)         # f2 / f1 = 2 >= 1.5
    >>> round(float(g[0]), 4), round(float(dg[0, 0]), 4)
    (0.3332, -0.6666)
    """
    lam, dlam = e.eigenvalues[:n_modes], e.d_eigenvalues[:, :n_modes]
    scale = (1.0 + separation) * (1.0 + CONSTRAINT_SLACK)
    r = np.sqrt(lam[1:] / lam[:-1])
    dr = 0.5 * r[None, :] * (dlam[:, 1:] / lam[1:] - dlam[:, :-1] / lam[:-1])
    return r / scale - 1.0, (dr / scale).T


def _divergence_constraint(margin: float, e: Evaluation):
    """g_a = 1 - q_a mu >= 0 per envelope altitude, q_a = rho_a ((1 + margin) (1 + slack) M a)^2
    / 2 the dynamic pressure the divergence must exceed (q_D = 1 / mu >= q_a), and its gradient
    -q_a dmu. Smooth where the design loses its divergence (mu through zero, q_D through
    infinity); no real divergence eigenvalue (NaN mu) counts as none, gradient 0."""
    q = 0.5 * e.densities * ((1.0 + margin) * (1.0 + CONSTRAINT_SLACK) * e.envelope_ms) ** 2
    if not np.isfinite(e.divergence_mu):
        return np.ones_like(q), np.zeros((q.size, e.d_mass.size))
    return 1.0 - q * e.divergence_mu, -q[:, None] * e.d_divergence_mu[None, :]


@dataclass(frozen=True)
class DesignResult:
    """The outcome of :func:`optimise`.

    paths : the variables' case keys; baseline, optimised : :class:`Evaluation` at the case's
    values and at the optimum; history : one dict per optimiser iteration (values, mass_kg,
    min_margin_pct); success, message : the optimiser's verdict; evaluations : chain
    evaluations; seconds : wall time; gradient_check : (n_var,) max relative error of the
    analytic gradients (mass and flutter speeds) against central differences at the baseline
    (None when not checked); gradient_check_seconds : the time of those differences;
    constraints : the constraint activity at the optimum, one dict per constraint
    (:func:`constraint_activity`).
    """

    paths: tuple[str, ...]
    baseline: Evaluation
    optimised: Evaluation
    history: tuple[dict, ...]
    success: bool
    message: str
    evaluations: int
    seconds: float
    gradient_check: np.ndarray | None = None
    gradient_check_seconds: float = 0.0
    constraints: tuple[dict, ...] = ()

    @property
    def max_rel_error(self) -> float | None:
        return None if self.gradient_check is None else float(np.max(self.gradient_check))


def variable_scales(problem: DesignProblem, x0: np.ndarray) -> np.ndarray:
    """The optimiser's variable scales: |baseline value|, or the bounds' width where the
    baseline is 0 (a fibre angle, a point mass starting at zero). SLSQP works on v / scale;
    the gradient check's step is ``rel_step`` times the scale.

    Examples
    --------
    >>> p = design_from_dict({"design": {"variable": [
    ...     {"path": "thickness.tip", "lower": 0.001, "upper": 0.004},
    ...     {"path": "point_mass[0].mass", "lower": 0.0, "upper": 0.05}]}})
    >>> variable_scales(p, np.array([0.002, 0.0])).tolist()
    [0.002, 0.05]
    """
    x0 = np.asarray(x0, float)
    width = np.array([v.upper - v.lower for v in problem.variables])
    return np.where(x0 != 0.0, np.abs(x0), width)


def gradient_check(ev: Evaluator, x0: np.ndarray, rel_step: float = 1e-4) -> np.ndarray:
    """Max relative error per variable of the analytic d(mass), d(pitch inertia), dU_f, dmu (the
    divergence eigenvalue) and, with a frequency-separation constraint, dlambda of its modes
    (the elastic eigenvalues) against central differences of the whole chain (step ``rel_step`` times the
    value, or the bounds' width where the value is 0: :func:`variable_scales`)."""
    e0 = ev(x0)
    scale = variable_scales(ev.problem, x0)
    err = np.zeros(x0.size)
    for j in range(x0.size):
        h = rel_step * scale[j]
        ep, em = ev(x0 + h * np.eye(x0.size)[j]), ev(x0 - h * np.eye(x0.size)[j])
        pairs = [(e0.d_mass[j], (ep.mass_kg - em.mass_kg) / (2 * h))]
        pairs += [(a, (b - c) / (2 * h)) for a, b, c in
                  zip(e0.d_speeds[:, j], ep.speeds_ms, em.speeds_ms) if np.isfinite(b - c)]
        if ev.problem.frequency_separation is not None:
            n_sep = ev.problem.frequency_separation_modes
            pairs += [(a, (b - c) / (2 * h)) for a, b, c in
                      zip(e0.d_eigenvalues[j, :n_sep], ep.eigenvalues, em.eigenvalues)]
        if e0.ase is not None and np.isfinite(ep.ase.phase_margin_deg - em.ase.phase_margin_deg):
            pairs.append((e0.ase.d_phase_margin_deg[j],
                          (ep.ase.phase_margin_deg - em.ase.phase_margin_deg) / (2 * h)))
        if np.isfinite(ep.divergence_mu - em.divergence_mu):
            pairs.append((e0.d_divergence_mu[j], (ep.divergence_mu - em.divergence_mu) / (2 * h)))
        err[j] = max(abs(a - f) / max(abs(f), 1e-300) for a, f in pairs)
        if np.isfinite(e0.pitch_inertia_kgm2):
            # relative to |fd|, floored at 1e-6 J per unit relative change of the variable where
            # J does not depend on it (a mass moved spanwise: the differences are round-off)
            fd = (ep.pitch_inertia_kgm2 - em.pitch_inertia_kgm2) / (2 * h)
            floor = 1e-6 * e0.pitch_inertia_kgm2 / scale[j]
            err[j] = max(err[j], abs(e0.d_pitch_inertia[j] - fd) / max(abs(fd), floor))
    return err


def smoothness_matrix(paths) -> np.ndarray:
    """(n_pairs, n_var) D with (D v)_p = v_a - v_b for every pair of adjacent table values
    (neighbours along eta or along x_over_c) that are both design variables."""
    where = {table_index(p): k for k, p in enumerate(paths) if table_index(p) is not None}
    rows = []
    for (i, j), a in where.items():
        for nb in ((i + 1, j), (i, j + 1)):
            if nb in where:
                r = np.zeros(len(paths))
                r[a], r[where[nb]] = 1.0, -1.0
                rows.append(r)
    return np.array(rows).reshape(len(rows), len(paths))


def smoothness_constraints(paths, x0: np.ndarray, step: float | None) -> list:
    """SLSQP linear inequalities step -+ D (z x0) >= 0 (:func:`smoothness_matrix`) on the
    scaled variables z = v / x0; none without a step or adjacent table variables."""
    D = smoothness_matrix(paths)
    if step is None or D.shape[0] == 0:
        return []
    A = np.vstack([-D, D]) * x0[None, :]
    return [{"type": "ineq", "fun": lambda z: step + A @ z, "jac": lambda z: A}]


def constraint_names(ev: Evaluator, e: Evaluation) -> list[tuple[str, float, float]]:
    """(name, value, bound) of each row of :func:`_constraint`, in its order: the flutter margin
    per envelope altitude (U_f / (M a) - 1 against ``flutter_margin``), the divergence margin
    (U_D / (M a) - 1; inf: no divergence), the frequency separations (f_{i+1} / f_i - 1)."""
    pr = ev.problem
    alts = [c.altitude for c in envelope_conditions(ev.case)]
    u = np.where(np.isnan(e.speeds_ms), ev.case.flight.velocities[-1], e.speeds_ms)
    rows = [(f"flutter_margin[{a:g} m]", float(m), pr.flutter_margin)
            for a, m in zip(alts, u / e.envelope_ms - 1.0)]
    if pr.divergence_margin is not None:
        rows += [(f"divergence_margin[{a:g} m]", float(ud / ue - 1.0), pr.divergence_margin)
                 for a, ud, ue in zip(alts, e.divergence_speeds_ms, e.envelope_ms)]
    if pr.frequency_separation is not None:
        f = e.elastic_frequencies_hz[:pr.frequency_separation_modes]
        rows += [(f"frequency_separation[f{i + 2}/f{i + 1}]", float(f[i + 1] / f[i] - 1.0),
                  pr.frequency_separation) for i in range(f.size - 1)]
    if pr.phase_margin_deg is not None:
        rows.append(("phase_margin_deg[AEM1]", e.ase.phase_margin_deg, pr.phase_margin_deg))
    if pr.gain_margin_db is not None:
        rows.append(("gain_margin_db[AEM1]", e.ase.gain_margin_db, pr.gain_margin_db))
    return rows


def constraint_activity(ev: Evaluator, e: Evaluation, multipliers=None,
                        epigraph: float | None = None,
                        baseline_mass: float | None = None) -> tuple[dict, ...]:
    """The constraints at the design ``e``: one dict {name, value, bound, active, multiplier}
    per constraint, ``active`` where the normalised row g <= :data:`ACTIVE_TOL`.

    Values are the physical ones (margins and separations as fractions, the smoothness steps and
    their bound in m, the mass in kg). ``multipliers`` are SLSQP's KKT multipliers in its order
    (the mass equality first, then :func:`_constraint`'s rows, then the smoothness rows -D, +D)
    for the scaled problem (variables over their baseline values, rows as normalised here);
    None: not reported. With the ``flutter_speed`` objective, ``epigraph`` is the maximised
    smallest margin t: the flutter rows are U_f / (M a) - 1 - t >= 0, bound t, and the mass
    equality (bound ``baseline_mass``, kg) leads the list.
    """
    mult = None if multipliers is None else list(np.asarray(multipliers, float))
    out = []

    def take(n):
        if mult is None:
            return [None] * n
        got, mult[:n] = mult[:n], []
        return [float(m) for m in got]

    if epigraph is not None:
        out.append({"name": "mass_kg (equality)", "value": e.mass_kg, "bound": baseline_mass,
                    "active": True, "multiplier": take(1)[0]})
    g = _constraint(ev, e)[0]
    names = constraint_names(ev, e)
    if epigraph is not None:
        n_f = len(envelope_conditions(ev.case))
        names[:n_f] = [(nm, v, epigraph) for nm, v, _ in names[:n_f]]
        g = g.copy()
        g[:n_f] = np.array([v for _, v, _ in names[:n_f]]) - epigraph
    for (name, value, bound), gi, m in zip(names, g, take(len(names))):
        out.append({"name": name, "value": value if math.isfinite(value) else None,
                    "bound": bound, "active": bool(gi <= ACTIVE_TOL), "multiplier": m})
    step = ev.problem.table_max_step_m
    D = smoothness_matrix(ev.paths)
    if step is not None and D.shape[0]:
        ms = take(2 * D.shape[0])
        for r, dv in enumerate(D @ e.values):
            a, b = (ev.paths[k] for k in np.flatnonzero(D[r]))
            m = None if ms[0] is None else ms[r] + ms[r + D.shape[0]]
            out.append({"name": f"table_step[{a} - {b}]", "value": float(abs(dv)),
                        "bound": step, "active": bool((step - abs(dv)) / step <= ACTIVE_TOL),
                        "multiplier": m})
    return tuple(out)


def _mass_problem(ev: Evaluator, sc: np.ndarray, m0: float, xb: np.ndarray):
    """SLSQP's (objective, constraints, z0, bounds) of the minimum-mass problem on z = v / sc
    (:func:`variable_scales`; xb the baseline values)."""
    def obj(z):
        e = ev(z * sc)
        return e.mass_kg / m0, e.d_mass * sc / m0

    cons = [{"type": "ineq", "fun": lambda z: _constraint(ev, ev(z * sc))[0],
             "jac": lambda z: _constraint(ev, ev(z * sc))[1] * sc[None, :]}]
    cons += smoothness_constraints(ev.paths, sc, ev.problem.table_max_step_m)
    bounds = [(v.lower / x, v.upper / x) for v, x in zip(ev.problem.variables, sc)]
    return obj, cons, xb / sc, bounds


def _flutter_speed_problem(ev: Evaluator, sc: np.ndarray, m0: float, xb: np.ndarray):
    """SLSQP's (objective, constraints, y0, bounds) of the maximum-flutter-speed problem: on
    y = (z, t), z = v / sc (:func:`variable_scales`), maximise t subject to
    U_f,a / (M a) - 1 - t >= 0 at every envelope altitude (t is then the smallest margin, the
    epigraph form of max min), the mass equal to
    the baseline's (mass / m0 - 1 = 0) and the other constraints of the design (divergence,
    frequency separation, smoothness) on z."""
    n, n_f = sc.size, len(envelope_conditions(ev.case))
    fm = ev.problem.flutter_margin

    def rows(y):
        e = ev(y[:n] * sc)
        g, dg = _constraint(ev, e)
        s = (1.0 + fm) * (1.0 + CONSTRAINT_SLACK)
        g, dg = g.copy(), dg * sc[None, :]
        g[:n_f], dg[:n_f] = (g[:n_f] + 1.0) * s - 1.0 - y[n], dg[:n_f] * s   # margin - t
        dt = np.zeros((g.size, 1))
        dt[:n_f] = -1.0
        return g, np.hstack([dg, dt])

    def pad(c):
        return {"type": c["type"], "fun": lambda y: c["fun"](y[:n]),
                "jac": lambda y: np.hstack([c["jac"](y[:n]), np.zeros((c["jac"](y[:n]).shape[0],
                                                                        1))])}

    cons = [{"type": "eq", "fun": lambda y: np.array([ev(y[:n] * sc).mass_kg / m0 - 1.0]),
             "jac": lambda y: np.append(ev(y[:n] * sc).d_mass * sc / m0, 0.0)[None, :]},
            {"type": "ineq", "fun": lambda y: rows(y)[0], "jac": lambda y: rows(y)[1]}]
    cons += [pad(c) for c in smoothness_constraints(ev.paths, sc, ev.problem.table_max_step_m)]
    t0 = float(np.min(ev(xb).margins))
    bounds = [(v.lower / x, v.upper / x) for v, x in zip(ev.problem.variables, sc)]
    return (lambda y: (-y[n], -np.eye(n + 1)[n]), cons, np.append(xb / sc, t0),
            bounds + [(None, None)])


def optimise(case: Case, problem: DesignProblem, check_gradients: bool = True,
             progress=None, evaluator: Evaluator | None = None) -> DesignResult:
    """Minimise the mass subject to the flutter margin (``objective = "mass"``), or maximise the
    smallest envelope flutter margin at the baseline's mass (``"flutter_speed"``,
    :func:`_flutter_speed_problem`), with SLSQP and the analytic gradients; variables scaled by
    their baseline values; the other constraints (module docstring) in both.

    Parameters
    ----------
    case : the case; problem : its :class:`DesignProblem`;
    check_gradients : compare the analytic gradients with central differences at the baseline;
    progress : optional callable ``progress(dict)`` called once per iteration (a history row);
    evaluator : an :class:`Evaluator` of this case and problem to reuse (its memoised
        evaluations and aerodynamic operators), default a new one.

    Returns
    -------
    :class:`DesignResult` with the constraint activity at the optimum.
    """
    from scipy.optimize import minimize
    t0 = time.perf_counter()
    ev = Evaluator(case, problem) if evaluator is None else evaluator
    x0 = np.array([case_value(case, p) for p in ev.paths])
    check, t_check = None, 0.0
    if check_gradients:
        tc = time.perf_counter()
        check = gradient_check(ev, x0, ev.problem.gradient_step)
        t_check = time.perf_counter() - tc
    m0 = ev(x0).mass_kg
    history = []
    n = x0.size
    sc = variable_scales(ev.problem, x0)

    def record(y):
        e = ev(y[:n] * sc)
        row = {"iteration": len(history) + 1, "values": (y[:n] * sc).tolist(),
               "mass_kg": e.mass_kg, "min_margin_pct": float(np.nanmin(e.margins) * 100)}
        history.append(row)
        if progress is not None:
            progress(row)

    speed = ev.problem.objective == "flutter_speed"
    obj, constraints, y0, bounds = (_flutter_speed_problem if speed else _mass_problem)(ev, sc, m0,
                                                                                        x0)
    res = minimize(obj, y0, jac=True, method="SLSQP", bounds=bounds, constraints=constraints,
                   options={"maxiter": problem.max_iterations, "ftol": 1e-6 if not speed
                            else 1e-9}, callback=record)
    variables = ev.problem.variables
    x = np.clip(res.x[:n] * sc, [v.lower for v in variables], [v.upper for v in variables])
    opt = ev(x)
    activity = constraint_activity(ev, opt, res.get("multipliers"),
                                   float(res.x[n]) if speed else None, m0)
    return DesignResult(paths=ev.paths, baseline=ev(x0), optimised=opt, history=tuple(history),
                        success=bool(res.success), message=str(res.message),
                        evaluations=ev.calls, seconds=time.perf_counter() - t0,
                        gradient_check=check, gradient_check_seconds=t_check,
                        constraints=activity)


# ---------------------------------------------------------------------------------------------
# the ASE loop's margins and their derivatives (issue 28, design.phase_margin_deg /
# design.gain_margin_db)
# ---------------------------------------------------------------------------------------------
# The ASE loop's gain and phase margins and their design derivatives for a case (issue 28).
#
# The chain of :mod:`asekit.case.design` (plate matrices and their derivatives, the elastic modes
# of the shaft-supported fin with the transmission held, FN1, and Nelson's mode-shape derivatives)
# is extended by the rigid pitch mode r (unit nose-up rotation about the shaft, the FN2 model's
# first mode, independent of thickness, material and masses) to the modal basis [r, Phi] of the
# aeroservoelastic model:
#
#     M_a = [r, Phi]^T M [r, Phi],   K_a = diag(0, Lambda),                                  (1)
#
# (the rigid rotation strains neither plate nor shaft spring; the elastic modes are
# mass-normalised, Phi^T M Phi = I). Its derivatives follow from Nelson's dPhi, dLambda
# (:func:`asekit.aeroelastic.sensitivity.modal_matrix_derivative`, dr = 0), the GAF derivatives
# dQ from the extended mode table [r, Phi, 0, dPhi_j] through the case's boxes and the DLM
# operators at the actuator's Mach (:func:`asekit.aeroelastic.sensitivity.gaf_derivative`), the
# Roger coefficients' derivatives dA_j = fit(dQ) (:func:`asekit.rfa.roger.roger_fit_derivative`)
# and the AEM1 loop's dF and margins (:mod:`asekit.ase.loop_sensitivity`).
#
# This modal basis is the "held-transmission elastic modes + rigid attachment mode" form of the
# thesis's Eq. (2.60); the case pipeline's FN2 model (fictitious-mass method) gives elastic modes
# that differ from these by O(J_fin / I_f) (:mod:`asekit.case.design`), so the margins here agree
# with :func:`asekit.case.pipeline.ase`'s to that order, not to round-off. Undamped structures
# (no ``[damping]``), shaft supports with a rigid mode (FN2, ``modes.keep_rigid``), Roger fits.


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


def _ase_modal(case: Case, paths, n_elastic: int, rigid: np.ndarray):
    """M_a, K_a (Eq. 1), their derivatives, and the mode tables [r, Phi] and derivatives."""
    mesh = P.structural_mesh(case)
    K, M = P.mass_and_stiffness(case)
    parts = element_parts(mesh, case.material)
    ev = types.SimpleNamespace(paths=tuple(paths))
    dK, dM, _, _ = _matrix_derivatives(ev, case, mesh, parts, K, M)
    system = _system(case, mesh, K, M)
    lam, q = _elastic_modes(system, M, n_elastic)
    dKr = [reduce(system.T, a) for a in dK]
    for j, path in enumerate(paths):
        extra = _support_derivative(system, path)
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


def _ase_aero_operators(case: Case, mach: float):
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
        case = with_values(case, paths, values)
    values = np.array([case_value(case, p) for p in paths])
    act, ctl, _ = P.actuator_setup(case)
    a = case.actuator
    ops = _ase_aero_operators(case, a.mach) if operators is None else operators
    n_el = base.frequencies_hz.size - 1
    rigid = np.asarray(base.shapes)[:, :, 0]        # unit pitch about the shaft, (n_nodes, 3)
    mesh, Ma, Ka, dMa, dKa, shapes, dshapes = _ase_modal(case, paths, n_el, rigid)
    n = n_el + 1
    Q = _gafs(types.SimpleNamespace(case=case, operators=ops), mesh,
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
