"""Structural finite-element model of a lifting surface (thesis Ch. 2.1, 3.1).

mesh (structured quadrilateral meshes) -> plate (MITC4 element) -> assembly (sparse K, M,
supports) -> modes (eigen-analysis, mode selection, the modal model); beam (3-D Euler-Bernoulli
stick models clamped at the root, their modes).
"""

from asekit.structure.modes import ModalModel, mode_shapes_at

__all__ = ["ModalModel", "mode_shapes_at"]
