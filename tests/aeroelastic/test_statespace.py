"""asekit.aeroelastic.statespace: refusals of non-finite inputs and outputs (issue 22). The
equations themselves are tested in tests/aeroelastic/test_aeroelastic.py."""

import dataclasses
import math

import numpy as np
import pytest
from property_targets import two_dof_coalescence

from asekit.aeroelastic.statespace import aeroelastic_matrices


class _DuckFit:
    """A fit-like object (duck-typed: A, b_ref, n_lags, lag_realization) that no dataclass
    check guards, so that aeroelastic_matrices' own checks are exercised."""

    def __init__(self, fit, A=None, roots=None, b_ref=None):
        self._fit, self.A = fit, fit.A if A is None else A
        self.b_ref = fit.b_ref if b_ref is None else b_ref
        self.n_lags, self._roots = fit.n_lags, roots

    def lag_realization(self, n_rigid):
        D, E, roots, names = self._fit.lag_realization(n_rigid)
        return D, E, roots if self._roots is None else self._roots, names


def test_roger_fit_holding_nan_gives_a_named_error_not_nan_matrices():
    """Issue 22's reproducer: aeroelastic_matrices returned NaN matrices from a Roger fit
    holding NaN. A RogerFit refuses NaN at construction; a duck-typed fit is refused by the
    builder, naming rfa.A and the entry."""
    modal, _, fit = two_dof_coalescence(1.0)
    A = fit.A.copy()
    A[0, 1, 0] = math.nan
    with pytest.raises(ValueError, match=r"A must be finite, got A\[0, 1, 0\] = nan"):
        dataclasses.replace(fit, A=A)
    with pytest.raises(ValueError, match=r"rfa\.A must be finite, got rfa\.A\[0, 1, 0\] = nan"):
        aeroelastic_matrices(modal, _DuckFit(fit, A=A), 1.2, 50.0)


def test_non_finite_lag_roots_and_b_ref_are_refused():
    modal, _, fit = two_dof_coalescence(1.0)
    fit1 = dataclasses.replace(fit, A=np.concatenate([fit.A, 0.1 * fit.A[:1]]),
                               lag_roots=np.array([0.5]))
    with pytest.raises(ValueError, match="rfa.lag_roots must be finite"):
        aeroelastic_matrices(modal, _DuckFit(fit1, roots=np.full(2, math.inf)), 1.2, 50.0)
    with pytest.raises(ValueError, match="rfa.b_ref must be a finite number > 0"):
        aeroelastic_matrices(modal, _DuckFit(fit1, b_ref=math.nan), 1.2, 50.0)


def test_overflowing_dynamic_pressure_is_named():
    """rho U^2 / 2 = inf for U = 1e300 was an OverflowError of Python's float power."""
    modal, _, fit = two_dof_coalescence(1.0)
    with pytest.raises(ValueError, match=r"rho = 1\.2 and velocity = 1e\+300 give an infinite "
                                         "dynamic pressure"):
        aeroelastic_matrices(modal, fit, 1.2, 1e300)


@pytest.mark.filterwarnings("ignore:overflow:RuntimeWarning")
@pytest.mark.filterwarnings("ignore:invalid value:RuntimeWarning")
def test_overflowing_matrices_are_refused_as_non_finite_results():
    """q finite but q A0 / M overflows: the result check names rho and velocity."""
    from asekit.util.validate import NonFiniteResultError
    modal, _, fit = two_dof_coalescence(1.0)
    big = dataclasses.replace(fit, A=fit.A * 1e300)
    with pytest.raises(NonFiniteResultError, match=r"aeroelastic A_sys is not finite.*rho = "):
        aeroelastic_matrices(modal, big, 1.2, 1e10)


def test_singular_apparent_mass_is_named():
    """M - rho b^2 / 2 A2 = 0 (A2 = 2 M / (rho b^2)) was a bare LinAlgError."""
    modal, _, fit = two_dof_coalescence(1.0)
    A = fit.A.copy()
    A[2] = 2.0 * np.eye(2) / 1.2
    with pytest.raises(ValueError, match=r"M - rho b\^2 / 2 A2 is singular at rho = 1\.2"):
        aeroelastic_matrices(modal, dataclasses.replace(fit, A=A), 1.2, 50.0)


@pytest.mark.parametrize("kw, word, error", [
    ({"velocity": np.complex128(50 + 1j)}, "velocity must be a real number", TypeError),
    ({"rho": "1.2"}, "rho must be a real number", ValueError),
])
def test_strict_types(kw, word, error):
    modal, _, fit = two_dof_coalescence(1.0)
    a = {"rho": 1.2, "velocity": 50.0} | kw
    with pytest.raises(error, match=word):
        aeroelastic_matrices(modal, fit, a["rho"], a["velocity"])


def test_valid_fit_gives_finite_matrices():
    """The 2-dof quasi-steady model: no lag, A_sys = [[0, I], [-(K - q A0), 0]] with M = I."""
    modal, _, fit = two_dof_coalescence(0.0)
    m = aeroelastic_matrices(modal, fit, 1.2, 50.0)
    q = 0.5 * 1.2 * 50.0 ** 2
    np.testing.assert_allclose(m.A[2:, :2], -(modal.K - q * fit.A[0]))
