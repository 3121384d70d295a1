"""Aerodynamics of lifting surfaces: boxes and mesh rules, the steady vortex-lattice method,
the subsonic doublet-lattice method, structure-to-aero splines and generalised aerodynamic
forces (thesis Sections 2.2 and 3.2)."""
