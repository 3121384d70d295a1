"""Aeroelastic models: the modal state space (Eq. 2.63), flutter methods, the typical
section and nonlinear connections (freeplay)."""
