"""The flutter methods, one registry (:data:`FLUTTER_METHODS`): the case layer's
``[flutter] method`` key and the pipeline pick a method here by name.

Every method answers the same question on the same inputs -- the roots of the aeroelastic
system over an airspeed sweep at one density and Mach, and the instabilities they cross into --
so the pipeline, the report and the sweeps treat them alike:

- ``"pk"``: the p-k method with mode tracking on the tabulated GAFs (thesis Eq. 3.12,
  :func:`asekit.aeroelastic.flutter.pk_flutter`);
- ``"nastran_pk"``, ``"k"``, ``"ke"``: MSC Nastran's PK, K and KE methods with Nastran's
  damping definitions (:mod:`asekit.aeroelastic.nastran`; docs/nastran-flutter.md); PKNL's
  matched flight points are a FLUTTER card's, run by :func:`asekit.io.bdf.deck_flutter`;
- ``"root_locus"``: eigenvalues of the state-space system A_sys (thesis Eq. 2.63) on a rational
  function approximation of the GAFs (:func:`asekit.aeroelastic.flutter.root_locus`).

Adding a method: a function ``solve(modal, gaf, rfa, density, velocities) -> (roots,
instabilities)`` (``roots`` a :class:`~asekit.aeroelastic.flutter.PkResult`, whose ``p`` holds
one tracked root per column) and one :class:`FlutterMethod` entry below.

Examples
--------
>>> sorted(FLUTTER_METHODS)
['k', 'ke', 'nastran_pk', 'pk', 'root_locus']
>>> flutter_method("root_locus").needs_rfa
True
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from asekit.aeroelastic.flutter import (
    PkResult,
    pk_flutter,
    pk_instabilities,
    root_locus,
    root_locus_instabilities,
)
from asekit.aeroelastic.nastran import solve_k, solve_ke, solve_pk


@dataclass(frozen=True)
class FlutterMethod:
    """One flutter method: ``name`` (registry key), ``description`` (one line), ``needs_rfa``
    (True: ``solve`` uses a rational function approximation, built by the caller) and
    ``solve(modal, gaf, rfa, density, velocities) -> (PkResult, list[Instability])``."""

    name: str
    description: str
    needs_rfa: bool
    solve: Callable


def _pk(modal, gaf, rfa, density, velocities):
    roots = pk_flutter(modal, gaf, density, velocities)
    return roots, pk_instabilities(roots, modal, gaf)


def _root_locus(modal, gaf, rfa, density, velocities):
    result = root_locus(modal, rfa, density, velocities)
    lam = result.elastic                                   # (n_v, n_s) tracked roots, 1/s
    U = np.asarray(result.velocities, float)
    n_v, n_s = lam.shape
    roots = PkResult(velocities=U, p=lam, k=np.abs(lam.imag) * rfa.b_ref / U[:, None],
                     vectors=np.zeros((n_v, n_s, 0), complex),
                     converged=np.ones((n_v, n_s), bool),
                     structural_frequencies_hz=np.abs(lam[0].imag) / (2 * np.pi),
                     density=float(result.density), mach=getattr(rfa, "mach", None),
                     b_ref=float(rfa.b_ref))
    return roots, root_locus_instabilities(result, modal, rfa)


#: name -> :class:`FlutterMethod`.
FLUTTER_METHODS: dict[str, FlutterMethod] = {
    "pk": FlutterMethod("pk", "p-k with mode tracking on the tabulated GAFs (Eq. 3.12)",
                        False, _pk),
    "nastran_pk": FlutterMethod("nastran_pk", "MSC Nastran's PK: k iterated per mode to EPS "
                                "1e-3, g = 2 Re p / |Im p|, no continuation", False, solve_pk),
    "k": FlutterMethod("k", "MSC Nastran's K method: the structural damping g that makes "
                       "harmonic motion possible, V = omega b / k", False, solve_k),
    "ke": FlutterMethod("ke", "MSC Nastran's KE: the K method, eigenvalues only", False,
                        solve_ke),
    "root_locus": FlutterMethod("root_locus", "eigenvalues of the RFA state space (Eq. 2.63)",
                                True, _root_locus),
}


def flutter_method(name: str, where: str = "flutter.method") -> FlutterMethod:
    """The registered method ``name``; a ValueError naming ``where`` (the key path) and the
    known methods otherwise."""
    try:
        return FLUTTER_METHODS[name]
    except (KeyError, TypeError):
        raise ValueError(f"{where} must be one of {sorted(FLUTTER_METHODS)}, got "
                         f"{name!r}") from None
