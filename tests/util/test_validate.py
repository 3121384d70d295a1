"""asekit.util.validate: the shared argument checks (issue 22: strict types, no silent NaN)."""

import math

import numpy as np
import pytest

from asekit.util.validate import (
    NonFiniteResultError,
    finite_array,
    finite_result,
    in_range,
    integer,
    positive,
    positive_array,
    real,
    real_array,
)


@pytest.mark.parametrize("value", [3, np.int64(3), np.uint8(3)])
def test_integer_accepts_python_and_numpy_integers(value):
    assert integer("n", value, low=1) == 3 and type(integer("n", value)) is int


@pytest.mark.parametrize("value", [4.5, 4.0, np.float64(4.0), True, np.bool_(True), "4", None,
                                   4 + 0j])
def test_integer_refuses_non_integers_naming_the_argument(value):
    with pytest.raises(TypeError, match=r"n_states must be an integer >= 1, got"):
        integer("n_states", value, low=1)


def test_integer_range_names_the_bounds():
    with pytest.raises(ValueError, match=r"n must be an integer in \[2, 10\], got 11"):
        integer("n", 11, low=2, high=10)
    with pytest.raises(ValueError, match=r"n must be an integer <= 10, got 11"):
        integer("n", 11, high=10)


@pytest.mark.parametrize("value, error", [("1.0", ValueError), (1 + 0j, TypeError),
                                          (np.complex128(1 + 2j), TypeError), (True, TypeError),
                                          (None, TypeError)])
def test_real_refuses_strings_complex_bools(value, error):
    with pytest.raises(error, match="b_ref must be a real number"):
        real("b_ref", value)


def test_real_accepts_numpy_reals_and_keeps_non_finite():
    assert real("x", np.float32(0.5)) == 0.5 and math.isnan(real("x", math.nan))


def test_real_array_refuses_what_numpy_coerces_silently():
    with pytest.raises(TypeError, match=r"k must be real numbers, got the complex value "
                                        r"\(1\+0\.5j\) at k\[2\]"):
        real_array("k", np.array([0.0, 0.5, 1.0 + 0.5j]))
    with pytest.raises(TypeError, match=r"at altitude\[0, 1\]"):
        real_array("altitude", np.array([[1.0, 2.0 + 1j]]))
    with pytest.raises(ValueError, match="altitude must be real numbers, got the string"):
        real_array("altitude", "1000")
    with pytest.raises(ValueError, match="altitude must be real numbers, got strings"):
        real_array("altitude", ["1000", "2000"])
    for bad in ([1.0, None], [True, False], np.array([True])):
        with pytest.raises(TypeError, match="x must be real numbers"):
            real_array("x", bad)


def test_real_array_accepts_ints_reals_and_a_zero_imaginary_part():
    np.testing.assert_array_equal(real_array("x", [1, 2]), [1.0, 2.0])
    np.testing.assert_array_equal(real_array("x", np.array([1.0 + 0j, 2.0])), [1.0, 2.0])
    assert real_array("x", np.float32(3.0)).dtype == float


def test_finite_array_names_the_first_bad_entry():
    a = np.zeros((2, 3))
    a[1, 2] = math.inf
    with pytest.raises(ValueError, match=r"A must be finite, got A\[1, 2\] = inf \(1 non-finite "
                                         r"of 6\)"):
        finite_array("A", a)
    q = np.ones((2, 2), complex)
    q[0, 1] = complex(0, math.nan)
    with pytest.raises(ValueError, match=r"Q\[0, 1\]"):
        finite_array("Q", q, complex_values=True)
    with pytest.raises(ValueError, match="Q must be numbers, got the string"):
        finite_array("Q", "1", complex_values=True)
    with pytest.raises(TypeError, match="Q must be numbers"):
        finite_array("Q", [None, 1.0], complex_values=True)


def test_finite_result_is_a_value_error_naming_the_cause():
    assert finite_result("x", [1.0], "hint") == [1.0]
    with pytest.raises(NonFiniteResultError, match=r"the step response is not finite \(1 of 2 "
                                                   r"entries\): shorten t_final"):
        finite_result("the step response", np.array([1.0, math.nan]), "shorten t_final")
    assert issubclass(NonFiniteResultError, ValueError)


def test_positive_array_refuses_complex_velocities():
    """Issue 22: ``velocities`` with an imaginary part were cast to float silently."""
    with pytest.raises(TypeError, match=r"velocities\[1\]"):
        positive_array("velocities", np.array([10.0, 20.0 + 1j]))
    with pytest.raises(ValueError, match="velocities"):
        positive_array("velocities", ["10", "20"])


def test_existing_scalar_checks_refuse_strings_and_complex():
    with pytest.raises(ValueError, match="the string"):
        positive("b_ref", "1.0")
    with pytest.raises(TypeError, match="rho must be a real number"):
        in_range("rho", np.complex128(1.2 + 1j))


def test_type_refusals_are_value_errors_too():
    """Project convention: every user-input error is a ValueError subclass; a wrong type is
    also a TypeError (ArgumentTypeError), so both ``except`` clauses catch it."""
    from asekit.util.validate import ArgumentTypeError
    for call in (lambda: integer("n", 2.5), lambda: real("x", 1j),
                 lambda: real_array("k", [1j]), lambda: finite_array("Q", [None], True)):
        with pytest.raises(ArgumentTypeError) as info:
            call()
        assert isinstance(info.value, ValueError) and isinstance(info.value, TypeError)
