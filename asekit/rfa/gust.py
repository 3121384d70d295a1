"""Roger's rational approximation of the gust GAF column (issue 27).

The gust column Q_hg(M, k) (n_k, n) of :mod:`asekit.aero.gust` (per unit dynamic pressure and
unit gust angle W/U) is fitted column-wise in the form of thesis Eq. (2.13), with the same lag
roots beta_n as the modal columns:

    Q~_g(k) = A0g + (ik) A1g + (ik)^2 A2g + sum_n (ik) A_{g,n+2} / (ik + beta_n),

i.e. in the Laplace domain (p = s b / U, thesis Eq. 2.28)

    Q~_g(s) = A0g + (s b/U) A1g + (s b/U)^2 A2g + sum_n s A_{g,n+2} / (s + (U/b) beta_n),

so that the modal gust force is F = q Q~_g(s) w_g(s) / U. The A1g and A2g terms multiply the
gust's first and second time derivatives (the state space of :mod:`asekit.aeroelastic.gust`
takes w_g, dw_g/dt and d2w_g/dt2 as inputs); ``quasi_steady_terms=1`` drops A2g and
``quasi_steady_terms=0`` drops A1g too (a gust input without derivatives). The lag terms need
one state per lag root, shared by all modes (the gust is one scalar input).

The fit is the linear least-squares problem of Eqs. (2.17)-(2.24) (the same design rows,
:func:`asekit.rfa.roger.design_rows`); ``constrain_k0`` passes the fit through the real part
of the lowest-k data exactly (Tiffany & Adams, NASA TP-2776, 1988). The indicial (sharp-edged
gust) response of the fit, for s' = U t / b > 0, is A0g + sum_n A_{g,n+2} exp(-beta_n s')
(the inverse Laplace transform of Q~_g / p without the impulses of A1g, A2g at s' = 0): with
the gust referred to the leading edge of a 2-D plate it approximates Kussner's function
(R. T. Jones, "The unsteady lift of a wing of finite aspect ratio", NACA Rep. 681, 1940:
psi(s) = 1 - 0.5 exp(-0.13 s) - 0.5 exp(-s) is itself such a fit).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from asekit.rfa.roger import check_coefficients, default_lag_roots, design_rows
from asekit.util.validate import finite_array, integer, positive, real_array


@dataclass(frozen=True)
class GustFit:
    """A Roger fit of one Mach's gust column.

    Attributes
    ----------
    A : (N + 3, n) real coefficients A0g, A1g, A2g, A_{g,3}..A_{g,N+2}.
    lag_roots : (N,) beta_n > 0; b_ref : reference semi-chord of k (m);
    k : (n_k,) fitted reduced frequencies; Qg : (n_k, n) complex data;
    fit_error : ||Qg - Q~g||_F / ||Qg||_F over all k and modes; mach : informational.
    """

    A: np.ndarray
    lag_roots: np.ndarray
    b_ref: float
    k: np.ndarray
    Qg: np.ndarray
    fit_error: float = 0.0
    mach: float | None = None

    def __post_init__(self):
        check_coefficients(self, ("A",))
        if self.A.ndim != 2 or self.A.shape[0] != 3 + self.lag_roots.size:
            raise ValueError(f"A must be (N + 3, n) = ({3 + self.lag_roots.size}, n), got "
                             f"{self.A.shape}")

    @property
    def n_lags(self) -> int:
        return int(self.lag_roots.size)

    @property
    def n_modes(self) -> int:
        return int(self.A.shape[1])

    def evaluate(self, k) -> np.ndarray:
        """Q~g at reduced frequencies ``k``: (n,) or (len(k), n) complex.

        Examples
        --------
        >>> f = GustFit(np.array([[1.0], [0.0], [0.0], [-0.5]]), np.array([0.13]), 0.5,
        ...             np.array([0.0, 1.0]), np.ones((2, 1)))
        >>> complex(np.round(f.evaluate(0.0)[0], 12))
        (1+0j)
        """
        k_arr = np.atleast_1d(real_array("k", k))
        ik = 1j * k_arr
        basis = np.stack([np.ones_like(ik), ik, ik ** 2]
                         + [ik / (ik + b) for b in self.lag_roots], axis=1)
        out = basis @ self.A
        return out[0] if np.ndim(k) == 0 else out

    def indicial(self, s) -> np.ndarray:
        """Sharp-edged-gust response of the fit at reduced times s' = U t / b > 0 (the gust
        front at the reference station at s' = 0): A0g + sum_n A_{g,n+2} exp(-beta_n s'),
        (len(s), n) per unit q and W/U (module docstring; the impulses of A1g, A2g at s' = 0
        are left out).

        Examples
        --------
        >>> f = GustFit(np.array([[1.0], [0.0], [0.0], [-0.5], [-0.5]]),
        ...             np.array([0.13, 1.0]), 0.5, np.array([0.0, 1.0]), np.ones((2, 1)))
        >>> float(np.round(f.indicial([0.0])[0, 0], 12))     # Jones's psi(0)
        0.0
        """
        s_arr = np.atleast_1d(real_array("s", s))
        basis = np.column_stack([np.ones_like(s_arr)]
                                + [np.exp(-b * s_arr) for b in self.lag_roots])
        return basis @ self.A[[0, *range(3, self.A.shape[0])]]


def gust_fit(k, Qg, b_ref: float, lag_roots=None, n_lags: int = 4,
             quasi_steady_terms: int = 2, constrain_k0: bool = False,
             mach: float | None = None) -> GustFit:
    """Least-squares Roger fit of a gust column (module docstring; thesis Eqs. 2.13-2.24).

    Parameters
    ----------
    k : (n_k,) reduced frequencies, ascending, >= 0.
    Qg : (n_k, n) complex gust column (per unit q and unit W/U).
    b_ref : reference semi-chord (m) > 0.
    lag_roots : (N,) beta_n > 0, those of the modal fit (``RogerFit.lag_roots``); default
        :func:`asekit.rfa.roger.default_lag_roots` (k_max, ``n_lags``).
    quasi_steady_terms : 2 (A0g, A1g, A2g), 1 (A0g, A1g; A2g = 0) or 0 (A0g only).
    constrain_k0 : match Re Qg at the lowest k exactly.
    mach : informational.

    Returns
    -------
    :class:`GustFit`

    Examples
    --------
    >>> import numpy as np
    >>> k = np.linspace(0.0, 2.0, 9)
    >>> q = (1 - 0.5j * k / (1j * k + 0.13) - 0.5j * k / (1j * k + 1.0))[:, None]   # Jones
    >>> f = gust_fit(k, q, 0.5, lag_roots=[0.13, 1.0], quasi_steady_terms=0)
    >>> np.round(f.A[:, 0], 9) + 0.0
    array([ 1. ,  0. ,  0. , -0.5, -0.5])
    """
    positive("b_ref", b_ref)
    k = finite_array("k", k)
    qg = finite_array("Qg", Qg, complex_values=True)
    if qg.ndim == 1:
        qg = qg[:, None]
    if k.ndim != 1 or qg.ndim != 2 or qg.shape[0] != k.size:
        raise ValueError(f"Qg must be (n_k, n) with n_k = len(k) = {k.size}; got {qg.shape}")
    if k.size < 2 or np.any(k < 0) or np.any(np.diff(k) <= 0):
        raise ValueError(f"k must be >= 0 and strictly ascending, got {k}")
    nq = integer("quasi_steady_terms", quasi_steady_terms, low=0, high=2)
    if lag_roots is None:
        lag_roots = default_lag_roots(float(k.max()), integer("n_lags", n_lags, low=0))
    roots = np.atleast_1d(finite_array("lag_roots", lag_roots))
    if np.any(roots <= 0):
        raise ValueError(f"lag_roots must all be > 0, got {roots}")
    kr, ki = design_rows(k, roots)
    cols = [0, *range(1, 1 + nq), *range(3, 3 + roots.size)]
    G = np.vstack([kr[:, cols], ki[:, cols]])
    if 2 * k.size < len(cols):
        raise ValueError(f"k has {k.size} points, fewer than the {len(cols)} coefficients "
                         "(2 n_k >= coefficients); give more k points or fewer lag_roots")
    rhs = np.vstack([qg.real, qg.imag])
    if constrain_k0:
        C = kr[:1, cols]
        kkt = np.block([[G.T @ G, C.T], [C, np.zeros((1, 1))]])
        coef = np.linalg.lstsq(kkt, np.vstack([G.T @ rhs, qg[:1].real]), rcond=None)[0]
        coef = coef[:len(cols)]
    else:
        coef = np.linalg.lstsq(G, rhs, rcond=None)[0]
    A = np.zeros((3 + roots.size, qg.shape[1]))
    A[cols] = coef
    fit = GustFit(A, roots, float(b_ref), k, qg, 0.0, mach)
    err = float(np.linalg.norm(fit.evaluate(k) - qg) / max(np.linalg.norm(qg), 1e-300))
    return GustFit(A, roots, float(b_ref), k, qg, err, mach)
