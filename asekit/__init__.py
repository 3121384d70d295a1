"""asekit: an open Python workbench for the aeroservoelastic modelling of all-movable fins.

The package follows the chapters of the reference thesis (Nalci 2013, "Aeroservoelastic
Modeling of a Missile Control Fin"): structure -> aerodynamics -> rational function
approximation -> aeroelastic state space -> flutter -> servo-actuator -> aeroservoelastic loop.
SI units everywhere inside the package; degrees and Hz only at the edges (plots, tables).
"""

__version__ = "0.1.0"
