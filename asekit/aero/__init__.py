"""Aerodynamics of lifting surfaces (thesis Sections 2.2 and 3.2).

- :mod:`asekit.aero.boxes`: trapezoidal surfaces, box meshes and the DLM mesh rules.
- :mod:`asekit.aero.control_surface`: hinged control surfaces: hinge-aligned boxes, the
  deflection normalwash, hinge moments and steady control derivatives.
- :mod:`asekit.aero.vlm`: steady vortex lattice with Prandtl-Glauert compressibility.
- :mod:`asekit.aero.dlm`: subsonic doublet-lattice method (parabolic and quartic kernels).
- :mod:`asekit.aero.spline`: structure -> aero interpolation and the force transpose.
- :mod:`asekit.aero.gaf`: generalised aerodynamic forces and the fin's cached GAF database.
- :mod:`asekit.aero.gust`: the gust normalwash and the gust GAF column Q_hg(M, k).

Conventions: x downstream, y span, z up; e^{i omega t}; k = omega b / U with the reference
semi-chord b stated by the caller (the fin: root semi-chord 0.078 m); Delta Cp > 0 pushes a box
along its normal (+z); normalwash w/U = dh/dx + i k h / b.
"""

from asekit.aero.boxes import (
                               BoxMesh,
                               MeshRuleReport,
                               MeshRuleWarning,
                               TrapezoidSurface,
                               check_mesh_rules,
                               mesh_surfaces,
)
from asekit.aero.dlm import (
                               AicFactor,
                               aic_matrix,
                               factor_aic,
                               factor_normalwash_matrix,
                               iter_normalwash_matrices,
                               map_normalwash_matrices,
                               normalwash_matrices,
                               normalwash_matrix,
                               pressure_jump,
)
from asekit.aero.vlm import lift_curve_slope, steady_pressure, vlm_normalwash_matrix

__all__ = ["BoxMesh", "MeshRuleReport", "MeshRuleWarning", "TrapezoidSurface", "check_mesh_rules",
           "mesh_surfaces", "aic_matrix", "normalwash_matrices", "AicFactor", "factor_aic",
           "factor_normalwash_matrix", "iter_normalwash_matrices", "map_normalwash_matrices",
           "normalwash_matrix", "pressure_jump", "lift_curve_slope", "steady_pressure",
           "vlm_normalwash_matrix"]
