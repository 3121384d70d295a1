"""Rational function approximations of tabulated generalized aerodynamic forces.

Two fits behind one interface (``evaluate(k)``, ``evaluate_laplace(s, U)``, ``A`` holding
A0, A1, A2 in front, ``lag_realization()``, ``fit_error``, ``b_ref``):

* :mod:`asekit.rfa.roger` -- Roger's fit (thesis Sec. 2.2.1.4, Eqs. 2.13-2.24), N lag terms
  per element, N n aerodynamic states for n modes;
* :mod:`asekit.rfa.minimum_state` -- the minimum-state fit of Karpel (1982) by the iterative
  least squares of Tiffany & Adams (1988), n_L lag states shared by all elements.

The gust column Q_hg of :mod:`asekit.aero.gust` has its own Roger fit, :mod:`asekit.rfa.gust`
(one lag state per lag root, shared by the modes; :mod:`asekit.aeroelastic.gust` uses it).

The aeroelastic state space (:mod:`asekit.aeroelastic.statespace`), the root locus and the ASE loop take
either.
"""

from asekit.rfa.minimum_state import (
                                      MinimumStateFit,
                                      default_ms_roots,
                                      minimum_state_fit,
                                      minimum_state_fit_database,
                                      reduced_frequency_weights,
)
from asekit.rfa.roger import (
    RogerFit,
    default_lag_roots,
    design_rows,
    roger_fit,
    roger_fit_database,
    roger_fit_derivative,
)

__all__ = ["RogerFit", "MinimumStateFit", "default_lag_roots", "default_ms_roots",
           "design_rows", "roger_fit", "roger_fit_database", "roger_fit_derivative",
           "minimum_state_fit", "minimum_state_fit_database", "reduced_frequency_weights"]
