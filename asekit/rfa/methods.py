"""The rational function approximations, one registry (:data:`RFA_FITS`): the case layer's
``[flutter] rfa`` key, the pipeline's ASE loop and root-locus flutter, and the sweeps pick a
fit here by name.

Adding a fit: write it in its own module of :mod:`asekit.rfa` with the common interface
(``evaluate(k)``, ``evaluate_laplace(s, U)``, ``A``, ``lag_realization()``, ``fit_error``,
``b_ref``; see :mod:`asekit.rfa`), then add one :class:`RfaKind` entry below. Nothing else
changes: the schema's check, the pipeline and ``docs/case-format.md``'s list read this table.

Examples
--------
>>> sorted(RFA_FITS)
['minimum_state', 'roger']
>>> rfa_kind("pade")
Traceback (most recent call last):
...
ValueError: flutter.rfa must be one of ['minimum_state', 'roger'], got 'pade'
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from asekit.rfa.minimum_state import minimum_state_fit
from asekit.rfa.roger import roger_fit


@dataclass(frozen=True)
class RfaKind:
    """One rational function approximation.

    Attributes
    ----------
    name : its registry key; description : one line for docs and errors;
    fit : ``fit(k, Q, b_ref, mach, lags) -> RFA`` on tabulated GAFs Q (n_k, n, n) at the reduced
        frequencies k (k = omega b_ref / U, b_ref in m), ``lags`` the number of lag roots (Roger:
        per element, N n aerodynamic states; minimum state: shared, n_L states).
    """

    name: str
    description: str
    fit: Callable


def _roger(k, Q, b_ref, mach, lags):
    return roger_fit(k, Q, b_ref, n_lags=lags, mach=mach)


def _minimum_state(k, Q, b_ref, mach, lags):
    return minimum_state_fit(k, Q, b_ref, n_states=lags, mach=mach)


#: name -> :class:`RfaKind`.
RFA_FITS: dict[str, RfaKind] = {
    "roger": RfaKind("roger", "Roger's fit, lag terms per element (thesis Eqs. 2.13-2.24)",
                     _roger),
    "minimum_state": RfaKind("minimum_state", "Karpel's minimum-state fit, lag states shared "
                             "by all elements (Tiffany & Adams 1988)", _minimum_state),
}


def rfa_kind(name: str, where: str = "flutter.rfa") -> RfaKind:
    """The registered fit ``name``; a ValueError naming ``where`` (the key path) and the known
    fits otherwise."""
    try:
        return RFA_FITS[name]
    except (KeyError, TypeError):
        raise ValueError(f"{where} must be one of {sorted(RFA_FITS)}, got {name!r}") from None
