"""The parameter checks: a number or an integer in its range, or one line naming it and the range."""

import numpy as np
import pytest

from agents.parameters import check_integer, check_parameter


@pytest.mark.parametrize(
    ("value", "low", "high", "low_open", "message"),
    [
        ("1e-3", 0, 1, False, "c must be a number in [0, 1], got '1e-3' (text: YAML reads an exponent"),
        ("fast", 0, 1, False, "c must be a number in [0, 1], got 'fast'"),
        (True, 0, 1, False, "c must be a number in [0, 1], got True"),
        (float("inf"), 0, np.inf, False, "c must be a finite number in [0, inf), got inf"),
        (0.0, 0, 1, True, "c must be in (0, 1], got 0.0"),
        (1.5, 0, 1, False, "c must be in [0, 1], got 1.5"),
    ],
)
def test_a_parameter_outside_its_range_is_named_with_the_range(value, low, high, low_open, message):
    with pytest.raises(ValueError) as error:
        check_parameter("c", value, low, high, low_open)
    assert str(error.value).startswith(message) and "\n" not in str(error.value)


@pytest.mark.parametrize("value", [0.0, 0.5, 1, np.float32(1.0), np.int64(0)])
def test_a_parameter_in_its_range_passes(value):
    check_parameter("c", value, 0, 1)


def test_an_integer_parameter_refuses_floats_and_booleans_rather_than_truncating():
    check_integer("n", np.int32(7), 1, 10)
    for value, message in [
        (2.0, "n must be an integer in [1, 10,000], got 2.0"),
        (True, "n must be an integer in [1, 10,000], got True"),
        (0, "n must be in [1, 10,000], got 0"),
        (12_345, "n must be in [1, 10,000], got 12,345"),
    ]:
        with pytest.raises(ValueError) as error:
            check_integer("n", value, 1, 10_000)
        assert str(error.value) == message
